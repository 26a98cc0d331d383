//! The photon pass of volume photon mapping (paper section 4, eqs. 1–10): photons leave the
//! lights with power Φ/N, cross dielectric boundaries by the Fresnel reflect-or-refract
//! roulette (total internal reflection included), fly freely (eq. 2), scatter or are absorbed
//! by the albedo roulette (eqs. 3–4), turn by the medium's phase function (eqs. 7–10), and
//! pass from medium to medium through the interfaces the scene declares.
//!
//! Storage rules (they must mirror what the camera pass computes by ray tracing):
//! - volume map of medium m: every scattering event inside m, except — in [`StoreMode::Paper`]
//!   — the first scattering event of a photon that so far only crossed boundaries by
//!   transmission (no reflection, no earlier scattering): that single scattering is computed by
//!   shadow rays with eqs. 12–13. [`StoreMode::All`] stores it too (`vpm-full`).
//! - surface map: every hit on an opaque surface, except photons that arrive straight from a
//!   light, crossing only index-matched boundaries and never scattering: those are direct light,
//!   computed by shadow rays. Photons that went through a disc (refracted) land in the surface
//!   map: the light under and behind translucent objects.
//!
//! Randomness: photon batch b uses `Stream::new(seed, band, PHOTON_STREAM | b)`; batches run in
//! parallel (rayon) and are concatenated in batch order, so maps do not depend on threads.

use crate::control::Control;
use crate::error::{Error, Result};
use crate::geometry::Ray;
use crate::integrators::aim::{Aim, Aimed, Source};
use crate::integrators::hero::HeroWalk;
pub use crate::integrators::ledger::Ledger;
use crate::integrators::transport::{cross, flight_reach, spawn};
use crate::math::Frame;
use crate::photon_map::{Photon, PhotonMap};
use crate::rng::{Stream, PHOTON_STREAM, SURFACE_PASS};
use crate::sampling::{cosine_hemisphere, sample_exponential};
use crate::scene::{Boundary, Scene};
use rayon::prelude::*;
use std::time::Instant;

/// Photons per batch (fixed: part of the determinism contract).
pub const BATCH: u64 = 4096;
/// Most interactions one photon may have before it is dropped (a guard against endless TIR
/// loops; reported in the ledger as `cut`).
const MAX_EVENTS: u32 = 100_000;

/// Which scattering events the volume maps store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StoreMode {
    /// The paper: single scattering of transmitted light is ray traced, not stored (`vpm`).
    Paper,
    /// Every scattering event is stored (`vpm-full`): exact through refraction.
    All,
}

/// Which maps a photon pass fills (the ledger is kept either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Targets {
    /// Fill the per-medium volume maps.
    pub volume: bool,
    /// Fill the surface map.
    pub surface: bool,
}

impl Targets {
    /// Both maps.
    pub const BOTH: Targets = Targets {
        volume: true,
        surface: true,
    };
}

/// The photon maps of one band.
#[derive(Debug, Clone, Default)]
pub struct PhotonMaps {
    /// One volume map per medium (empty for non-scattering media), indexed like `scene.media`.
    pub volume: Vec<PhotonMap>,
    /// Photons on opaque surfaces.
    pub surface: PhotonMap,
    /// Photons emitted.
    pub emitted: u64,
    /// Energy bookkeeping of the pass.
    pub ledger: Ledger,
    /// Seconds spent tracing photons.
    pub trace_seconds: f64,
    /// Seconds spent building the kd-trees.
    pub build_seconds: f64,
}

impl PhotonMaps {
    /// Photons stored in all maps.
    pub fn stored(&self) -> usize {
        self.surface.len() + self.volume.iter().map(|m| m.len()).sum::<usize>()
    }
    /// Memory held by all maps [bytes].
    pub fn bytes(&self) -> usize {
        self.surface.bytes() + self.volume.iter().map(|m| m.bytes()).sum::<usize>()
    }
}

struct BatchOut {
    volume: Vec<Vec<Photon>>,
    surface: Vec<Photon>,
    ledger: Ledger,
    /// Photons traced (fewer than asked when `stop_at` ended the batch).
    traced: u64,
    /// Spectral passes: each stored photon's power in every band (B values per photon, in
    /// the order of `volume[m]` and `surface`), and each band's ledger.
    bands: Option<BandPowers>,
}

/// The per-band side of a spectral batch ([`super::hero`]).
#[derive(Debug, Default)]
struct BandPowers {
    volume: Vec<Vec<f32>>,
    surface: Vec<f32>,
    ledgers: Vec<Ledger>,
}

impl BatchOut {
    /// Photons stored in the volume maps.
    fn volume_len(&self) -> u64 {
        self.volume.iter().map(|v| v.len() as u64).sum()
    }
}

/// Trace one batch of `count` photons (aimed at the media when `aim` is given); with
/// `stop_at`, stop after the photon whose events bring the batch's volume maps to that many.
/// `surface_left`: how many of the batch's photons may still store on surfaces. With more
/// than one scene (the bands of a spectral pass, sharing their geometry), each photon walks
/// in a hero band's scene and stores every band's power ([`super::hero`]).
#[allow(clippy::too_many_arguments)]
fn trace_batch(
    scenes: &[Scene],
    n_total: u64,
    count: u64,
    mode: StoreMode,
    targets: Targets,
    aim: Option<&Aim>,
    stop_at: Option<u64>,
    surface_left: u64,
    rng: &mut Stream,
    control: &Control,
) -> BatchOut {
    let nb = scenes.len();
    let spectral = nb > 1;
    let nm = scenes[0].media.len();
    let mut out = BatchOut {
        volume: vec![Vec::new(); nm],
        surface: Vec::new(),
        ledger: Ledger::new(nm),
        traced: 0,
        bands: spectral.then(|| BandPowers {
            volume: vec![Vec::new(); nm],
            surface: Vec::new(),
            ledgers: vec![Ledger::new(nm); nb],
        }),
    };
    let mut hw = HeroWalk::new(nb);
    let led = &mut out.ledger;
    let mut pending: Vec<(Pending, u32)> = Vec::new();
    for _ in 0..count {
        if let Some(stop) = stop_at {
            // (the field, not `volume_len`: `out.ledger` is borrowed mutably above)
            if out.volume.iter().map(|v| v.len() as u64).sum::<u64>() >= stop {
                break;
            }
        }
        let on_surfaces = targets.surface && out.traced < surface_left;
        out.traced += 1;
        // a long random walk (huge optical depth) must still stop promptly on cancel
        if control.is_cancelled() {
            break;
        }
        let hero = if spectral {
            ((rng.uniform() * nb as f64) as usize).min(nb - 1)
        } else {
            0
        };
        let scene = &scenes[hero];
        let (li, p_light) = scene.pick_light(rng.uniform());
        let (u1, u2) = (rng.uniform2(), rng.uniform2());
        let u3 = aim.map(|_| rng.uniform());
        let emit = |s: &Scene| match aim {
            Some(a) => a.sample_emission(&s.lights[li], u1, u2, u3.unwrap_or(0.0)),
            None => {
                let (ray, power) = s.lights[li].sample_emission(u1, u2);
                Aimed::whole(ray, power)
            }
        };
        let Aimed {
            mut ray,
            power: weight,
            mut source,
        } = emit(scene);
        // Φ_l / (N · P(l)): every photon carries Φ_total / N for uniform emission
        let mut power = weight / (p_light * n_total as f64);
        if !(power > 0.0 && power.is_finite()) {
            continue;
        }
        led.emitted += power;
        let bands = out.bands.as_mut();
        if let Some(bp) = bands {
            hw.start(scenes, li, p_light, n_total, |j| emit(&scenes[j]).power);
            hw.book(&mut bp.ledgers, |l| &mut l.emitted);
        }
        let mut medium = scene.ambient_medium;
        let mut scattered = false; // any scattering (volume or diffuse surface) so far
        let mut reflected = false; // any reflection at a mismatched boundary so far
        let mut specular = false; // any event at a mismatched boundary so far
        let mut events = 0u32;
        // distance from ray.o within which the scene has no surface (`Scene::clearance`)
        let mut clear = 0.0;
        // the walks a split photon still owes (`Aim::split_at`), each entry traced after the
        // walk that split: those start from its state; a walk may split again where it
        // enters another medium from a clear one, so they stack (depth first)
        pending.clear();
        loop {
            loop {
                events += 1;
                if events > MAX_EVENTS {
                    led.cut += power;
                    if let Some(bp) = out.bands.as_mut() {
                        hw.book(&mut bp.ledgers, |l| &mut l.cut);
                    }
                    break;
                }
                let m = &scene.media[medium as usize];
                let mi = medium as usize;
                let sigma_t = m.sigma_t();
                let sigma_t_of = |j: usize| scenes[j].media[mi].sigma_t();
                // free flight, eq. 2 (∞ in a clear medium)
                let s = if sigma_t > 0.0 {
                    sample_exponential(rng.uniform_open0(), sigma_t)
                } else {
                    f64::INFINITY
                };
                // within the clearance no surface can be met: the same walk, no intersection
                let hit = if flight_reach(s) < clear {
                    None
                } else {
                    scene.intersect_in(medium, &ray, flight_reach(s))
                };
                let t_hit = hit.map_or(f64::INFINITY, |h| h.t);
                if sigma_t > 0.0 && s < t_hit {
                    let x = ray.at(s);
                    if spectral {
                        // collision density σt e^{−σt s}, relative to the hero's
                        let ln_density = |st: f64| {
                            if st > 0.0 {
                                st.ln() - st * s
                            } else {
                                f64::NEG_INFINITY
                            }
                        };
                        hw.scale_ln(ln_density(sigma_t), |j| ln_density(sigma_t_of(j)));
                    }
                    // scatter or absorb, eqs. 3–4
                    if rng.uniform() >= m.albedo() {
                        led.absorbed_medium[mi] += power;
                        if let Some(bp) = out.bands.as_mut() {
                            let absorb = |j: usize| 1.0 - scenes[j].media[mi].albedo();
                            hw.book_with(&mut bp.ledgers, 1.0 - m.albedo(), absorb, |l| {
                                &mut l.absorbed_medium[mi]
                            });
                        }
                        break;
                    }
                    if spectral {
                        hw.scale(m.albedo(), |j| scenes[j].media[mi].albedo());
                    }
                    // only scattering events are stored: their density is σs φ, what eq. 11's
                    // Σ p ΔΦ / V estimates (storing absorptions too would give σt φ, 1/albedo
                    // too bright)
                    let single_traced = !scattered && !reflected;
                    if targets.volume && (mode == StoreMode::All || !single_traced) {
                        out.volume[mi].push(Photon::new(x, ray.d, power));
                        led.stored_volume[mi] += power;
                        if let Some(bp) = out.bands.as_mut() {
                            bp.volume[mi].extend(hw.powers().iter().map(|&p| p as f32));
                            hw.book(&mut bp.ledgers, |l| &mut l.stored_volume[mi]);
                        }
                    }
                    // new direction from the phase function, eqs. 7–10
                    let d = m.phase.sample(ray.d, rng.uniform2(), rng.azimuth());
                    if spectral {
                        let cos = ray.d.dot(d);
                        let phase_of = |j: usize| &scenes[j].media[mi].phase;
                        if (0..nb).any(|j| *phase_of(j) != m.phase) {
                            hw.scale(m.phase.eval(cos), |j| phase_of(j).eval(cos));
                        }
                    }
                    // the ball left around x; a fresh bound when it holds less than a mean
                    // free path
                    clear = if clear - s >= 1.0 / sigma_t {
                        clear - s
                    } else {
                        scene.clearance_in(medium, x)
                    };
                    ray = Ray { o: x, d };
                    scattered = true;
                    continue;
                }
                if spectral {
                    // no collision before the boundary: e^{−σt t}, relative to the hero's
                    if t_hit.is_finite() {
                        hw.scale_ln(-sigma_t * t_hit, |j| -sigma_t_of(j) * t_hit);
                    } else {
                        hw.forbid(|j| sigma_t_of(j) > 0.0);
                    }
                }
                // every branch below starts the next flight from a surface
                clear = 0.0;
                let Some(hit) = hit else {
                    led.escaped += power;
                    if let Some(bp) = out.bands.as_mut() {
                        hw.book(&mut bp.ledgers, |l| &mut l.escaped);
                    }
                    break;
                };
                match scene.boundary(hit.shape) {
                    Boundary::Opaque { surface } => {
                        if on_surfaces && (scattered || specular) {
                            out.surface.push(Photon::new(hit.p, ray.d, power));
                            led.stored_surface += power;
                            if let Some(bp) = out.bands.as_mut() {
                                bp.surface.extend(hw.powers().iter().map(|&p| p as f32));
                                hw.book(&mut bp.ledgers, |l| &mut l.stored_surface);
                            }
                        }
                        let uv_scale = scene.shapes()[hit.shape as usize].uv_scale;
                        let si = surface as usize;
                        let rho = scene.surfaces[si].reflectance(&hit, uv_scale);
                        let rho_of = |j: usize| scenes[j].surfaces[si].reflectance(&hit, uv_scale);
                        if rng.uniform() >= rho {
                            led.absorbed_surface += power;
                            if let Some(bp) = out.bands.as_mut() {
                                hw.book_with(
                                    &mut bp.ledgers,
                                    1.0 - rho,
                                    |j| 1.0 - rho_of(j),
                                    |l| &mut l.absorbed_surface,
                                );
                            }
                            break;
                        }
                        if spectral {
                            hw.scale(rho, rho_of);
                        }
                        // Lambertian bounce on the side the photon came from
                        let n = if ray.d.dot(hit.n) < 0.0 {
                            hit.n
                        } else {
                            -hit.n
                        };
                        let d = Frame::from_axis(n).to_world(cosine_hemisphere(rng.uniform2()));
                        ray = spawn(scene, &hit, d);
                        scattered = true;
                    }
                    Boundary::Dielectric { inside, outside } => {
                        let c = cross(scene, &hit, ray.d, inside, outside);
                        let refracted = if rng.uniform() < c.reflectance {
                            None
                        } else {
                            c.refracted
                        };
                        if spectral {
                            // bands of another index: their own Fresnel choice, and a refraction
                            // that bends elsewhere (a delta direction) is one they cannot draw
                            let other = |j: usize| cross(&scenes[j], &hit, ray.d, inside, outside);
                            let differs = |j: usize| {
                                let mj = &scenes[j].media;
                                mj[c.from as usize].eta != c.eta_i
                                    || mj[c.to as usize].eta != c.eta_t
                            };
                            if (0..nb).any(differs) {
                                if refracted.is_none() {
                                    hw.scale(c.reflectance, |j| other(j).reflectance);
                                } else {
                                    hw.forbid(|j| differs(j) && other(j).refracted != c.refracted);
                                    hw.scale(1.0 - c.reflectance, |j| 1.0 - other(j).reflectance);
                                }
                            }
                        }
                        if let Some(d) = refracted {
                            ray = spawn(scene, &hit, d);
                            medium = c.to;
                            let enters = |m: u32| scene.media[m as usize].sigma_s > 0.0;
                            let split = match (aim, source) {
                                (Some(a), Some(src)) if enters(c.to) && !enters(c.from) => {
                                    a.split_at(&src, hit.p)
                                }
                                _ => 1,
                            };
                            if split > 1 {
                                // a heavy photon enters a medium: `split` walks from here, each
                                // with 1/split of its power (the expected power is kept)
                                power /= split as f64;
                                source = source.map(|s| s.divided(split));
                                if spectral {
                                    hw.divide_power(split);
                                }
                                let state = Pending {
                                    ray,
                                    medium,
                                    scattered,
                                    reflected,
                                    specular,
                                    events,
                                    power,
                                    source,
                                    hero: spectral.then(|| hw.clone()),
                                };
                                pending.push((state, split - 1));
                            }
                        } else {
                            ray = spawn(scene, &hit, c.reflected);
                            reflected |= c.mismatched();
                        }
                        specular |= c.mismatched();
                    }
                }
            }
            // up to MAX_SPLIT walks per split of up to MAX_EVENTS events each: check for a
            // cancel
            if control.is_cancelled() {
                break;
            }
            let Some((w, left)) = pending.last_mut() else {
                break;
            };
            (
                ray, medium, scattered, reflected, specular, events, power, source,
            ) = (
                w.ray,
                w.medium,
                w.scattered,
                w.reflected,
                w.specular,
                w.events,
                w.power,
                w.source,
            );
            if let Some(h) = &w.hero {
                hw.clone_from(h);
            }
            clear = 0.0;
            *left -= 1;
            if *left == 0 {
                pending.pop();
            }
        }
    }
    out
}

/// The state of a split photon where it entered the medium, from which its remaining walks
/// start (its power and power factor already divided).
struct Pending {
    ray: Ray,
    medium: u32,
    scattered: bool,
    reflected: bool,
    specular: bool,
    events: u32,
    power: f64,
    source: Option<Source>,
    hero: Option<HeroWalk>,
}

/// Trace `photons` photons from the scene's lights and build both maps (see
/// [`trace_photons_with`]).
pub fn trace_photons(
    scene: &Scene,
    photons: u64,
    mode: StoreMode,
    seed: u64,
    band: u64,
    control: &Control,
) -> Result<PhotonMaps> {
    trace_photons_with(scene, photons, mode, Targets::BOTH, 0, seed, band, control)
}

/// Trace `photons` photons from the scene's lights into the maps `targets` selects, batch b
/// drawing from `Stream::new(seed, band, PHOTON_STREAM | tag | b)`. Batches run a chunk at a
/// time (8 per thread), so transient memory stays a small multiple of one batch per thread.
#[allow(clippy::too_many_arguments)]
pub fn trace_photons_with(
    scene: &Scene,
    photons: u64,
    mode: StoreMode,
    targets: Targets,
    tag: u64,
    seed: u64,
    band: u64,
    control: &Control,
) -> Result<PhotonMaps> {
    let emission = Emission {
        photons,
        ..Emission::default()
    };
    trace_emission(scene, &emission, mode, targets, tag, seed, band, control)
}

/// How many photons a pass emits, and where.
#[derive(Debug, Clone, Default)]
pub struct Emission {
    /// Photons to emit (with `stored_cap`: at most this many).
    pub photons: u64,
    /// Stop after the photon at which the volume maps hold at least this many photons
    /// (counted in batch order, so the maps do not depend on the thread count); powers are
    /// then normalised by the photons actually emitted.
    pub stored_cap: Option<u64>,
    /// Aim part of the photons at the media ([`Aim`]).
    pub aim: Option<Aim>,
    /// Store surface photons (where `Targets::surface`) only from the first this many
    /// photons emitted (in batch order); `None`: from every photon.
    pub surface_first: Option<u64>,
}

/// Batches in the next chunk of a photon pass, traced in parallel: 8 per thread; with a
/// stored budget, the batches it still needs at the rate of the `done` batches so far (whole
/// rounds of the threads, one round first to learn the rate), so that little traced work lies
/// past the budget and is thrown away. The maps do not depend on it: the budget cuts the
/// batches in batch order.
fn chunk_len(stored_cap: Option<u64>, stored: u64, done: u64, threads: u64) -> u64 {
    let full = threads * 8;
    let Some(cap) = stored_cap else {
        return full;
    };
    if done == 0 {
        return threads;
    }
    if stored == 0 {
        return full;
    }
    let need = (cap.saturating_sub(stored) as f64 * done as f64 / stored as f64).ceil() as u64;
    need.div_ceil(threads)
        .max(1)
        .saturating_mul(threads)
        .min(full)
}

/// The error for photon maps that cannot be allocated: a user-set photon count too large
/// for this machine's memory (an allocation failure would otherwise abort the process).
fn too_many_photons(photons: usize) -> Error {
    Error::InvalidInput(format!(
        "photon maps of {photons} photons ({} bytes) cannot be allocated: out of memory; \
         ask for fewer photons (photons, volume_photons, volume_stored)",
        photons.saturating_mul(std::mem::size_of::<Photon>())
    ))
}

/// Make room for `extra` more band powers (`bands` per photon) in `v`, or fail with
/// [`too_many_photons`].
fn grow_powers(v: &mut Vec<f32>, extra: usize, bands: usize) -> Result<()> {
    v.try_reserve(extra)
        .map_err(|_| too_many_photons(v.len().saturating_add(extra) / bands))
}

/// Make room for `extra` more photons in `v`, or fail with [`too_many_photons`].
fn grow(v: &mut Vec<Photon>, extra: usize) -> Result<()> {
    v.try_reserve(extra)
        .map_err(|_| too_many_photons(v.len().saturating_add(extra)))
}

/// [`trace_photons_with`] with a stored-photon budget and aimed emission.
#[allow(clippy::too_many_arguments)]
pub fn trace_emission(
    scene: &Scene,
    emission: &Emission,
    mode: StoreMode,
    targets: Targets,
    tag: u64,
    seed: u64,
    band: u64,
    control: &Control,
) -> Result<PhotonMaps> {
    let scenes = std::slice::from_ref(scene);
    let maps = trace_emission_bands(scenes, emission, mode, targets, tag, seed, band, control)?;
    Ok(maps.into_iter().next().expect("one band"))
}

/// [`trace_emission`] for the bands of one render at once (`scenes`, sharing their
/// geometry): with more than one, a spectral pass ([`super::hero`]) whose photons walk in a
/// hero band each and whose maps (one [`PhotonMaps`] per band) hold the same photons with
/// each band's power. The streams are those of band key `band`.
#[allow(clippy::too_many_arguments)]
pub fn trace_emission_bands(
    scenes: &[Scene],
    emission: &Emission,
    mode: StoreMode,
    targets: Targets,
    tag: u64,
    seed: u64,
    band: u64,
    control: &Control,
) -> Result<Vec<PhotonMaps>> {
    let t0 = Instant::now();
    let photons = emission.photons;
    let nb = scenes.len();
    let nm = scenes[0].media.len();
    let n_batches = photons.div_ceil(BATCH);
    let threads = (rayon::current_num_threads() as u64).max(1);
    let mut volume: Vec<Vec<Photon>> = vec![Vec::new(); nm];
    let mut surface = Vec::new();
    let mut ledger = Ledger::new(nm);
    let mut powers = BandPowers {
        volume: vec![Vec::new(); nm],
        surface: Vec::new(),
        ledgers: vec![Ledger::new(nm); nb],
    };
    let mut emitted = 0u64;
    let mut stored = 0u64;
    let mut start = 0;
    'chunks: while start < n_batches {
        control.check()?;
        let end = (start + chunk_len(emission.stored_cap, stored, start, threads)).min(n_batches);
        let batch = |b: u64, stop_at: Option<u64>| {
            let count = BATCH.min(photons - b * BATCH);
            let mut rng = Stream::new(seed, band, PHOTON_STREAM | tag | b);
            let aim = emission.aim.as_ref();
            let surface_left = emission
                .surface_first
                .map_or(u64::MAX, |n| n.saturating_sub(b * BATCH));
            trace_batch(
                scenes,
                photons,
                count,
                mode,
                targets,
                aim,
                stop_at,
                surface_left,
                &mut rng,
                control,
            )
        };
        let outs: Vec<(u64, BatchOut)> = (start..end)
            .into_par_iter()
            .map(|b| {
                let o = batch(b, None);
                // progress: photons emitted, or with a budget photons stored (the emitted
                // count is not known in advance)
                control.add_done(match emission.stored_cap {
                    Some(_) => o.volume_len(),
                    None => o.traced,
                });
                (b, o)
            })
            .collect();
        for (b, mut o) in outs {
            let last = match emission.stored_cap {
                Some(cap) if stored + o.volume_len() >= cap => {
                    // the budget is reached inside this batch: trace it again (same stream)
                    // up to the photon that reaches it, so the maps overshoot by less than
                    // one emitted photon's events (all its split walks) and the thread count
                    // does not matter
                    o = batch(b, Some(cap - stored));
                    true
                }
                _ => false,
            };
            for (v, ov) in volume.iter_mut().zip(o.volume) {
                stored += ov.len() as u64;
                grow(v, ov.len())?;
                v.extend_from_slice(&ov);
            }
            grow(&mut surface, o.surface.len())?;
            surface.extend_from_slice(&o.surface);
            ledger.add(&o.ledger);
            if let Some(ob) = o.bands {
                for (v, ov) in powers.volume.iter_mut().zip(ob.volume) {
                    grow_powers(v, ov.len(), nb)?;
                    v.extend_from_slice(&ov);
                }
                grow_powers(&mut powers.surface, ob.surface.len(), nb)?;
                powers.surface.extend_from_slice(&ob.surface);
                for (l, ol) in powers.ledgers.iter_mut().zip(&ob.ledgers) {
                    l.add(ol);
                }
            }
            emitted += o.traced;
            if last {
                break 'chunks;
            }
        }
        if let (Some(cap), 0) = (emission.stored_cap, start) {
            // after the first chunk, reserve each map's share of the budget (+5 %) at once:
            // growing by doubling would briefly hold up to 3× the final map
            for v in volume.iter_mut().filter(|v| !v.is_empty()) {
                let share = cap as f64 * v.len() as f64 / stored.max(1) as f64;
                let target = (1.05 * share) as usize + BATCH as usize;
                v.try_reserve_exact(target.saturating_sub(v.len()))
                    .map_err(|_| too_many_photons(target))?;
            }
        }
        start = end;
    }
    control.check()?;
    if emitted > 0 && emitted < photons {
        // powers were Φ / photons; the estimate needs Φ / emitted
        let f = photons as f64 / emitted as f64;
        for p in volume.iter_mut().flatten().chain(surface.iter_mut()) {
            p.power *= f as f32;
        }
        for w in powers
            .volume
            .iter_mut()
            .flatten()
            .chain(powers.surface.iter_mut())
        {
            *w *= f as f32;
        }
        ledger.scale(f);
        for l in &mut powers.ledgers {
            l.scale(f);
        }
    }
    let trace_seconds = t0.elapsed().as_secs_f64();
    if nb == 1 {
        let t1 = Instant::now();
        let volume = (volume.into_iter())
            .map(|v| PhotonMap::try_build(v, control))
            .collect::<Result<Vec<_>>>()?;
        let surface = PhotonMap::try_build(surface, control)?;
        return Ok(vec![PhotonMaps {
            volume,
            surface,
            emitted,
            ledger,
            trace_seconds,
            build_seconds: t1.elapsed().as_secs_f64(),
        }]);
    }
    // band b's maps: the shared photons with band b's powers
    let with_band = |photons: &[Photon], w: &[f32], b: usize| -> Vec<Photon> {
        (photons.iter().zip(w.chunks_exact(nb)))
            .map(|(p, w)| {
                let mut p = *p;
                p.power = w[b];
                p
            })
            .collect()
    };
    let mut maps = Vec::with_capacity(nb);
    for (b, ledger) in powers.ledgers.into_iter().enumerate() {
        control.check()?;
        let t = Instant::now();
        let vol = (volume.iter().zip(&powers.volume))
            .map(|(v, w)| PhotonMap::try_build(with_band(v, w, b), control))
            .collect::<Result<Vec<_>>>()?;
        maps.push(PhotonMaps {
            volume: vol,
            surface: PhotonMap::try_build(with_band(&surface, &powers.surface, b), control)?,
            emitted,
            ledger,
            trace_seconds: trace_seconds / nb as f64,
            build_seconds: t.elapsed().as_secs_f64(),
        });
    }
    Ok(maps)
}

/// The maps a camera pass needs: `settings.volume_photons` photons filling the volume maps
/// (stream tag `tag`), and a surface map from `settings.photons` emitted photons. Those are
/// the volume pass's own first `photons` photons: their random walks are traced to the end
/// anyway, so the surface photons they leave (light that crossed a disc and landed under
/// it) cost nothing, where a separate surface pass traced every walk again. Only when the
/// volume pass emits fewer (a `volume_stored` budget) does a surface pass
/// (`SURFACE_PASS | tag`, independent streams) emit the rest; the two are then one emission
/// of `photons` photons (both emit alike, aimed or not). Used by `vpm`/`vpm-full` (tag 0)
/// and by each `ppm` pass.
pub fn trace_camera_maps(
    scene: &Scene,
    settings: &crate::integrators::settings::Settings,
    mode: StoreMode,
    tag: u64,
    control: &Control,
) -> Result<PhotonMaps> {
    let scenes = std::slice::from_ref(scene);
    let maps = trace_camera_maps_bands(scenes, settings, mode, tag, control)?;
    Ok(maps.into_iter().next().expect("one band"))
}

/// [`trace_camera_maps`] for the bands of one render at once: with more than one scene, a
/// spectral pass ([`trace_emission_bands`]) giving each band its maps.
pub fn trace_camera_maps_bands(
    scenes: &[Scene],
    settings: &crate::integrators::settings::Settings,
    mode: StoreMode,
    tag: u64,
    control: &Control,
) -> Result<Vec<PhotonMaps>> {
    let (seed, band) = (settings.seed, settings.band);
    let emission = Emission {
        photons: settings.volume_photons,
        stored_cap: (settings.volume_stored > 0).then_some(settings.volume_stored),
        aim: Aim::new(&scenes[0], settings.aim),
        surface_first: Some(settings.photons),
    };
    let mut all = trace_emission_bands(
        scenes,
        &emission,
        mode,
        Targets::BOTH,
        tag,
        seed,
        band,
        control,
    )?;
    let emitted = all[0].emitted;
    let from_volume = settings.photons.min(emitted);
    let rest = settings.photons - from_volume;
    // progress counts `photons` surface photons (render.rs): these are done
    control.add_done(from_volume);
    if from_volume > 0 {
        // the volume pass's photons carry Φ / (its photons emitted); as part of an emission
        // of `photons` photons they carry Φ / photons (its tree stands: powers do not move it)
        for maps in &mut all {
            maps.surface
                .scale_powers(emitted as f64 / settings.photons as f64);
        }
    }
    if rest > 0 {
        // the surface pass is aimed too: the light that reaches a surface through a medium
        // (under and behind a disc) is what its map is for
        let surface_emission = Emission {
            photons: rest,
            aim: emission.aim.clone(),
            ..Emission::default()
        };
        let surf_only = Targets {
            volume: false,
            surface: true,
        };
        let tag = SURFACE_PASS | tag;
        let surfs = trace_emission_bands(
            scenes,
            &surface_emission,
            mode,
            surf_only,
            tag,
            seed,
            band,
            control,
        )?;
        for (maps, mut surf) in all.iter_mut().zip(surfs) {
            surf.surface
                .scale_powers(rest as f64 / settings.photons as f64);
            let t0 = Instant::now();
            let pooled = (maps.surface.photons().iter())
                .chain(surf.surface.photons())
                .copied()
                .collect();
            maps.surface = PhotonMap::try_build(pooled, control)?;
            maps.emitted += surf.emitted;
            maps.trace_seconds += surf.trace_seconds;
            maps.build_seconds += surf.build_seconds + t0.elapsed().as_secs_f64();
        }
    }
    for maps in &mut all {
        maps.ledger.stored_surface = maps.surface.total_power();
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photon_maps_too_large_for_memory_are_an_error_not_an_abort() {
        let mut v: Vec<Photon> = Vec::new();
        // more bytes than any address space: refused without allocating
        let e = grow(&mut v, usize::MAX / 4).unwrap_err();
        assert!(matches!(e, Error::InvalidInput(ref m) if m.contains("out of memory")));
        assert!(grow(&mut v, 16).is_ok() && v.capacity() >= 16);
    }
}
