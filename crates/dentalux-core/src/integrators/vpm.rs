//! The camera pass of volume photon mapping (paper section 4, eq. 11): camera rays split at
//! dielectric boundaries by Fresnel into reflection and refraction; inside a scattering
//! medium they are marched, at points drawn in proportion to the transmittance from the eye
//! (their number set by the step Δx, [`march_points`]), adding at each point
//! - single scattering from every light by a shadow ray attenuated by eq. 12 with the eq. 13
//!   refraction correction of the in-medium distance (`vpm`; in `vpm-full` the photon map
//!   carries single scattering instead),
//! - multiple scattering from the medium's volume photon map, Σ p ΔΦ / (4/3 π r³),
//!
//! integrated against the transmittance e^(−σt s) from the eye; then the ray continues behind the
//! medium (it leaves through the far boundary, refracts and meets the checker behind a disc).
//! Opaque Lambertian surfaces take direct light by shadow rays plus the surface photon map.
//!
//! Radiance across a refracting boundary is scaled by (η_i/η_t)² (η_i on the camera side):
//! photon maps measure radiance inside the medium, which is η² times the radiance outside.
//!
//! Parameters (defaults derived from the scene; each overridable by settings):
//! | setting | default | meaning |
//! |---|---|---|
//! | `k` | 64 | photons per estimate in media |
//! | `surface_k` | `k` | photons per estimate of the surface map |
//! | `radius` [mm] | 2 · cbrt(3 k V / (4π n)) per medium: twice the radius that holds k photons at the map's mean density (V: bounding box of the map's photons, n: its photons), at most the medium's typical half-thickness ([`half_thickness`]) | largest gathering radius in media |
//! | `surface_radius` [mm] | `radius`, else the 2-D analogue of its default, at most 0.1 × scene diagonal | largest gathering radius of the surface map |
//! | `kernel_layer` | 0.3 | volume kernel: half-height of the boundary-aligned layer kernel over the gathering radius; 0 = the paper's sphere |
//! | `kernel_clip` | true | clip the layer kernel (and the surface map's disc) by every other face within it, found by 8 rays: not only by the camera ray's entry and exit planes |
//! | `step` Δx [mm] | per medium min(0.5 / σt, scene diagonal / 64); never below 1e-5 × diagonal | march resolution: a segment gets half the points jittered steps of Δx would evaluate (at least 2; [`march_points`]) |
//! | `light_strata` (VpmParams only) | 3 | an area light's direct light on a surface: 3 × 3 stratified samples |
//! | `map_threshold` (VpmParams only) | 0.3 | in [`march_points`]' count: a step whose eye transmittance T is below this counts T / 0.3 |
//!
//! Noise and speed on the Fig. 3 scene: docs/notes/2026-12-02-vpm-convergence.md ("Camera-pass noise and
//! speed"), measured by the ignored test `fig3_noise_budget`.

use crate::control::Control;
use crate::error::Result;
use crate::geometry::{Hit, Ray, Vec3};
use crate::integrators::photon_trace::trace_camera_maps;
use crate::integrators::photon_trace::{PhotonMaps, StoreMode};
use crate::integrators::settings::{Settings, Stats, VolumeEstimator, DEFAULT_CLIP, DEFAULT_LAYER};
use crate::integrators::tiles::{render_tiles, Scratch, Totals};
use crate::integrators::transport::{cross, eq13_transmittance, spawn, straight_transmittance};
use crate::lights::Light;
use crate::photon_map::PHOTON_BYTES;
use crate::photon_map::{BeamMap, KernelClip, PhotonMap, Planes, Segment};
use crate::rng::Stream;
use crate::scene::{Boundary, Scene};
use std::f64::consts::PI;
use std::time::Instant;

/// Camera-path depth up to which a mismatched boundary splits into both reflection and
/// refraction; deeper, one of the two is chosen by Fresnel (unbiased either way).
pub(super) const SPLIT_DEPTH: u32 = 2;
/// Smallest march step as a fraction of the scene diagonal (a guard against settings that
/// would make a camera ray take billions of steps).
const MIN_STEP_FRACTION: f64 = 1e-5;
/// Path weight below which Russian roulette starts.
pub(super) const RR_WEIGHT: f64 = 0.05;
/// Default of [`VpmParams::map_threshold`].
pub const DEFAULT_MAP_THRESHOLD: f64 = 0.3;
/// Default of [`VpmParams::light_strata`].
pub const DEFAULT_LIGHT_STRATA: u32 = 3;
/// Single-scattering points per camera-ray segment of the beam estimate (`vpm` mode).
const SINGLE_SAMPLES: u32 = 8;

/// Points of the camera pass's march over a segment of length `t_end` [mm] in a medium of
/// extinction `sigma_t` [1/mm] (> 0): half the steps that jittered steps of `step` [mm] would
/// evaluate, rounded, at least 2, where a step whose transmittance from the eye T is below
/// `threshold` counts T / `threshold` (the steps' own sampling before transmittance
/// stratification; each stratified point counts about twice: Fig. 3's discs showed less
/// noise with 2 points than with the 4.3 such steps, docs/notes/2026-12-02-vpm-convergence.md). So the step
/// sets how finely an optically thin segment is sampled along its length.
pub fn march_points(sigma_t: f64, t_end: f64, step: f64, threshold: f64) -> u32 {
    let n = (t_end / step).ceil().max(1.0);
    let a = (-sigma_t * step).exp(); // transmittance over one step
    let t0 = (-0.5 * sigma_t * step).exp(); // at the first step's middle
    let expected = if threshold <= 0.0 {
        n
    } else {
        // steps i < full have T_i = t0 aⁱ ≥ threshold; the rest count T_i / threshold
        let full = ((threshold / t0).ln() / a.ln()).floor() + 1.0;
        let full = if a < 1.0 { full.clamp(0.0, n) } else { n };
        let tail = if a < 1.0 && full < n {
            t0 * (a.powf(full) - a.powf(n)) / ((1.0 - a) * threshold)
        } else {
            0.0
        };
        full + tail
    };
    ((0.5 * expected).round() as u32).clamp(2, 1 << 16)
}

/// The distance [mm] of point `j` of `n` drawn by the eye's transmittance over [0, `t_end`]
/// in a medium of extinction `sigma_t`, `xi` uniform in [0, 1): with F = `absorbed` =
/// 1 − e^(−σt t_end), s = −ln(1 − u F)/σt at u = (j + ξ)/n has density σt e^(−σt s)/F
/// within stratum j (the inverse of the truncated exponential's CDF), kept below `t_end`
/// whatever the rounding.
#[inline]
fn stratum_point(sigma_t: f64, t_end: f64, absorbed: f64, j: u32, n: u32, xi: f64) -> f64 {
    let u = (j as f64 + xi) / n as f64;
    (-(-u * absorbed).ln_1p() / sigma_t).min(t_end * (1.0 - 1e-12))
}

/// Settings of the camera pass; `None` means "derive from the scene".
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VpmParams {
    /// Photons per density estimate in media.
    pub k: usize,
    /// Photons per estimate of the surface map (`Settings::surface_photons_k`).
    pub surface_k: usize,
    /// Largest gathering radius in media [mm].
    pub radius: Option<f64>,
    /// Largest gathering radius of the surface map [mm] (`Settings::surface_cap`).
    pub surface_radius: Option<f64>,
    /// Ray-marching step Δx [mm].
    pub step: Option<f64>,
    /// `Paper` (`vpm`) or `All` (`vpm-full`): who carries single scattering.
    pub mode: StoreMode,
    /// Guard on camera-path length (boundary events); roulette ends paths long before.
    pub max_depth: u32,
    /// Direct light at an opaque surface: an area light is sampled `light_strata`² times, once
    /// in each cell of a `light_strata` × `light_strata` grid over its sample square
    /// (stratified, unbiased); point and spot lights once. On the Fig. 3 scene one sample per
    /// hit left the lit checker with 30 % per-sample noise at fixed pixel positions
    /// (`fig3_noise_budget`), most of the camera pass's noise.
    pub light_strata: u32,
    /// Transmittance from the eye below which a step of Δx counts only T / `map_threshold`
    /// towards a segment's number of march points ([`march_points`]); 0 counts every step.
    /// Deep in a dense medium the light seen from the eye is faint, and the map estimates of
    /// nearby points share most of their photons, so the points go where T is high.
    pub map_threshold: f64,
    /// Shape of the density-estimation kernel in media: 0 a sphere (the paper's); otherwise
    /// a flat cylinder along the nearer of the camera ray's entry and exit planes, half-height
    /// `layer` × the gathering radius, fitted linearly in depth where the plane cuts it
    /// (`PhotonMap::volume_layer_knn`). Default [`DEFAULT_LAYER`]: the sphere is up to
    /// half too dark within its radius of a boundary, where a camera looking into a dense
    /// medium gets most of its light (−8.4 % vs the slab simulator on a slab at 4 M photons;
    /// the layer kernel −0.1 %).
    pub layer: f64,
    /// Clip the layer kernel by every face of the scene within it, not only by the entry and
    /// exit planes, and the surface map's gathering disc by faces standing on the surface
    /// (a disc on the ribbon): 8 rays per estimate find them (`photon_map::KernelClip`);
    /// only estimates whose kernel meets another face change.
    pub clip: bool,
}

impl Default for VpmParams {
    fn default() -> Self {
        Self {
            k: 64,
            surface_k: 64,
            radius: None,
            surface_radius: None,
            step: None,
            mode: StoreMode::Paper,
            max_depth: 64,
            light_strata: DEFAULT_LIGHT_STRATA,
            map_threshold: DEFAULT_MAP_THRESHOLD,
            layer: DEFAULT_LAYER,
            clip: DEFAULT_CLIP,
        }
    }
}

impl VpmParams {
    /// The parameters a render's settings give (`vpm`, `vpm-full`, `bre`, `ppm`), with `mode`
    /// choosing who carries single scattering; the rest at their defaults.
    pub fn from_settings(settings: &Settings, mode: StoreMode) -> Self {
        Self {
            k: settings.k,
            surface_k: settings.surface_photons_k(),
            radius: settings.radius,
            surface_radius: settings.surface_cap(),
            step: settings.step,
            mode,
            max_depth: settings.max_depth,
            layer: settings.kernel_layer,
            clip: settings.kernel_clip,
            ..Self::default()
        }
    }
}

/// Per-medium values resolved from the scene and the maps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MediumSetup {
    /// Ray-marching step Δx [mm].
    pub step: f64,
    /// Largest gathering radius [mm].
    pub radius: f64,
}

/// A ready camera pass: scene, maps and resolved parameters.
#[derive(Debug)]
pub struct Vpm<'a> {
    pub(super) scene: &'a Scene,
    maps: &'a PhotonMaps,
    pub(super) params: VpmParams,
    /// Resolved step and radius per medium (indexed like `scene.media`).
    pub media: Vec<MediumSetup>,
    /// Resolved radius of the surface map [mm].
    pub surface_radius: f64,
    /// Gather every photon within the radii above instead of the k nearest (progressive
    /// photon mapping sets this and the radii of its pass).
    pub fixed_radius: bool,
    /// Per medium, the photon map's discs for the beam radiance estimate
    /// (`settings.volume_estimator = "beam"`, [`Vpm::build_beams`]); `None`: eq. 11's march.
    pub beams: Option<Vec<BeamMap>>,
}

/// Twice the radius of a ball holding `k` photons at the map's mean density.
pub(crate) fn default_radius(map: &PhotonMap, k: usize, flat: bool) -> f64 {
    if map.is_empty() {
        return 1.0;
    }
    let (lo, hi) = map.bounds();
    let mut e: Vec<f64> = (0..3).map(|a| (hi[a] - lo[a]) as f64).collect();
    e.sort_by(|a, b| b.total_cmp(a));
    let n = map.len() as f64;
    let r = if flat {
        // surface photons: density per area of the two largest extents
        (k as f64 * e[0] * e[1].max(e[0] * 1e-3) / (PI * n)).sqrt()
    } else {
        let v = e[0] * e[1].max(e[0] * 1e-3) * e[2].max(e[0] * 1e-3);
        (3.0 * k as f64 * v / (4.0 * PI * n)).cbrt()
    };
    (2.0 * r).max(1e-6)
}

/// Typical half-thickness of the region a volume map's photons live in [mm]: for up to 256
/// photons spread through the map, the shortest chord through the point along 7 lines (the
/// axes and the body diagonals) to the surrounding boundaries, halved; the median over the
/// photons. A 0.5 mm disc gives about 0.25 mm, a 1 mm enamel shell about 0.5 mm.
pub(crate) fn half_thickness(scene: &Scene, map: &PhotonMap) -> Option<f64> {
    const LINES: [[f64; 3]; 7] = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [1.0, 1.0, -1.0],
        [1.0, -1.0, 1.0],
        [-1.0, 1.0, 1.0],
    ];
    let photons = map.photons();
    let stride = (photons.len() / 256).max(1);
    let mut halves: Vec<f64> = photons
        .iter()
        .step_by(stride)
        .filter_map(|p| {
            let x = p.position();
            LINES
                .iter()
                .filter_map(|l| {
                    let d = Vec3::new(l[0], l[1], l[2]);
                    let up = scene.intersect(&Ray::new(x, d), f64::INFINITY)?.t;
                    let down = scene.intersect(&Ray::new(x, -d), f64::INFINITY)?.t;
                    Some(0.5 * (up + down))
                })
                .min_by(f64::total_cmp)
        })
        .collect();
    if halves.is_empty() {
        return None;
    }
    let mid = halves.len() / 2;
    Some(*halves.select_nth_unstable_by(mid, f64::total_cmp).1)
}

/// Default largest gathering radius of a medium's map [mm]: twice the mean-density radius,
/// at most the medium's typical half-thickness, so that in a thin layer (a 0.5 mm disc, an
/// enamel shell) the sphere does not reach across it and blur what lies behind.
pub(crate) fn default_volume_radius(scene: &Scene, map: &PhotonMap, k: usize) -> f64 {
    let r = default_radius(map, k, false);
    half_thickness(scene, map).map_or(r, |h| r.min(h.max(1e-6)))
}

impl<'a> Vpm<'a> {
    /// The kernel clip of one volume estimate when `params.clip` asks for it: `faces` finds
    /// the faces, rotated at random (one uniform drawn only then).
    fn kernel_clip<'c>(
        &self,
        faces: &'c dyn Fn(Vec3, Vec3, f64) -> Option<(Vec3, Vec3)>,
        rng: &mut Stream,
    ) -> Option<KernelClip<'c>> {
        self.params.clip.then(|| KernelClip {
            hit: faces,
            u: rng.uniform(),
        })
    }

    /// Resolve the parameters for `scene` and `maps`.
    pub fn new(scene: &'a Scene, maps: &'a PhotonMaps, params: VpmParams) -> Self {
        let (lo, hi) = scene.bounds();
        let diag = (hi - lo).length();
        let diag = if diag.is_finite() && diag > 0.0 {
            diag
        } else {
            1.0
        };
        let media = scene
            .media
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let st = m.sigma_t();
                let step = params.step.unwrap_or(if st > 0.0 {
                    (0.5 / st).min(diag / 64.0)
                } else {
                    diag / 64.0
                });
                // a step far below the scene's size would march for ever: floor it
                let step = step.max(diag * MIN_STEP_FRACTION);
                let radius = params.radius.unwrap_or_else(|| {
                    maps.volume
                        .get(i)
                        .map_or(1.0, |map| default_volume_radius(scene, map, params.k))
                });
                MediumSetup { step, radius }
            })
            .collect();
        // capped like the surface photon mapping integrator's default (0.1 × scene diagonal)
        let surface_radius = params.surface_radius.unwrap_or_else(|| {
            default_radius(&maps.surface, params.surface_k, true)
                .min(super::pm::default_r_max(scene))
        });
        Self {
            scene,
            maps,
            params,
            media,
            surface_radius,
            fixed_radius: false,
            beams: None,
        }
    }

    /// Give every volume photon its disc for the beam radiance estimate: of the medium's
    /// gathering radius ([`MediumSetup::radius`]: `settings.radius`, else the scene-derived
    /// default of [`default_volume_radius`]).
    pub fn build_beams(&mut self) {
        let beams = (self.maps.volume.iter().zip(&self.media))
            .map(|(map, setup)| BeamMap::build(map, setup.radius))
            .collect();
        self.beams = Some(beams);
    }

    /// Radiance arriving at the camera along `ray` (which starts in the ambient medium).
    pub fn radiance(&self, ray: &Ray, rng: &mut Stream, sc: &mut Scratch) -> f64 {
        self.trace(*ray, self.scene.ambient_medium, 1.0, 0, rng, sc)
    }

    /// Follow a camera path of weight `beta` from `ray` in `medium`; `depth` counts boundary
    /// events. Returns the radiance it carries times `beta`.
    fn trace(
        &self,
        mut ray: Ray,
        mut medium: u32,
        mut beta: f64,
        mut depth: u32,
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        let scene = self.scene;
        let mut l = 0.0;
        // the boundary plane where the ray entered its medium: (point, outward normal)
        let mut entry: Option<(Vec3, Vec3)> = None;
        loop {
            let m = &scene.media[medium as usize];
            let hit = scene.intersect_in(medium, &ray, f64::INFINITY);
            sc.rays += 1;
            let t_hit = hit.map_or(f64::INFINITY, |h| h.t);
            let sigma_t = m.sigma_t();
            // lights seen directly (they are not in the BVH and do not block)
            if let Some((le, t)) = scene.emitted(&ray, t_hit) {
                l += beta * le * (-sigma_t * t).exp();
            }
            if sigma_t > 0.0 {
                let exit = hit.map(|h| (h.p, if ray.d.dot(h.n) > 0.0 { h.n } else { -h.n }));
                l += beta * self.segment(&ray, medium, t_hit, [entry, exit], rng, sc);
                beta *= (-sigma_t * t_hit).exp();
                if beta == 0.0 {
                    return l;
                }
            }
            let Some(hit) = hit else {
                return l;
            };
            depth += 1;
            if depth > self.params.max_depth {
                return l;
            }
            match scene.boundary(hit.shape) {
                Boundary::Opaque { surface } => {
                    let rho = scene.surfaces[surface as usize]
                        .reflectance(&hit, scene.shapes()[hit.shape as usize].uv_scale);
                    if rho > 0.0 {
                        l += beta * rho / PI
                            * self.direct_and_map_irradiance(&ray, &hit, medium, rng, sc);
                    }
                    return l;
                }
                Boundary::Dielectric { inside, outside } => {
                    let c = cross(scene, &hit, ray.d, inside, outside);
                    let scale = (c.eta_i / c.eta_t).powi(2);
                    match c.refracted {
                        None => ray = spawn(scene, &hit, c.reflected),
                        Some(t) if !c.mismatched() => {
                            ray = spawn(scene, &hit, t);
                            medium = c.to;
                        }
                        Some(t) if depth <= SPLIT_DEPTH => {
                            // split: reflection recursively, refraction in this loop
                            let rr = spawn(scene, &hit, c.reflected);
                            l += self.trace(rr, c.from, beta * c.reflectance, depth, rng, sc);
                            beta *= (1.0 - c.reflectance) * scale;
                            ray = spawn(scene, &hit, t);
                            medium = c.to;
                        }
                        Some(t) => {
                            // choose one branch with the Fresnel probabilities
                            if rng.uniform() < c.reflectance {
                                ray = spawn(scene, &hit, c.reflected);
                            } else {
                                beta *= scale;
                                ray = spawn(scene, &hit, t);
                                medium = c.to;
                            }
                        }
                    }
                }
            }
            // the new ray leaves this boundary into its medium: remember the plane
            entry = Some((
                hit.p,
                if ray.d.dot(hit.n) < 0.0 {
                    hit.n
                } else {
                    -hit.n
                },
            ));
            // Russian roulette on the path weight (unbiased; no hard depth cut)
            if beta < RR_WEIGHT {
                let survive = beta / RR_WEIGHT;
                if rng.uniform() >= survive {
                    return l;
                }
                beta = RR_WEIGHT;
            }
        }
    }

    /// ∫_0^t_end e^(−σt s) S(x(s)) ds along `ray` in `medium`, between the planes where it
    /// entered and leaves the medium: by the beam estimate where the beams are built, else
    /// by eq. 11's march.
    pub(super) fn segment(
        &self,
        ray: &Ray,
        medium: u32,
        t_end: f64,
        planes: [Option<(Vec3, Vec3)>; 2],
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        match &self.beams {
            Some(_) => self.beam(ray, medium, t_end, planes, rng, sc),
            None => self.march(ray, medium, t_end, planes, rng, sc),
        }
    }

    /// ∫_0^t_end e^(−σt s) S(x(s)) ds along `ray` in `medium` (eq. 11's march):
    /// S = σs Σ_l L_l p (single scattering, `vpm` only) + Σ p ΔΦ / V, V the gathering sphere
    /// 4/3 π r³, or the layer kernel oriented by the nearer of the boundary planes where the
    /// ray entered and leaves the medium (`planes`: point, outward normal).
    ///
    /// The points are drawn in proportion to the transmittance from the eye, one in each of
    /// [`march_points`] equal strata of 1 − e^(−σt s) over the segment: the integral is
    /// (1 − e^(−σt t_end)) / σt times the mean of S over them (unbiased for any count). Where
    /// the light comes from the first mean free paths, as in the dense discs and teeth, this
    /// needs fewer density estimates than jittered steps of equal weight.
    fn march(
        &self,
        ray: &Ray,
        medium: u32,
        t_end: f64,
        planes: [Option<(Vec3, Vec3)>; 2],
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        let scene = self.scene;
        let m = &scene.media[medium as usize];
        if m.sigma_s <= 0.0 {
            return 0.0;
        }
        let sigma_t = m.sigma_t();
        let setup = self.media[medium as usize];
        let wo = -ray.d;
        let n = march_points(sigma_t, t_end, setup.step, self.params.map_threshold);
        // the segment's share of the light: ∫_0^t_end e^(−σt s) ds = absorbed / σt
        let absorbed = -(-sigma_t * t_end).exp_m1();
        let weight = absorbed / (sigma_t * n as f64);
        let mut sum = 0.0;
        for j in 0..n {
            let s = stratum_point(sigma_t, t_end, absorbed, j, n, rng.uniform());
            let x = ray.at(s);
            let mut src = 0.0;
            if self.params.mode == StoreMode::Paper {
                src += self.single_scatter(x, ray.d, medium, rng, sc);
            }
            src += self.map_source(x, wo, medium, planes, rng, sc);
            sum += weight * src;
        }
        sum
    }

    /// The medium's volume photon map's estimate of eq. 11's multiple-scattering source
    /// Σ p ΔΦ / V at `x` seen along `-wo`, its kernel oriented by the nearer of `planes`
    /// (the boundary planes where the camera ray entered and leaves the medium); 0 where the
    /// map is empty.
    fn map_source(
        &self,
        x: Vec3,
        wo: Vec3,
        medium: u32,
        planes: [Option<(Vec3, Vec3)>; 2],
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        let scene = self.scene;
        let m = &scene.media[medium as usize];
        let setup = self.media[medium as usize];
        let map = &self.maps.volume[medium as usize];
        if map.is_empty() {
            return 0.0;
        }
        // the nearer of the entry and exit planes orients the layer kernel
        let depth = |p: &(Vec3, Vec3)| (p.0 - x).dot(p.1).abs();
        let near = planes
            .iter()
            .flatten()
            .min_by(|a, b| depth(a).total_cmp(&depth(b)))
            .copied()
            .filter(|_| self.params.layer > 0.0);
        let faces = |o, d, t_max| scene.first_face(medium, o, d, t_max);
        let clip = self.kernel_clip(&faces, rng);
        let planes = near.map(|near| Planes {
            near,
            far: planes.iter().flatten().find(|p| **p != near).copied(),
            clip,
        });
        let (k, r, layer) = (self.params.k, setup.radius, self.params.layer);
        let e = match (self.fixed_radius, planes) {
            (true, Some(pl)) => map.volume_layer_at_radius(x, wo, &m.phase, r, layer, pl),
            (true, None) => map.volume_sphere_at_radius(x, wo, &m.phase, r),
            (false, Some(pl)) => map.volume_layer_knn(x, wo, &m.phase, k, r, layer, pl, &mut sc.nb),
            (false, None) => map.volume_sphere_knn(x, wo, &m.phase, k, r, &mut sc.nb),
        };
        sc.radius_sum += e.radius;
        sc.estimates += 1;
        e.value
    }

    /// σs Σ_l p L_l T_l at `x` in `medium` for a camera ray along `d`: single scattering
    /// from every light by one shadow ray each, attenuated by eq. 12 with eq. 13's
    /// refraction correction.
    fn single_scatter(
        &self,
        x: Vec3,
        d: Vec3,
        medium: u32,
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        let scene = self.scene;
        let m = &scene.media[medium as usize];
        let mut src = 0.0;
        for light in &scene.lights {
            let Some(ls) = light.sample_li(x, rng.uniform2()) else {
                continue;
            };
            let t = eq13_transmittance(scene, x, ls.wi, ls.dist, medium);
            sc.rays += 1;
            if t > 0.0 {
                src += m.sigma_s * m.phase.eval(ls.wi.dot(d)) * ls.value * t;
            }
        }
        src
    }

    /// ∫_0^t_end e^(−σt s) S(x(s)) ds along `ray` in `medium` without marching: single
    /// scattering (`vpm` mode) at [`SINGLE_SAMPLES`] points drawn from the truncated
    /// exponential e^(−σt s) on [0, t_end] (stratified; unbiased), multiple scattering by
    /// one beam radiance estimate over the segment (photon_map/beam.rs), its photons cut
    /// by the planes where the ray entered and leaves the medium.
    fn beam(
        &self,
        ray: &Ray,
        medium: u32,
        t_end: f64,
        planes: [Option<(Vec3, Vec3)>; 2],
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        let m = &self.scene.media[medium as usize];
        if m.sigma_s <= 0.0 {
            return 0.0;
        }
        let sigma_t = m.sigma_t();
        let mut l = 0.0;
        if self.params.mode == StoreMode::Paper {
            let f = -(-sigma_t * t_end).exp_m1();
            let n = SINGLE_SAMPLES as f64;
            for j in 0..SINGLE_SAMPLES {
                let s = stratum_point(sigma_t, t_end, f, j, SINGLE_SAMPLES, rng.uniform());
                let x = ray.at(s);
                l += f / sigma_t * self.single_scatter(x, ray.d, medium, rng, sc) / n;
            }
        }
        let map = &self.maps.volume[medium as usize];
        if !map.is_empty() {
            let Some(b) = self.beams.as_ref().map(|b| &b[medium as usize]) else {
                return l;
            };
            let scene = self.scene;
            let faces = |o, d, t_max| scene.first_face(medium, o, d, t_max);
            let clip = self.kernel_clip(&faces, rng);
            let e = b.estimate(
                map,
                &Segment {
                    o: ray.o,
                    d: ray.d,
                    t_end,
                    entry: planes[0],
                    exit: planes[1],
                    sigma_t,
                    phase: &m.phase,
                    clip,
                },
            );
            sc.estimates += 1;
            sc.radius_sum += b.radius();
            l += e.value;
        }
        l
    }

    /// Irradiance at an opaque hit from the side the ray came from: direct light by shadow
    /// rays (through index-matched boundaries only) plus the surface photon map.
    pub(super) fn direct_and_map_irradiance(
        &self,
        ray: &Ray,
        hit: &Hit,
        medium: u32,
        rng: &mut Stream,
        sc: &mut Scratch,
    ) -> f64 {
        let scene = self.scene;
        let n = if ray.d.dot(hit.n) < 0.0 {
            hit.n
        } else {
            -hit.n
        };
        let p = spawn(scene, hit, n).o;
        let mut e = 0.0;
        for light in &scene.lights {
            let strata = match light {
                Light::Point { .. } | Light::Spot { .. } => 1,
                _ => self.params.light_strata.max(1),
            };
            let inv = 1.0 / strata as f64;
            let mut sum = 0.0;
            for cell in 0..strata * strata {
                let [a, b] = rng.uniform2();
                let u = [
                    ((cell % strata) as f64 + a) * inv,
                    ((cell / strata) as f64 + b) * inv,
                ];
                let Some(ls) = light.sample_li(p, u) else {
                    continue;
                };
                let cos = ls.wi.dot(n);
                if cos <= 0.0 {
                    continue;
                }
                sum += ls.value * cos * straight_transmittance(scene, p, ls.wi, ls.dist, medium);
                sc.rays += 1;
            }
            e += sum * inv * inv;
        }
        if !self.maps.surface.is_empty() {
            e += if self.fixed_radius {
                self.maps
                    .surface
                    .irradiance_disc_at_radius(hit.p, n, self.surface_radius)
            } else if self.params.clip {
                // rays along the surface start just off it, on the lit side
                let lift = n * scene.eps;
                let faces = |o: Vec3, d, t_max| scene.first_face(medium, o + lift, d, t_max);
                let clip = KernelClip {
                    hit: &faces,
                    u: rng.uniform(),
                };
                let (k, r) = (self.params.surface_k, self.surface_radius);
                self.maps
                    .surface
                    .irradiance_clipped_disc_knn(hit.p, n, k, r, &mut sc.nb, &clip)
            } else {
                let (k, r) = (self.params.surface_k, self.surface_radius);
                self.maps
                    .surface
                    .irradiance_disc_knn(hit.p, n, k, r, &mut sc.nb)
            }
            .value;
        }
        e
    }
}

/// Render a band with volume photon mapping: `settings.volume_photons` photons fill the volume
/// maps, `settings.photons` of them (`trace_camera_maps`) the surface map; `full` selects
/// `vpm-full` (single scattering in the map) over `vpm` (single scattering by eqs. 12–13).
pub fn render(
    scene: &Scene,
    settings: &Settings,
    control: &Control,
    full: bool,
) -> Result<(Vec<f32>, Stats)> {
    let maps = trace_camera_maps(scene, settings, store_mode(full), 0, control)?;
    render_with_maps(scene, settings, control, full, &maps)
}

/// What the volume maps of `vpm` (`full` false) or `vpm-full` store.
pub fn store_mode(full: bool) -> StoreMode {
    if full {
        StoreMode::All
    } else {
        StoreMode::Paper
    }
}

/// The camera pass of [`render`] over photon maps already traced (a spectral pass's maps
/// of this band, `integrators::hero`).
pub fn render_with_maps(
    scene: &Scene,
    settings: &Settings,
    control: &Control,
    full: bool,
    maps: &PhotonMaps,
) -> Result<(Vec<f32>, Stats)> {
    let mut vpm = Vpm::new(
        scene,
        maps,
        VpmParams::from_settings(settings, store_mode(full)),
    );
    let t_beams = Instant::now();
    let beam = settings.estimator() == VolumeEstimator::Beam;
    if beam {
        vpm.build_beams();
    }
    let seconds_beams = t_beams.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let (image, totals) = render_tiles(scene, settings, control, |ray, rng, sc| {
        vpm.radiance(ray, rng, sc)
    })?;
    let seconds_camera = t0.elapsed().as_secs_f64();
    let stats = band_stats(&vpm, maps, settings, seconds_beams, seconds_camera, totals);
    Ok((image, stats))
}

/// The statistics of one band's camera pass `vpm` over `maps`: photon counts and powers,
/// the resolved steps and radii per scattering medium, and the times [s].
pub(super) fn band_stats(
    vpm: &Vpm,
    maps: &PhotonMaps,
    settings: &Settings,
    seconds_beams: f64,
    seconds_camera: f64,
    totals: Totals,
) -> Stats {
    let scene = vpm.scene;
    let beam = vpm.beams.is_some();
    let volume_stored: usize = maps.volume.iter().map(|m| m.len()).sum();
    let mut extra = vec![
        ("volume_photons".into(), volume_stored as f64),
        ("surface_photons".into(), maps.surface.len() as f64),
        ("surface_radius".into(), vpm.surface_radius),
        ("emitted_power".into(), maps.ledger.emitted),
        (
            "stored_volume_power".into(),
            maps.ledger.stored_volume.iter().sum(),
        ),
        ("stored_surface_power".into(), maps.ledger.stored_surface),
    ];
    for (i, m) in vpm.media.iter().enumerate() {
        if scene.media[i].sigma_s > 0.0 {
            if !beam {
                extra.push((format!("step_medium{i}"), m.step));
            }
            extra.push((format!("radius_medium{i}"), m.radius));
        }
    }
    Stats {
        integrator: settings.integrator.name().into(),
        estimator: settings.estimator().name().into(),
        seconds_photons: maps.trace_seconds,
        seconds_build: maps.build_seconds + seconds_beams,
        seconds_camera,
        photons_emitted: maps.emitted,
        photons_stored: maps.stored() as u64,
        bytes_per_photon: PHOTON_BYTES as u64,
        photon_map_bytes: maps.bytes() as u64,
        radius: totals.mean_radius(),
        rays: totals.rays,
        extra,
        ..Stats::default()
    }
}

#[cfg(test)]
mod march_tests {
    use super::march_points;

    #[test]
    fn march_points_halve_the_steps_that_count() {
        // a dense disc: steps of 0.5 / σt count 2 in full and 2.44 by transmittance
        assert_eq!(march_points(7.7, 5.0, 0.5 / 7.7, 0.3), 2);
        // a thin segment with every step counted: 12 steps, 6 points
        assert_eq!(march_points(1e-3, 50.0, 4.4, 0.3), 6);
        assert_eq!(march_points(7.7, 5.0, 0.5 / 7.7, 0.0), 39);
        // never fewer than 2, never unbounded
        assert_eq!(march_points(7.7, 1e-6, 0.5 / 7.7, 0.3), 2);
        assert_eq!(march_points(1e-9, 1e9, 1e-3, 0.3), 1 << 16);
    }
}
