//! Shared steps of light transport in scenes with media, used by the photon tracer, the
//! volume photon mapping camera pass and the reference volumetric path tracer:
//! crossing a dielectric boundary (medium tracking from the boundary's explicit inside and
//! outside: a ray enters when d · n < 0, n pointing outward), straight-line transmittance for
//! shadow rays (eq. 12), the eq. 13 refraction correction of the in-medium distance, and
//! spawning rays off surfaces.
//!
//! A boundary is *index-matched* when both sides have the same refractive index: light
//! crosses it without reflection or bending, so shadow rays may pass it. A mismatched
//! boundary is specular: shadow rays stop there (the photon map or the path carries the light).

use crate::fresnel;
use crate::geometry::{offset_origin, Hit, Ray, Vec3};
use crate::rng::Stream;
use crate::scene::{Boundary, Scene};

/// Most boundary crossings a shadow ray follows before giving up (a guard, not physics:
/// only nested index-matched shells add crossings).
const MAX_SHADOW_CROSSINGS: usize = 64;

/// How far to search for a boundary ahead of a free flight of sampled length `s` [mm]: only
/// a face nearer than the collision changes the walk, so the BVH is searched up to `s`
/// instead of to infinity (inside a tooth mesh the exit face lies millimetres away, a flight
/// tenths of a millimetre). The relative margin keeps a face at `s` itself, which wins the
/// tie `s < t_hit` as a boundary, inside the search, so the walk is the one a search to
/// infinity gives.
#[inline]
pub fn flight_reach(s: f64) -> f64 {
    s * (1.0 + 1e-9)
}

/// What happens to a ray at a dielectric boundary.
#[derive(Debug, Clone, Copy)]
pub struct Crossing {
    /// Medium the ray arrives from.
    pub from: u32,
    /// Medium on the other side.
    pub to: u32,
    /// Refractive index on the arrival side.
    pub eta_i: f64,
    /// Refractive index on the other side.
    pub eta_t: f64,
    /// Fresnel reflectance (1 under total internal reflection, 0 when index-matched).
    pub reflectance: f64,
    /// Reflected travel direction.
    pub reflected: Vec3,
    /// Refracted travel direction (`None` under total internal reflection).
    pub refracted: Option<Vec3>,
}

impl Crossing {
    /// Whether the indices differ (a specular event).
    #[inline]
    pub fn mismatched(&self) -> bool {
        self.eta_i != self.eta_t
    }

    /// Fresnel roulette for one path: refract with probability 1 − R (radiance scaled by
    /// (η_i/η_t)², the path's medium switched to `to`), else reflect. Draws a uniform only
    /// when refraction is possible. Returns the new travel direction.
    #[inline]
    pub fn choose(&self, rng: &mut Stream, beta: &mut f64, medium: &mut u32) -> Vec3 {
        match self.refracted {
            Some(t) if rng.uniform() >= self.reflectance => {
                *beta *= (self.eta_i / self.eta_t).powi(2);
                *medium = self.to;
                t
            }
            _ => self.reflected,
        }
    }
}

/// The crossing of a ray travelling along `d` through the dielectric boundary `hit` between
/// media `inside` and `outside`.
#[inline]
pub fn cross(scene: &Scene, hit: &Hit, d: Vec3, inside: u32, outside: u32) -> Crossing {
    let entering = d.dot(hit.n) < 0.0;
    let (from, to) = if entering {
        (outside, inside)
    } else {
        (inside, outside)
    };
    let eta_i = scene.media[from as usize].eta;
    let eta_t = scene.media[to as usize].eta;
    let cos_i = d.dot(hit.n).abs();
    let reflectance = fresnel::reflectance(cos_i, eta_i, eta_t);
    let refracted = if reflectance >= 1.0 {
        None
    } else if eta_i == eta_t {
        Some(d)
    } else {
        fresnel::refract(d, hit.n, eta_i, eta_t)
    };
    Crossing {
        from,
        to,
        eta_i,
        eta_t,
        reflectance,
        reflected: fresnel::reflect(d, hit.n),
        refracted,
    }
}

/// The ray leaving `hit` along `d`, offset off the surface.
#[inline]
pub fn spawn(scene: &Scene, hit: &Hit, d: Vec3) -> Ray {
    Ray {
        o: offset_origin(hit.p, hit.n, d, scene.eps),
        d,
    }
}

/// Transmittance along the straight segment from `p` (in medium `medium`) along unit `d` for
/// `dist` [mm] (eq. 12 per medium crossed): passes index-matched dielectric boundaries,
/// returns 0 at an opaque surface or a mismatched (refracting) boundary.
pub fn straight_transmittance(scene: &Scene, p: Vec3, d: Vec3, dist: f64, medium: u32) -> f64 {
    let mut ray = Ray { o: p, d };
    let mut left = dist;
    let mut medium = medium;
    let mut tr = 1.0;
    for _ in 0..MAX_SHADOW_CROSSINGS {
        let sigma_t = scene.media[medium as usize].sigma_t();
        let Some(hit) = scene.intersect_in(medium, &ray, left) else {
            return tr * (-sigma_t * left).exp();
        };
        tr *= (-sigma_t * hit.t).exp();
        match scene.boundary(hit.shape) {
            Boundary::Opaque { .. } => return 0.0,
            Boundary::Dielectric { inside, outside } => {
                let c = cross(scene, &hit, d, inside, outside);
                if c.mismatched() {
                    return 0.0;
                }
                medium = c.to;
            }
        }
        left -= hit.t;
        ray = spawn(scene, &hit, d);
        if left <= 0.0 || tr == 0.0 {
            return tr;
        }
    }
    0.0
}

/// The paper's approximate transmittance for single scattering behind refracting boundaries
/// (eqs. 12–13): follow the straight line from `p` towards the light for `dist` [mm]; at each
/// mismatched boundary multiply by the Fresnel transmittance 1 − F and replace the length `d`
/// of the segment just travelled by the refracted length of eq. 13,
/// d' = d |ω·n| / sqrt(1 − (η_t/η_i)² (1 − |ω·n|²)); opaque surfaces block.
pub fn eq13_transmittance(scene: &Scene, p: Vec3, d: Vec3, dist: f64, medium: u32) -> f64 {
    let mut ray = Ray { o: p, d };
    let mut left = dist;
    let mut medium = medium;
    let mut tr = 1.0;
    for _ in 0..MAX_SHADOW_CROSSINGS {
        let sigma_t = scene.media[medium as usize].sigma_t();
        let Some(hit) = scene.intersect_in(medium, &ray, left) else {
            return tr * (-sigma_t * left).exp();
        };
        match scene.boundary(hit.shape) {
            Boundary::Opaque { .. } => return 0.0,
            Boundary::Dielectric { inside, outside } => {
                let c = cross(scene, &hit, d, inside, outside);
                let mut seg = hit.t;
                if c.mismatched() {
                    let cos = d.dot(hit.n).abs();
                    let ratio = c.eta_t / c.eta_i;
                    let arg = 1.0 - ratio * ratio * (1.0 - cos * cos);
                    if arg <= 0.0 {
                        // no refracted path inside reaches this outside direction
                        return 0.0;
                    }
                    seg = hit.t * cos / arg.sqrt();
                    tr *= 1.0 - fresnel::reflectance(cos, c.eta_t, c.eta_i);
                }
                tr *= (-sigma_t * seg).exp();
                medium = c.to;
            }
        }
        left -= hit.t;
        ray = spawn(scene, &hit, d);
        if left <= 0.0 || tr == 0.0 {
            return tr;
        }
    }
    0.0
}
