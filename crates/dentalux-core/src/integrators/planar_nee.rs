//! Next-event estimation through one flat refracting face, for the reference path tracer.
//!
//! From a scattering point x inside a medium of index n1, light from an area light at y
//! outside (index n2) can arrive along one refracted path x → q → y per flat face, q on the
//! face's plane where Snell's law n1 sin θ1 = n2 sin θ2 holds. With h1, h2 the distances of x
//! and y from the plane and D the distance between their projections, q lies on the segment
//! between the projections at the one root u of n1 u / l1 − n2 (D − u) / l2 (increasing in u).
//!
//! The solid angle at x per area at y follows from the refracted ray bundle: in the plane of
//! incidence it spreads as if from a source at l1 (n2/n1) cos²θ2 / cos²θ1 behind q, across
//! it as if from l1 n2/n1 behind q, so
//!
//!   dω1/dA_y = cos θ_y / ([l1 cos θ2 / cos θ1 + l2 (n1/n2) cos θ1 / cos θ2] · [l1 + l2 n1/n2]),
//!
//! which is cos θ_y / (l1 + l2)² when n1 = n2. Radiance crossing into the medium is scaled by
//! (1 − F)(n1/n2)², so a distant source keeps its irradiance (1 − F) L A / d² (the unit test
//! checks the Jacobian against finite differences).
//!
//! The path tracer counts these paths here and skips them when a sampled path finds them
//! (the light reached by a refraction out of the medium through one of these faces right
//! after a scattering vertex, then straight through index-matched boundaries only), so every
//! light path is counted once.

use crate::geometry::shapes::Cylinder;
use crate::geometry::{Ray, Vec3};
use crate::integrators::transport::{cross, spawn, straight_transmittance};
use crate::lights::AreaPoint;
use crate::phase::PhaseFunction;
use crate::scene::{Boundary, Geometry, Scene};

/// Transmittance bound below which a face's estimate is computed only with probability
/// bound / ROULETTE_BOUND (on the Fig. 3 discs most scattering vertices lie deep).
const ROULETTE_BOUND: f64 = 0.05;

/// A flat face through which a medium is left: a point on its plane, the unit normal out of
/// the medium, the medium on the other side.
type Face = (Vec3, Vec3, u32);

/// Flat faces through which each medium is left: cylinder caps and box faces of dielectric
/// shapes, seen from their inside.
#[derive(Debug, Clone, Default)]
pub struct PlanarFaces {
    per_medium: Vec<Vec<Face>>,
}

impl PlanarFaces {
    /// No faces: next-event estimation through refracting boundaries off.
    pub fn none() -> Self {
        Self::default()
    }

    /// The flat faces of the scene's dielectric cylinders and boxes, per inside medium.
    pub fn of(scene: &Scene) -> Self {
        let mut per_medium = vec![Vec::new(); scene.media.len()];
        for shape in scene.shapes() {
            let Boundary::Dielectric { inside, outside } = shape.boundary else {
                continue;
            };
            let local: Vec<(Vec3, Vec3)> = match &shape.geometry {
                Geometry::Cylinder(Cylinder {
                    center,
                    axis,
                    height,
                    ..
                }) => vec![(*center, -*axis), (*center + *axis * *height, *axis)],
                Geometry::Box(b) => (0..3)
                    .flat_map(|a| {
                        let mut e = Vec3::ZERO;
                        e[a] = 1.0;
                        [(b.min, -e), (b.max, e)]
                    })
                    .collect(),
                _ => continue,
            };
            for (p, n) in local {
                let (p, n) = match &shape.transform {
                    Some(t) => (t.point(p), t.normal(n).normalize()),
                    None => (p, n),
                };
                per_medium[inside as usize].push((p, n, outside));
            }
        }
        Self { per_medium }
    }

    fn faces(&self, medium: u32) -> &[Face] {
        self.per_medium
            .get(medium as usize)
            .map_or(&[], |v| v.as_slice())
    }

    /// Whether the boundary point `p` (unit normal `n`, either orientation) lies on one of
    /// `medium`'s flat faces.
    pub fn on_face(&self, scene: &Scene, medium: u32, p: Vec3, n: Vec3) -> bool {
        let tol = 1e3 * scene.eps;
        self.faces(medium)
            .iter()
            .any(|&(p0, nf, _)| n.dot(nf).abs() > 1.0 - 1e-9 && (p - p0).dot(nf).abs() < tol)
    }

    /// Light from every area light reaching `x` (in `medium`, travelling along `wo_in`, the
    /// direction the path arrived in) through each flat face by one refraction, times the phase
    /// function: Σ p(ω1 · wo_in) L_i(x, ω1) over the sampled light points (one per light,
    /// uniforms from `u`), each divided by its pdf.
    pub fn estimate(
        &self,
        scene: &Scene,
        medium: u32,
        x: Vec3,
        wo_in: Vec3,
        phase: &PhaseFunction,
        mut u: impl FnMut() -> [f64; 2],
    ) -> f64 {
        let faces = self.faces(medium);
        if faces.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0;
        for light in &scene.lights {
            let Some(lp) = light.area_point(u()) else {
                continue;
            };
            let sigma_t = scene.media[medium as usize].sigma_t();
            for &(p0, nf, beyond) in faces {
                // deep below a face its light is faint (at most e^(−σt h1)) but costs as much:
                // Russian roulette on that bound, weighted by its inverse (unbiased)
                let bound = (-sigma_t * (p0 - x).dot(nf).max(0.0)).exp();
                let keep = (bound / ROULETTE_BOUND).min(1.0);
                if keep < 1.0 && u()[0] >= keep {
                    continue;
                }
                sum += through_face(scene, medium, x, wo_in, phase, &lp, (p0, nf, beyond)) / keep;
            }
        }
        sum
    }
}

/// One light point through one face (0 when no valid refracted path exists).
fn through_face(
    scene: &Scene,
    medium: u32,
    x: Vec3,
    wo_in: Vec3,
    phase: &PhaseFunction,
    lp: &AreaPoint,
    (p0, nf, beyond): Face,
) -> f64 {
    let (n1, n2) = (
        scene.media[medium as usize].eta,
        scene.media[beyond as usize].eta,
    );
    if n1 == n2 {
        return 0.0; // index-matched faces are the straight shadow ray's
    }
    let y = lp.point;
    let h1 = (p0 - x).dot(nf);
    let h2 = (y - p0).dot(nf);
    if h1 <= 0.0 || h2 <= 0.0 {
        return 0.0;
    }
    let xp = x + nf * h1;
    let yp = y - nf * h2;
    let span = yp - xp;
    let dd = span.length();
    let u = if dd > 0.0 {
        snell_root(n1, n2, h1, h2, dd)
    } else {
        0.0
    };
    let q = if dd > 0.0 { xp + span * (u / dd) } else { xp };
    let d1 = q - x;
    let l1 = d1.length();
    let w1 = d1 / l1;
    // the segment x → q must meet this face first, at q
    let Some(hit) = scene.intersect(&Ray::new(x, w1), f64::INFINITY) else {
        return 0.0;
    };
    if (hit.t - l1).abs() > 1e3 * scene.eps || hit.n.dot(nf).abs() < 1.0 - 1e-9 {
        return 0.0;
    }
    let Boundary::Dielectric { inside, outside } = scene.boundary(hit.shape) else {
        return 0.0;
    };
    let c = cross(scene, &hit, w1, inside, outside);
    let Some(w2) = c.refracted else {
        return 0.0;
    };
    if c.from != medium || c.to != beyond {
        return 0.0;
    }
    let d2 = y - q;
    let l2 = d2.length();
    if w2.dot(d2 / l2) < 1.0 - 1e-6 {
        return 0.0;
    }
    let cos_y = -w2.dot(lp.normal);
    if cos_y <= 0.0 || lp.radiance <= 0.0 {
        return 0.0;
    }
    let t2 = straight_transmittance(scene, spawn(scene, &hit, w2).o, w2, l2, c.to);
    if t2 <= 0.0 {
        return 0.0;
    }
    let (cos1, cos2) = (h1 / l1, h2 / l2);
    let r = n1 / n2;
    let jac = cos_y / ((l1 * cos2 / cos1 + l2 * r * cos1 / cos2) * (l1 + l2 * r));
    phase.eval(w1.dot(wo_in))
        * (1.0 - c.reflectance)
        * r
        * r
        * lp.radiance
        * lp.area
        * jac
        * (-scene.media[medium as usize].sigma_t() * l1).exp()
        * t2
}

/// The root u ∈ [0, D] of n1 u / √(u² + h1²) − n2 (D − u) / √((D − u)² + h2²) (Snell's law
/// at a flat face; the function increases in u), by bisection: near grazing exit the function
/// is steep at one end and flat at the other, where Newton steps wander.
pub fn snell_root(n1: f64, n2: f64, h1: f64, h2: f64, d: f64) -> f64 {
    let f = |u: f64| {
        n1 * u / (u * u + h1 * h1).sqrt() - n2 * (d - u) / ((d - u) * (d - u) + h2 * h2).sqrt()
    };
    let (mut lo, mut hi) = (0.0, d);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi || hi - lo < 1e-13 * h1.min(h2) {
            break;
        }
        if f(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direction from x to the refraction point towards y through the plane z = 0 (x below,
    /// y above), by the root solver.
    fn w1(n1: f64, n2: f64, x: Vec3, y: Vec3) -> Vec3 {
        let (h1, h2) = (-x.z, y.z);
        let (xp, yp) = (Vec3::new(x.x, x.y, 0.0), Vec3::new(y.x, y.y, 0.0));
        let dd = (yp - xp).length();
        let u = snell_root(n1, n2, h1, h2, dd);
        let q = xp + (yp - xp) * (u / dd);
        (q - x).normalize()
    }

    #[test]
    fn snell_holds_at_the_root() {
        let (n1, n2) = (1.54, 1.0);
        for (h1, h2, d) in [
            (0.3, 10.0, 4.0),
            (2.0, 1.0, 0.5),
            (0.01, 30.0, 25.0),
            (0.2, 0.1, 40.0),
        ] {
            let u = snell_root(n1, n2, h1, h2, d);
            let s1 = u / (u * u + h1 * h1).sqrt();
            let s2 = (d - u) / ((d - u) * (d - u) + h2 * h2).sqrt();
            assert!((n1 * s1 - n2 * s2).abs() < 1e-12, "{h1} {h2} {d}: {u}");
        }
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        // dω1/dA_y by moving y over a small square on a tilted light and measuring the solid
        // angle the four refracted directions at x span
        let (n1, n2) = (1.54, 1.0);
        let x = Vec3::new(0.0, 0.0, -0.7);
        let y = Vec3::new(3.0, 1.0, 5.0);
        let ln = Vec3::new(-0.3, 0.1, -1.0).normalize(); // the light faces down, tilted
        let e1 = ln.cross(Vec3::X).normalize();
        let e2 = ln.cross(e1);
        let h = 1e-4;
        let corners = [
            w1(n1, n2, x, y - e1 * h - e2 * h),
            w1(n1, n2, x, y + e1 * h - e2 * h),
            w1(n1, n2, x, y + e1 * h + e2 * h),
            w1(n1, n2, x, y - e1 * h + e2 * h),
        ];
        // solid angle of the small quad of directions ≈ |(b − a) × (d − a)| (parallelogram)
        let a = corners[0];
        let omega = (corners[1] - a).cross(corners[3] - a).length();
        let numeric = omega / (4.0 * h * h);
        let wc = w1(n1, n2, x, y);
        let q = x + wc * (-x.z / wc.z);
        let (l1, l2) = ((q - x).length(), (y - q).length());
        let w2 = (y - q) / l2;
        let (cos1, cos2, cos_y) = (wc.z, w2.z, -w2.dot(ln));
        let r = n1 / n2;
        let analytic = cos_y / ((l1 * cos2 / cos1 + l2 * r * cos1 / cos2) * (l1 + l2 * r));
        assert!(
            (numeric / analytic - 1.0).abs() < 1e-3,
            "numeric {numeric} analytic {analytic}"
        );
    }
}
