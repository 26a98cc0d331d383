//! Photon mapping for surfaces (`pm`): opaque Lambertian surfaces and smooth dielectric shapes
//! filled with clear media (Jensen's two-pass method, one band).
//!
//! 1. Photon pass ([`trace_photons`], shared with volume photon mapping): photons leave the
//!    lights with power Φ/N; the surface map keeps every landing on an opaque surface except
//!    those arriving straight from a light (direct light is ray traced here).
//! 2. Camera pass: camera rays follow the specular chain through dielectrics (Fresnel
//!    reflect-or-refract roulette, Beer–Lambert absorption, radiance scaled by (η_i/η_t)² across
//!    a refraction) to the first opaque surface. There the radiance is
//!    ρ/π · (E_direct + E_photons): E_direct by next-event estimation with a shadow ray
//!    ([`direct_irradiance`]), E_photons the density estimate Σ ΔΦ / (π r²) over the k nearest
//!    photons arriving from the viewed side (r: distance of the k-th, at most `r_max`).
//!    With `final_gather`, the first surface instead sends one cosine-weighted gather ray and
//!    takes ρ times the radiance found there (direct + density estimate at the second surface):
//!    it hides the blotches of the density estimate at the cost of one more ray per sample.
//!
//! `r_max` is `settings.surface_cap()` (`surface_radius`, else `radius`) or, when unset, a
//! tenth of the scene's bounding-box diagonal (it only matters where fewer than k photons lie
//! within it).

use super::direct::{check_clear_media, direct_irradiance, facing};
use super::photon_trace::{trace_photons, StoreMode};
use super::settings::{Settings, Stats};
use super::tiles::{render_tiles, Scratch};
use super::transport::{cross, spawn};
use crate::control::Control;
use crate::error::Result;
use crate::geometry::Ray;
use crate::math::Frame;
use crate::photon_map::{PhotonMap, PHOTON_BYTES};
use crate::rng::Stream;
use crate::sampling::cosine_hemisphere;
use crate::scene::{Boundary, Scene};
use std::f64::consts::PI;
use std::time::Instant;

/// A ready camera pass: the scene, its surface photon map and the estimate's parameters.
#[derive(Debug)]
pub struct SurfacePm<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The surface photon map (photon powers already divided by N).
    pub map: &'a PhotonMap,
    /// Photons per density estimate.
    pub k: usize,
    /// Largest gathering radius [mm].
    pub r_max: f64,
    /// Gather one diffuse bounce before the estimate.
    pub final_gather: bool,
    /// Guard on the number of specular events along a camera path.
    pub max_depth: u32,
}

/// Default gathering-radius cap: a tenth of the scene's bounding-box diagonal [mm].
pub fn default_r_max(scene: &Scene) -> f64 {
    let (lo, hi) = scene.bounds();
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 {
        0.1 * d
    } else {
        1.0
    }
}

impl SurfacePm<'_> {
    /// Radiance arriving at the camera along `ray`.
    pub fn radiance(&self, ray: &Ray, rng: &mut Stream, scratch: &mut Scratch) -> f64 {
        self.trace(
            *ray,
            self.scene.ambient_medium,
            true,
            self.final_gather,
            rng,
            scratch,
        )
    }

    /// Follow the specular chain from `ray` in `medium` to an opaque surface and return the
    /// radiance found. `count_emission`: area lights seen now add their radiance (false right
    /// after a diffuse bounce, whose light sample already counted them). `gather`: the opaque
    /// surface met sends a final-gather ray instead of reading the photon map.
    fn trace(
        &self,
        mut ray: Ray,
        mut medium: u32,
        mut count_emission: bool,
        gather: bool,
        rng: &mut Stream,
        scratch: &mut Scratch,
    ) -> f64 {
        let scene = self.scene;
        let mut beta = 1.0;
        let mut l = 0.0;
        for _ in 0..self.max_depth {
            let hit = scene.intersect(&ray, f64::INFINITY);
            scratch.rays += 1;
            let t_hit = hit.map_or(f64::INFINITY, |h| h.t);
            let sigma_a = scene.media[medium as usize].sigma_a;
            if count_emission {
                if let Some((le, t)) = scene.emitted(&ray, t_hit) {
                    l += beta * le * (-sigma_a * t).exp();
                }
            }
            let Some(hit) = hit else {
                return l;
            };
            beta *= (-sigma_a * hit.t).exp();
            match scene.boundary(hit.shape) {
                Boundary::Dielectric { inside, outside } => {
                    let c = cross(scene, &hit, ray.d, inside, outside);
                    let d = c.choose(rng, &mut beta, &mut medium);
                    count_emission |= c.mismatched();
                    ray = spawn(scene, &hit, d);
                }
                Boundary::Opaque { .. } => {
                    let rho = scene.reflectance(&hit);
                    if rho <= 0.0 {
                        return l;
                    }
                    let n_f = facing(&hit, ray.d);
                    let direct = direct_irradiance(scene, &hit, n_f, medium, rng, scratch);
                    let indirect = if gather {
                        // one cosine-weighted gather ray: f cos / pdf = ρ, so ρ/π · π L
                        let d = Frame::from_axis(n_f).to_world(cosine_hemisphere(rng.uniform2()));
                        PI * self.trace(spawn(scene, &hit, d), medium, false, false, rng, scratch)
                    } else {
                        let e = self.map.irradiance_flattened_disc_knn(
                            hit.p,
                            n_f,
                            self.k,
                            self.r_max,
                            &mut scratch.nb,
                        );
                        scratch.radius_sum += e.radius;
                        scratch.estimates += 1;
                        e.value
                    };
                    return l + beta * rho / PI * (direct + indirect);
                }
            }
            if beta == 0.0 {
                break;
            }
        }
        l
    }
}

/// Render a band with surface photon mapping.
pub fn render(scene: &Scene, settings: &Settings, control: &Control) -> Result<(Vec<f32>, Stats)> {
    check_clear_media(scene, "pm")?;
    let maps = trace_photons(
        scene,
        settings.photons,
        StoreMode::Paper,
        settings.seed,
        settings.band,
        control,
    )?;
    let pm = SurfacePm {
        scene,
        map: &maps.surface,
        k: settings.surface_photons_k(),
        r_max: settings
            .surface_cap()
            .unwrap_or_else(|| default_r_max(scene)),
        final_gather: settings.final_gather,
        max_depth: settings.max_depth,
    };
    let t0 = Instant::now();
    let (image, totals) = render_tiles(scene, settings, control, |ray, rng, scratch| {
        pm.radiance(ray, rng, scratch)
    })?;
    Ok((
        image,
        Stats {
            integrator: "pm".into(),
            seconds_photons: maps.trace_seconds,
            seconds_build: maps.build_seconds,
            seconds_camera: t0.elapsed().as_secs_f64(),
            photons_emitted: maps.emitted,
            photons_stored: maps.surface.len() as u64,
            bytes_per_photon: PHOTON_BYTES as u64,
            photon_map_bytes: maps.surface.bytes() as u64,
            radius: totals.mean_radius(),
            rays: totals.rays,
            extra: vec![
                ("r_max".into(), pm.r_max),
                ("stored_power".into(), maps.ledger.stored_surface),
                ("emitted_power".into(), maps.ledger.emitted),
            ],
            ..Stats::default()
        },
    ))
}
