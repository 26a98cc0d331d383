//! The radiance estimates of the paper over a photon map: eq. 11's multiple-scattering term
//! in a medium (a sphere, or the boundary-aligned layer kernel of [`super::kernel`]) and the
//! surface irradiance Σ ΔΦ / (π r²) (a disc, a disc flattened about the tangent plane as
//! `pm` gathers (Jensen's disc filter), or the disc clipped by faces standing on the
//! surface), each with the radius of the k nearest photons (`_knn`) or a fixed radius
//! (`_at_radius`, progressive photon mapping).

use super::kernel::{disc_fraction_inside, inside_planes, prism_moments, rotated_circle};
use super::kernel::{KernelClip, Planes, CLIP_RAYS};
use super::tree::{direction_cosines, Neighbours, Photon, PhotonMap};
use crate::math::{Frame, Vec3};
use crate::phase::PhaseFunction;
use std::f64::consts::PI;

/// Photons of a layer kernel whose weights are summed together (see `layer_estimate`).
const LAYER_BATCH: usize = 64;

/// A density estimate: its value, the radius it used [mm] and the number of photons in it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Estimate {
    /// The estimate (units depend on the estimator; see its doc).
    pub value: f64,
    /// Radius of the gathering sphere or disc [mm].
    pub radius: f64,
    /// Photons that contributed.
    pub count: usize,
}

/// Largest distance from the tangent plane, as a fraction of the gathering radius, at which a
/// photon still counts: the sphere is flattened into a disc so that photons on a neighbouring
/// wall near a corner are not counted as if they had landed here (Jensen's disc filter).
pub const DISC_THICKNESS: f64 = 0.25;

/// Gathering radius of a k-nearest query and the factor that makes its estimate unbiased
/// for a uniform density: when k photons were found the radius is the k-th distance and that
/// photon sits on the sphere, so Σ ΔΦ / V over k photons overestimates by k/(k − 1)
/// (E[(k − 1)/V_k] = density for a Poisson process); with fewer, the radius is `r_max`.
fn knn_radius(nb: &Neighbours, k: usize, r_max: f64) -> (f64, f64) {
    if nb.len() < k || k < 2 {
        (r_max, 1.0)
    } else {
        ((nb.max_dist2() as f64).sqrt(), (k - 1) as f64 / k as f64)
    }
}

/// Photons of the k-NN query that sets the layer kernel's radius for `k` photons per
/// estimate: a quarter of k, at least 16 (or k when smaller). Below 16 the radius of the
/// query itself varies by more than 8 % (1/(3√k_r)), and with it the kernel's photon count.
fn radius_query_k(k: usize) -> usize {
    (k / 4).max(k.min(16))
}

impl PhotonMap {
    /// Σ ΔΦ and the count over the found photons that arrived at the side `n` faces
    /// (d_p · n < 0) and that `keep` (photon index, photon) accepts, in the found order.
    fn front_power(
        &self,
        nb: &Neighbours,
        n: Vec3,
        keep: impl Fn(u32, &Photon) -> bool,
    ) -> (f64, usize) {
        let mut sum = 0.0;
        let mut count = 0;
        for &(_, i) in nb.items() {
            let p = &self.photons()[i as usize];
            if p.direction().dot(n) < 0.0 && keep(i, p) {
                sum += p.power as f64;
                count += 1;
            }
        }
        (sum, count)
    }

    /// Eq. 11's multiple-scattering term at `x`: Σ p(d_p · wo) ΔΦ_p / (4/3 π r³) over the `k`
    /// nearest photons within `r_max` [mm], r being the distance of the farthest one found
    /// (or `r_max` when fewer than `k` lie within it), times (k − 1)/k when k were found (see
    /// `knn_radius`: the k-th photon lies on the sphere). `wo` is the unit direction the
    /// scattered light leaves in (towards the viewer: minus the camera ray's direction).
    /// The value is σs·L_i, in-scattered radiance per mm [W/(sr·mm³) · mm² = radiance/mm]:
    /// multiply by the march step Δx [mm] and the transmittance to the eye.
    pub fn volume_sphere_knn(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let (r, unbias) = knn_radius(nb, k, r_max);
        let sum: f64 = nb
            .items()
            .iter()
            .map(|&(_, i)| {
                let p = &self.photons()[i as usize];
                phase.eval(p.direction().dot(wo)) * p.power as f64
            })
            .sum();
        Estimate {
            value: unbias * sum / (4.0 / 3.0 * PI * r * r * r),
            radius: r,
            count: nb.len(),
        }
    }

    /// [`Self::volume_sphere_knn`] with a kernel shaped for a boundary: the layer kernel of
    /// [`Self::volume_layer_at_radius`] with r the radius of a sphere that holds `k` photons,
    /// found as the distance of the k_r-th nearest photon times (k / k_r)^(1/3), k_r =
    /// [`radius_query_k`]`(k)`. The kernel gathers its photons itself (a box walk), so the
    /// k-NN query only sets the radius, and a query for fewer photons costs less: on the
    /// Fig. 3 discs at 512 × 384, k 200, 4 M photons, the camera pass took 0.86× the time
    /// with k_r = 50 (docs/notes/2026-12-06-bre.md). The k_r-th photon (on the query's sphere) is left out,
    /// which keeps the estimate unbiased for a uniform density: given that sphere, the other
    /// k_r − 1 photons are uniform inside it and the rest a Poisson process outside.
    #[allow(clippy::too_many_arguments)]
    pub fn volume_layer_knn(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        k: usize,
        r_max: f64,
        layer: f64,
        planes: Planes,
        nb: &mut Neighbours,
    ) -> Estimate {
        let kq = radius_query_k(k);
        let grow = (k as f64 / kq as f64).cbrt();
        let query_max = r_max / grow;
        self.knn(x, kq, query_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let r = (knn_radius(nb, kq, query_max).0 * grow).min(r_max);
        let kth = if nb.len() >= kq && kq >= 2 {
            nb.items()
                .iter()
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map(|&(_, i)| i as usize)
        } else {
            None
        };
        self.layer_estimate(x, wo, phase, r, layer, planes, kth)
    }

    /// Eq. 11's multiple-scattering term with a kernel shaped for a boundary, of the volume of
    /// the sphere of radius `r` [mm]: a flat cylinder whose axis is the normal n of the nearer
    /// boundary plane, half-height t = `layer` · r and radius R = r √(2/(3·layer)), cut by
    /// that plane (and by the opposite plane of a thin layer), z ∈ [a, b] with
    /// b = min(t, depth of `x`), z measured along n from `x`. Below a boundary the photon
    /// density changes with depth within a mean free path, along the boundary slowly; a sphere
    /// cut by the boundary misses photons (up to half) and sees the density's gradient. Here
    /// the density is fitted as ρ₀ + γ z from the moments Σ w, Σ w z of the phase-weighted
    /// photons against the cut cylinder's A (b − a), A (b² − a²)/2, A (b³ − a³)/3 and ρ₀
    /// reported: exact for a density linear in depth, and the plain mean where nothing cuts
    /// the kernel. Measured against the slab simulator and `volpath`: docs/notes/2026-12-02-vpm-convergence.md.
    #[allow(clippy::too_many_arguments)]
    pub fn volume_layer_at_radius(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        r: f64,
        layer: f64,
        planes: Planes,
    ) -> Estimate {
        self.layer_estimate(x, wo, phase, r, layer, planes, None)
    }

    #[allow(clippy::too_many_arguments)]
    fn layer_estimate(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        r: f64,
        layer: f64,
        planes: Planes,
        skip: Option<usize>,
    ) -> Estimate {
        let (p0, n) = planes.near;
        let t = layer * r;
        let big_r2 = r * r * 2.0 / (3.0 * layer);
        let b = t.min((p0 - x).dot(n).max(0.0));
        // the far plane of a thin layer (anti-parallel normal) bounds z from below
        let a = planes
            .far
            .filter(|(_, nf)| nf.dot(n) < -0.99)
            .map_or(-t, |(pf, nf)| (-t).max(-(pf - x).dot(nf).max(0.0)));
        let mut e = Estimate {
            radius: r,
            ..Estimate::default()
        };
        if b - a <= 1e-9 * r {
            return e;
        }
        let (mut s0, mut s1) = (0.0, 0.0);
        let skip = skip.map(|i| &self.photons()[i] as *const Photon);
        // the cut cylinder's bounding box: |z n_i + ρ_i| ≤ t |n_i| + R √(1 − n_i²)
        let big_r = big_r2.sqrt();
        let half = [n.x, n.y, n.z].map(|c| t * c.abs() + big_r * (1.0 - c * c).max(0.0).sqrt());
        // the walk only collects the photons in the kernel; their phase weights are summed
        // a batch at a time, in the same order, so the walk's unpredictable branches do not
        // stall the square roots and divisions of the weights, and those vectorise
        let mut zs = [0.0f64; LAYER_BATCH];
        let mut idx = [0u32; LAYER_BATCH];
        let mut len = 0;
        let photons = self.photons();
        let mut sum = |zs: &[f64], idx: &[u32]| {
            let (mut bits, mut power) = ([0u32; LAYER_BATCH], [0.0f32; LAYER_BATCH]);
            for (j, &i) in idx.iter().enumerate() {
                let p = &photons[i as usize];
                (bits[j], power[j]) = (p.direction_bits(), p.power);
            }
            let mut w = [0.0f64; LAYER_BATCH];
            let w = &mut w[..idx.len()];
            direction_cosines(&bits, wo, w);
            phase.eval_in_place(w);
            for ((&w, &z), &power) in w.iter().zip(zs).zip(&power) {
                let w = w * power as f64;
                s0 += w;
                s1 += w * z;
            }
        };
        self.for_each_within_box(x, (big_r2 + t * t).sqrt(), half, |p, i| {
            let d = p.position() - x;
            let z = d.dot(n);
            if z < a || z > b || d.dot(d) - z * z > big_r2 || skip == Some(p as *const Photon) {
                return;
            }
            zs[len] = z;
            idx[len] = i as u32;
            len += 1;
            e.count += 1;
            if len == LAYER_BATCH {
                sum(&zs, &idx);
                len = 0;
            }
        });
        sum(&zs[..len], &idx[..len]);
        let [v, m1, m2] = planes
            .clip
            .and_then(|c| c.moments(x, n, a, b, big_r))
            .unwrap_or_else(|| prism_moments(PI * big_r2, a, b));
        let det = v * m2 - m1 * m1;
        // radiance is not negative: a fit that extrapolates below 0 (few photons, steep
        // gradient) is clamped. That biases upwards only where it happens; with k ≥ 64 it is
        // rare (the slab test agrees with the slab simulator to 0.1 % either way).
        e.value = if det > 1e-12 * v * m2 {
            ((s0 * m2 - s1 * m1) / det).max(0.0)
        } else {
            s0 / v
        };
        e
    }

    /// Same as [`Self::volume_sphere_knn`] with a fixed radius `r` [mm] (progressive photon
    /// mapping): Σ_{|x_p − x| ≤ r} p(d_p · wo) ΔΦ_p / (4/3 π r³).
    pub fn volume_sphere_at_radius(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        r: f64,
    ) -> Estimate {
        let mut sum = 0.0;
        let mut count = 0;
        self.for_each_within(x, r, |p, _| {
            sum += phase.eval(p.direction().dot(wo)) * p.power as f64;
            count += 1;
        });
        Estimate {
            value: sum / (4.0 / 3.0 * PI * r * r * r),
            radius: r,
            count,
        }
    }

    /// Irradiance with a fixed radius `r` [mm] (progressive photon mapping):
    /// Σ_{|x_p − x| ≤ r, d_p · n < 0} ΔΦ_p / (π r²).
    pub fn irradiance_disc_at_radius(&self, x: Vec3, n: Vec3, r: f64) -> Estimate {
        let mut sum = 0.0;
        let mut count = 0;
        self.for_each_within(x, r, |p, _| {
            if p.direction().dot(n) < 0.0 {
                sum += p.power as f64;
                count += 1;
            }
        });
        Estimate {
            value: sum / (PI * r * r),
            radius: r,
            count,
        }
    }

    /// [`Self::irradiance_disc_knn`] with its disc cut by the faces that stand on the surface
    /// within the gathering radius r (a disc lying on the ribbon): photons stored beyond
    /// such a face (under the disc, where light that crossed the disc lands) would brighten
    /// the surface just outside it. Eight rays along the surface from `x` to distance r
    /// find the faces (`clip`: rays start at `x`, which the caller's `hit` offsets off the
    /// surface); photons beyond their tangent planes are dropped, the k-th photon (on the
    /// sphere) is left out, and the sum is divided by the area of the part of the disc on
    /// this side (512-point quadrature, rotated by `clip.u`). Without faces within r it is
    /// the plain estimate.
    pub fn irradiance_clipped_disc_knn(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
        clip: &KernelClip,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let (r, unbias) = knn_radius(nb, k, r_max);
        let frame = Frame::from_axis(n);
        let rays = rotated_circle::<CLIP_RAYS>(clip.u);
        let (planes, count) = clip.faces(x, &frame, r, |j| {
            Vec3::new(r * rays[j][0], r * rays[j][1], 0.0)
        });
        let planes = &planes[..count];
        let (area, unbias) = if count == 0 {
            (PI * r * r, unbias)
        } else {
            (PI * r * r * disc_fraction_inside(planes, r, clip.u), 1.0)
        };
        let kth = (count > 0 && nb.len() >= k && k >= 2)
            .then(|| {
                nb.items()
                    .iter()
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|e| e.1)
            })
            .flatten();
        let (sum, n_in) = self.front_power(nb, n, |i, p| {
            Some(i) != kth
                && (count == 0 || inside_planes(planes, frame.to_local(p.position() - x)))
        });
        Estimate {
            value: if area > 0.0 { unbias * sum / area } else { 0.0 },
            radius: r,
            count: n_in,
        }
    }

    /// Irradiance at a surface point `x` with unit normal `n` (facing the side that is lit):
    /// Σ ΔΦ_p / (π r²) over the `k` nearest photons within `r_max` [mm] that arrived from the
    /// front (d_p · n < 0). Multiply by the BRDF (ρ/π) for reflected radiance.
    pub fn irradiance_disc_knn(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let (r, unbias) = knn_radius(nb, k, r_max);
        let (sum, count) = self.front_power(nb, n, |_, _| true);
        Estimate {
            value: unbias * sum / (PI * r * r),
            radius: r,
            count,
        }
    }

    /// Irradiance at `x` on the side `n` faces, from the `k` nearest photons within `r_max` [mm]:
    /// E = Σ ΔΦ_p / (π r²) over the photons that arrived from the front (d_p · n < 0) and lie
    /// within `DISC_THICKNESS · r` of the tangent plane. r is the distance of the k-th photon,
    /// which is itself left out of the sum: for photons scattered by a Poisson process of
    /// density ρ, (k − 1)/(π r_k²) is the unbiased estimate of ρ, k/(π r_k²) is k/(k − 1) too
    /// high. With fewer than k photons within `r_max`, r = `r_max` and all of them count.
    pub fn irradiance_flattened_disc_knn(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate {
                value: 0.0,
                radius: r_max,
                count: 0,
            };
        }
        let full = nb.len() >= k;
        let (r2, far) = if full {
            let far = nb
                .items()
                .iter()
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map(|&(d2, i)| (d2, i))
                .unwrap();
            (far.0 as f64, Some(far.1))
        } else {
            (r_max * r_max, None)
        };
        let r = r2.sqrt();
        let thickness = DISC_THICKNESS * r;
        let (sum, count) = self.front_power(nb, n, |i, p| {
            Some(i) != far && (p.position() - x).dot(n).abs() <= thickness
        });
        Estimate {
            value: if r2 > 0.0 { sum / (PI * r2) } else { 0.0 },
            radius: r,
            count,
        }
    }
}
