//! Hero-wavelength camera paths (Wilkie, Nawaz, Droske, Weidlich & Hanika, EGSR 2014) for
//! the `vpm` camera pass over several bands: one camera path per pixel sample carries a
//! throughput per band, so the bands' estimates are made at the same points, along the same
//! rays, with the same light samples, and their noise is shared (grain in lightness rather
//! than coloured speckle).
//!
//! What every band shares, and what is per band:
//! - Rays and hits: the bands' scenes share their shapes, so one intersection serves all.
//! - A medium segment: each band's own estimate over it (`vpm`'s march by that band's
//!   transmittance, or the beam estimate), all from the same random numbers, so the bands'
//!   march points lie at the same quantiles of their transmittances. Drawing one set of
//!   points by a hero band's transmittance, weighted for the others by the balance heuristic
//!   over the choice of hero, was measured and is worse in the dental media, whose σt
//!   differs twofold between bands: Fig. 4's preview patch b* sd 2.91 → 3.78
//!   (docs/spectral-photons.md).
//! - A dielectric boundary: Fresnel's reflectance differs per band. Where the path splits
//!   ([`SPLIT_DEPTH`]) each band weighs both branches by its own R_b; deeper, reflection is
//!   chosen with the carried bands' mean reflectance R̄ and band b weighted R_b / R̄
//!   (refraction: (1 − R_b) / (1 − R̄)), a deterministic mixture: unbiased for every band.
//!   Where the bands' indices differ (dispersion), their refracted rays part: the path forks
//!   into one path per refracted direction, each carrying its own bands and starting from
//!   the same random numbers.
//! - Russian roulette on the largest band weight.
//! - An opaque surface: each band's reflectance, direct light and surface map, with the same
//!   random numbers.
//!
//! With one band this is the `vpm` camera pass, draw for draw. Given the photon maps, each
//! band's expectation is the band-by-band pass's (tests/hero_camera.rs).

use super::photon_trace::PhotonMaps;
use super::settings::{Settings, Stats, VolumeEstimator};
use super::tiles::{render_tiles_bands, Scratch};
use super::transport::{cross, spawn, Crossing};
use super::vpm::{store_mode, Vpm, VpmParams, RR_WEIGHT, SPLIT_DEPTH};
use crate::control::Control;
use crate::error::Result;
use crate::geometry::{Hit, Ray, Vec3};
use crate::rng::Stream;
use crate::scene::{Boundary, Scene};
use std::f64::consts::PI;
use std::time::Instant;

/// A boundary plane: (point, normal pointing into the medium the ray travels in).
type Plane = (Vec3, Vec3);

/// One camera pass over every band of a render.
pub struct HeroCamera<'a> {
    /// The camera pass of each band (its scene, its maps, its resolved parameters).
    bands: Vec<Vpm<'a>>,
}

/// Where a path goes after a boundary.
enum Next {
    /// On along `ray` (set) with every band still carried.
    On,
    /// Forked: one path per distinct refracted direction, each with the bands that take it.
    Fork(Vec<(Vec3, u32, Vec<usize>)>),
}

/// The plane of `hit` seen from a ray leaving it along `d`: its normal points along `d`'s side.
fn plane_towards(hit: &Hit, d: Vec3) -> Plane {
    (hit.p, if d.dot(hit.n) < 0.0 { hit.n } else { -hit.n })
}

impl<'a> HeroCamera<'a> {
    /// The pass over `bands` (one `Vpm` per band, their scenes sharing their shapes).
    pub fn new(bands: Vec<Vpm<'a>>) -> Self {
        Self { bands }
    }

    /// Add each band's radiance along the camera `ray` to `sum[b]`.
    pub fn radiance(&self, ray: &Ray, rng: &mut Stream, sc: &mut Scratch, sum: &mut [f64]) {
        let scene = self.bands[0].scene;
        let beta = vec![1.0; self.bands.len()];
        let l = self.trace(*ray, scene.ambient_medium, beta, 0, None, rng, sc);
        for (s, l) in sum.iter_mut().zip(l) {
            *s += l;
        }
    }

    /// Follow a camera path from `ray` in `medium` carrying band b with weight `beta[b]`
    /// (0: not carried); `depth` counts boundary events, `entry` is the plane where the ray
    /// entered its medium. Returns each band's radiance times its weight.
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &self,
        mut ray: Ray,
        mut medium: u32,
        mut beta: Vec<f64>,
        mut depth: u32,
        mut entry: Option<Plane>,
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> Vec<f64> {
        let scene = self.bands[0].scene;
        let max_depth = self.bands[0].params.max_depth;
        let mut l = vec![0.0; self.bands.len()];
        loop {
            if beta.iter().all(|&w| w == 0.0) {
                return l; // no band left to carry (a zero reflectance, an underflow)
            }
            let hit = scene.intersect(&ray, f64::INFINITY);
            sc.rays += 1;
            let t_hit = hit.map_or(f64::INFINITY, |h| h.t);
            let mut scatters = false;
            for (b, v) in self.bands.iter().enumerate() {
                if beta[b] == 0.0 {
                    continue;
                }
                let sigma_t = v.scene.media[medium as usize].sigma_t();
                // lights seen directly (they are not in the BVH and do not block)
                if let Some((le, t)) = v.scene.emitted(&ray, t_hit) {
                    l[b] += beta[b] * le * (-sigma_t * t).exp();
                }
                scatters |= sigma_t > 0.0;
            }
            if scatters {
                let exit = hit.map(|h| plane_towards(&h, -ray.d));
                let seg = self.segment(&ray, medium, t_hit, [entry, exit], &beta, rng, sc);
                for (b, v) in self.bands.iter().enumerate() {
                    let sigma_t = v.scene.media[medium as usize].sigma_t();
                    if sigma_t > 0.0 {
                        // (a clear band keeps its weight, also on a ray to infinity)
                        l[b] += beta[b] * seg[b];
                        beta[b] *= (-sigma_t * t_hit).exp();
                    }
                }
                if beta.iter().all(|&w| w == 0.0) {
                    return l;
                }
            }
            let Some(hit) = hit else {
                return l;
            };
            depth += 1;
            if depth > max_depth {
                return l;
            }
            let next = match scene.boundary(hit.shape) {
                Boundary::Opaque { surface } => {
                    let saved = rng.clone();
                    for (b, v) in self.bands.iter().enumerate() {
                        let rho = v.scene.surfaces[surface as usize]
                            .reflectance(&hit, v.scene.shapes()[hit.shape as usize].uv_scale);
                        if beta[b] > 0.0 && rho > 0.0 {
                            *rng = saved.clone();
                            l[b] += beta[b] * rho / PI
                                * v.direct_and_map_irradiance(&ray, &hit, medium, rng, sc);
                        }
                    }
                    return l;
                }
                Boundary::Dielectric { inside, outside } => {
                    let cs: Vec<Crossing> = (self.bands.iter())
                        .map(|v| cross(v.scene, &hit, ray.d, inside, outside))
                        .collect();
                    self.dielectric(
                        &hit,
                        &cs,
                        &mut ray,
                        &mut medium,
                        &mut beta,
                        &mut l,
                        depth,
                        rng,
                        sc,
                    )
                }
            };
            // Russian roulette on the largest band weight (unbiased; no hard depth cut)
            let top = beta.iter().copied().fold(0.0, f64::max);
            if top < RR_WEIGHT {
                let survive = top / RR_WEIGHT;
                if rng.uniform() >= survive {
                    return l;
                }
                // the largest weight becomes RR_WEIGHT, the others keep their ratio to it
                for w in &mut beta {
                    *w = if *w == top {
                        RR_WEIGHT
                    } else {
                        *w * (RR_WEIGHT / top)
                    };
                }
            }
            match next {
                Next::On => entry = Some(plane_towards(&hit, ray.d)),
                Next::Fork(groups) => {
                    // each refracted direction on its own path, all from the same numbers
                    let saved = rng.clone();
                    for (d, to, members) in groups {
                        let mut r = saved.clone();
                        let mut w = vec![0.0; beta.len()];
                        for b in members {
                            w[b] = beta[b];
                        }
                        let ray = spawn(scene, &hit, d);
                        let part =
                            self.trace(ray, to, w, depth, Some(plane_towards(&hit, d)), &mut r, sc);
                        for (a, p) in l.iter_mut().zip(part) {
                            *a += p;
                        }
                        *rng = r;
                    }
                    return l;
                }
            }
        }
    }

    /// A dielectric boundary with crossings `cs` (one per band): sets `ray`, `medium` and the
    /// band weights `beta` of the path that goes on, adds the radiance of a split-off
    /// reflection to `l`, and says where the path goes.
    #[allow(clippy::too_many_arguments)]
    fn dielectric(
        &self,
        hit: &Hit,
        cs: &[Crossing],
        ray: &mut Ray,
        medium: &mut u32,
        beta: &mut [f64],
        l: &mut [f64],
        depth: u32,
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> Next {
        let scene = self.bands[0].scene;
        let carried: Vec<usize> = (0..beta.len()).filter(|&b| beta[b] > 0.0).collect();
        let c0 = cs[carried[0]];
        let shared = carried.iter().all(|&b| cs[b].refracted == c0.refracted);
        if shared && c0.refracted.is_none() {
            *ray = spawn(scene, hit, c0.reflected);
            return Next::On;
        }
        if shared && carried.iter().all(|&b| !cs[b].mismatched()) {
            *ray = spawn(scene, hit, c0.refracted.unwrap_or(c0.reflected));
            *medium = c0.to;
            return Next::On;
        }
        // radiance across the boundary scales by (η_i/η_t)²
        let scale = |b: usize| (cs[b].eta_i / cs[b].eta_t).powi(2);
        if depth <= SPLIT_DEPTH {
            // split: reflection recursively, refraction on this path
            let w: Vec<f64> = (0..beta.len())
                .map(|b| beta[b] * cs[b].reflectance)
                .collect();
            let rr = spawn(scene, hit, c0.reflected);
            for (a, r) in l
                .iter_mut()
                .zip(self.trace(rr, c0.from, w, depth, None, rng, sc))
            {
                *a += r;
            }
            for &b in &carried {
                beta[b] *= (1.0 - cs[b].reflectance) * scale(b);
            }
        } else {
            // one branch, chosen with the carried bands' mean reflectance
            let p = carried.iter().map(|&b| cs[b].reflectance).sum::<f64>() / carried.len() as f64;
            if rng.uniform() < p {
                for &b in &carried {
                    beta[b] *= cs[b].reflectance / p;
                }
                *ray = spawn(scene, hit, c0.reflected);
                return Next::On;
            }
            for &b in &carried {
                beta[b] *= (1.0 - cs[b].reflectance) / (1.0 - p) * scale(b);
            }
        }
        if shared {
            *ray = spawn(scene, hit, c0.refracted.unwrap_or(c0.reflected));
            *medium = c0.to;
            return Next::On;
        }
        // dispersion: group the bands by their refracted direction
        let mut groups: Vec<(Vec3, u32, Vec<usize>)> = Vec::new();
        for &b in &carried {
            let Some(d) = cs[b].refracted else {
                continue; // totally reflected in this band: no refracted light
            };
            if beta[b] == 0.0 {
                continue;
            }
            match groups.iter_mut().find(|g| g.0 == d) {
                Some(g) => g.2.push(b),
                None => groups.push((d, cs[b].to, vec![b])),
            }
        }
        Next::Fork(groups)
    }

    /// ∫_0^t_end e^(−σt_b s) S_b(x(s)) ds for every carried band b along `ray` in `medium`:
    /// each band's own march (or beam estimate) over the segment, all from the same random
    /// numbers.
    #[allow(clippy::too_many_arguments)]
    fn segment(
        &self,
        ray: &Ray,
        medium: u32,
        t_end: f64,
        planes: [Option<Plane>; 2],
        beta: &[f64],
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> Vec<f64> {
        let saved = rng.clone();
        (self.bands.iter().zip(beta))
            .map(|(v, &w)| {
                if w == 0.0 {
                    return 0.0;
                }
                *rng = saved.clone();
                v.segment(ray, medium, t_end, planes, rng, sc)
            })
            .collect()
    }
}

/// The camera pass of `vpm` (`full` false) or `vpm-full` over every band at once, band b of
/// `scenes[b]` over its photon maps `maps[b]`, with `settings`' random streams: one image
/// and one set of statistics per band (the camera time split evenly between the bands).
pub fn render_with_maps(
    scenes: &[Scene],
    settings: &Settings,
    control: &Control,
    full: bool,
    maps: &[PhotonMaps],
) -> Result<Vec<(Vec<f32>, Stats)>> {
    let params = VpmParams::from_settings(settings, store_mode(full));
    let beam = settings.estimator() == VolumeEstimator::Beam;
    let t_beams = Instant::now();
    let mut bands: Vec<Vpm> = (scenes.iter().zip(maps))
        .map(|(scene, maps)| Vpm::new(scene, maps, params))
        .collect();
    if beam {
        for v in &mut bands {
            v.build_beams();
        }
    }
    let seconds_beams = t_beams.elapsed().as_secs_f64() / scenes.len() as f64;
    let hero = HeroCamera::new(bands);
    let t0 = Instant::now();
    let (images, totals) = render_tiles_bands(
        &scenes[0],
        settings,
        control,
        scenes.len(),
        |ray, rng, sc, s| hero.radiance(ray, rng, sc, s),
    )?;
    let seconds_camera = t0.elapsed().as_secs_f64() / scenes.len() as f64;
    Ok(images
        .into_iter()
        .zip(hero.bands.iter().zip(maps))
        .map(|(image, (v, maps))| {
            let mut stats =
                super::vpm::band_stats(v, maps, settings, seconds_beams, seconds_camera, totals);
            stats.extra.push(("hero_camera".into(), 1.0));
            (image, stats)
        })
        .collect())
}
