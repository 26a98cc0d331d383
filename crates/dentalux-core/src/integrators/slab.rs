//! The slab simulator: a stack of homogeneous layers, infinite in x and y, lit from above by
//! a collimated beam (normal or oblique) or by diffuse light. It tallies what leaves the top
//! (specular and diffuse reflectance), what leaves the bottom (unscattered and diffuse
//! transmittance) and what each layer absorbs, each with its standard error.
//!
//! Transport is the paper's photon tracing in its simplest geometry: free flight (eq. 2),
//! scatter-or-absorb by the albedo (eqs. 3–4), a new direction from the phase function
//! (eqs. 7–10), and Fresnel reflect-or-refract at every interface. z points down; layer i
//! spans [z_i, z_{i+1}] with z_0 = 0.
//!
//! Two unbiased estimators:
//! - `Analog` (the paper's): every photon carries weight 1 and is scattered or absorbed
//!   whole by the albedo roulette; interfaces reflect or refract it by a Fresnel roulette.
//! - `Weighted` (MCML style): the first-surface specular reflection is taken exactly, each
//!   interaction deposits w(1−a) and keeps w·a, and interfaces reflect or refract the whole
//!   weight by the Fresnel roulette (MCML's default). Once w < 1e-4 the photon finishes by
//!   Russian roulette with survival probability a that keeps its whole weight (and deposits
//!   it all when it loses). Unlike MCML's "survive with 1/m, weight ×m", this conserves
//!   energy exactly photon by photon, so R + T + A = 1 holds per run, not just on average.
//!
//! Splitting the weight at the outer surfaces (tally w(1−R), reflect w·R) was tried and
//! dropped: on the dentin-like slab (μa 0.04, μs 26, g 0.9, n 1.54, d 2 mm) it cut the
//! standard errors by only 5% but cost 3.7× the time per photon, since every photon then
//! walks back to the surfaces until its weight is spent.
//!
//! Hot-loop choices (measured with callgrind): per-layer constants (1/σt, albedo, depths,
//! the constants of eq. 9) are computed once per run, the azimuth comes from a rejection-
//! sampled disc point instead of sin/cos (its normalisation folded into the rotation's
//! division), and a single-lobe phase function draws one uniform per scattering.

use crate::batches;
use crate::control::Control;
use crate::error::{check_positive, check_range, Error, Result};
use crate::fresnel::reflectance_and_cos_t;
use crate::instrument::{self, Window};
use crate::math::{rotate_direction_scaled, Vec3};
use crate::medium::Medium;
use crate::phase::PhaseFunction;
use crate::rng::Stream;
use crate::sampling::{cosine_hemisphere, sample_azimuth_scaled_bits};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Most photons per batch: each batch has its own random stream keyed by (seed, band,
/// batch), so the numbers do not depend on how batches are spread over threads.
pub const BATCH: u64 = 8192;
/// Fewest photons per batch (below this, per-batch set-up would show).
pub const MIN_BATCH: u64 = 256;
/// Batches a run is cut into when it has enough photons, so that slow cases (e.g. 100 000
/// photons of a thick dentin slab) still keep many threads busy to the end.
const TARGET_BATCHES: u64 = 64;

/// Photons per batch for a run of `n_photons`: a function of `n_photons` only, never of
/// the thread count, so a seed gives the same numbers on any machine.
pub fn batch_size(n_photons: u64) -> u64 {
    batch_size_from(n_photons, MIN_BATCH)
}

/// [`batch_size`] with the smallest batch `min_batch`.
fn batch_size_from(n_photons: u64, min_batch: u64) -> u64 {
    (n_photons / TARGET_BATCHES).clamp(min_batch, BATCH)
}
/// Fewest photons per batch of a rim walk ([`BackingOrders::past_rim_only`]): each of its
/// photons is split into several walks, so small batches cost little set-up, and a run of a
/// few hundred photons still has [`REPLICATES`] batches for its standard error.
pub const MIN_RIM_BATCH: u64 = 8;

/// [`batch_size`], or for a rim walk the same with [`MIN_RIM_BATCH`].
fn run_batch_size(cfg: &SlabConfig) -> u64 {
    let min_batch = if cfg.is_rim_walk() {
        MIN_RIM_BATCH
    } else {
        MIN_BATCH
    };
    batch_size_from(cfg.n_photons, min_batch)
}
/// Below this weight the weighted estimator switches to the energy-exact roulette.
const WEIGHT_THRESHOLD: f64 = 1e-4;
/// Importance splitting of the rim walk ([`BackingOrders::past_rim_only`]): its tallies
/// come only from photons that reach the specimen's rim (and, for the window, come back), so
/// a photon is split in two, each half the weight, when it first gets farther out than each
/// of these fractions of the rim radius, and again, once past the rim, when it first comes
/// back inside each of them. Splitting keeps every tally's expectation (the halves are
/// independent continuations) and spends the walk's time on the histories that count.
const RIM_SPLIT_FRACTIONS: [f64; 3] = [0.5, 0.7, 0.85];
/// A photon with more interactions than this means an input Monte Carlo cannot finish.
pub(crate) const MAX_EVENTS: u64 = 50_000_000;

/// One layer of the slab.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlabLayer {
    /// The layer's medium.
    pub medium: Medium,
    /// Thickness [mm].
    pub thickness: f64,
}

/// How the slab's top is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Incidence {
    /// Collimated beam along +z.
    Normal,
    /// Collimated beam at this polar angle [rad] from the normal, in the above medium.
    Angle(f64),
    /// Diffuse (Lambertian) light from the whole upper hemisphere.
    Diffuse,
}

impl Incidence {
    /// From its name (`normal`, `diffuse`, `angle`; the polar angle `angle_deg` [deg] for
    /// `angle`), as the Python API and CLI spell it.
    pub fn parse(name: &str, angle_deg: f64) -> Result<Self> {
        match name {
            "normal" => Ok(Incidence::Normal),
            "diffuse" => Ok(Incidence::Diffuse),
            "angle" => Ok(Incidence::Angle(angle_deg.to_radians())),
            other => Err(Error::InvalidInput(format!(
                "incidence = {other:?}: allowed 'normal', 'diffuse' or 'angle'"
            ))),
        }
    }
}

/// Which estimator tallies the photons.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Estimator {
    /// Albedo roulette, weight 1 (the paper's).
    Analog,
    /// Weight deposition with energy-exact roulette (MCML style).
    Weighted,
}

impl Estimator {
    /// From its name (`analog`, `weighted`).
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "analog" => Ok(Estimator::Analog),
            "weighted" => Ok(Estimator::Weighted),
            other => Err(Error::InvalidInput(format!(
                "estimator = {other:?}: allowed 'analog' or 'weighted'"
            ))),
        }
    }
}

/// Everything one slab run needs.
#[derive(Debug, Clone, PartialEq)]
pub struct SlabConfig {
    /// Layers from top to bottom.
    pub layers: Vec<SlabLayer>,
    /// Refractive index above the slab.
    pub n_above: f64,
    /// Refractive index below the slab.
    pub n_below: f64,
    /// Illumination.
    pub incidence: Incidence,
    /// Estimator.
    pub estimator: Estimator,
    /// Number of photons launched (≥ 1).
    pub n_photons: u64,
    /// Seed of the run.
    pub seed: u64,
    /// Band index, mixed into the random streams.
    pub band: u64,
    /// Radial profile: number of bins and maximum radius [mm]; `None` for no profile.
    pub radial: Option<(usize, f64)>,
    /// Number of exit-angle bins over [0, 90°]; `None` for no histogram.
    pub angular_bins: Option<usize>,
    /// An instrument's finite lit spot, window and backing; `None` for the laterally
    /// infinite slab in the media above and below.
    pub window: Option<Window>,
    /// Tally the window by backing order instead of using the window's backing (see
    /// [`BackingOrders`]); needs a window.
    pub backing_orders: Option<BackingOrders>,
}

/// Every backing from one walk. A Lambertian backing of reflectance R_b returns what reaches
/// it with the same (cosine) direction law whatever R_b is, so a walk's history does not
/// depend on R_b except through the factor R_b per reflection. The walk therefore always
/// reflects at the backing, counts the reflections k, and tallies each window exit by k:
/// the reading over any backing is then the polynomial Σ_k V_k R_b^k, exactly, and every
/// backing is read from the same photons (their noise shared). Order k + 1 is reached by
/// survival roulette with probability `survival` (the weight divided by it), so walks under
/// a bright backing end; a walk reaching `max_order` backing reflections is cut and its
/// weight tallied as truncated (the polynomial misses it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackingOrders {
    /// Highest order tallied, in [1, [`MAX_BACKING_ORDER`]].
    pub max_order: usize,
    /// Probability of continuing after a backing reflection, in (0, 1].
    pub survival: f64,
    /// Tally only what the specimen's rim takes from the window: the walk goes on past the
    /// rim as in a laterally infinite specimen, and a window exit counts only once the walk
    /// has crossed the rim. The run then estimates (infinite specimen − finite specimen),
    /// the correction that a laterally infinite solution needs
    /// (python/dentalux/reading/layered.py); it is small, so it takes few photons.
    pub past_rim_only: bool,
}

impl BackingOrders {
    /// Check the highest order and the survival probability; messages name the field and
    /// its allowed range.
    pub fn validate(&self) -> Result<()> {
        if self.max_order == 0 || self.max_order > MAX_BACKING_ORDER {
            return Err(Error::InvalidInput(format!(
                "backing max_order = {} is out of range: allowed [1, {MAX_BACKING_ORDER}]",
                self.max_order
            )));
        }
        check_range("backing survival", self.survival, 0.0, true, 1.0, false, "")
    }
}

/// Most replicates (groups of consecutive batches) a backing-order run returns.
pub const REPLICATES: usize = 64;

/// Highest backing order a run may tally (bounds its memory: orders × 6 tallies per batch).
pub const MAX_BACKING_ORDER: usize = 1024;

/// Most bins of a radial or angular profile (`dentalux.limits` reads it): each batch keeps
/// its own copies, so the cap bounds a run's profile memory before anything is allocated.
pub const MAX_PROFILE_BINS: usize = 1_000_000;

/// Scalar results, in this order in [`SlabResult::values`] and [`SlabResult::stderr`].
pub const SCALAR_KEYS: [&str; 7] = [
    "specular_reflectance",
    "diffuse_reflectance",
    "total_reflectance",
    "unscattered_transmittance",
    "diffuse_transmittance",
    "total_transmittance",
    "absorbed",
];
const SPEC: usize = 0;
const DIFF_R: usize = 1;
const TOT_R: usize = 2;
const UNSC_T: usize = 3;
const DIFF_T: usize = 4;
const TOT_T: usize = 5;
const ABS: usize = 6;
/// Per-photon scalars: [`SCALAR_KEYS`] then the window's [`instrument::WINDOW_KEYS`].
const N_SCALARS: usize = 7;
const N_WINDOW: usize = instrument::WINDOW_KEYS.len();
const N_TALLIES: usize = N_SCALARS + N_WINDOW;

/// What a slab run measured; all fractions of the incident power.
#[derive(Debug, Clone, PartialEq)]
pub struct SlabResult {
    /// Means of [`SCALAR_KEYS`]. "Diffuse" reflectance is everything leaving the top except
    /// the first-surface specular reflection (as in MCML's Rd).
    pub values: [f64; 7],
    /// Standard errors of the means, per photon.
    pub stderr: [f64; 7],
    /// Absorbed fraction per layer.
    pub absorbed_per_layer: Vec<f64>,
    /// Photons launched.
    pub photons: u64,
    /// Diffuse reflectance per unit area R(r) [1/mm²] at radial bin centres (if asked).
    pub radial_reflectance: Vec<f64>,
    /// Transmittance per unit area T(r) [1/mm²] (if asked).
    pub radial_transmittance: Vec<f64>,
    /// Fraction of power leaving the top per exit-angle bin (if asked), specular excluded.
    pub angular_reflectance: Vec<f64>,
    /// Fraction of power leaving the bottom per exit-angle bin (if asked).
    pub angular_transmittance: Vec<f64>,
    /// Means of the window tallies [`instrument::WINDOW_KEYS`] (zeros without a window).
    pub window: [f64; 6],
    /// Their standard errors.
    pub window_stderr: [f64; 6],
    /// With [`BackingOrders`]: each replicate's sums of the window tallies by backing order,
    /// `[replicate][order][key]` flattened (keys [`instrument::WINDOW_KEYS`]); a replicate
    /// is a group of consecutive batches, at most [`REPLICATES`]. Empty otherwise.
    pub order_sums: Vec<f64>,
    /// Photons of each replicate (with [`BackingOrders`]).
    pub batch_photons: Vec<u64>,
    /// Weight cut at the highest backing order, per photon launched.
    pub truncated: f64,
    /// Whether the photons were walked in lanes ([`simulate_with`]).
    pub lanes: bool,
}

impl SlabResult {
    /// Mean of the scalar named `key` (one of [`SCALAR_KEYS`]).
    pub fn get(&self, key: &str) -> Option<f64> {
        SCALAR_KEYS
            .iter()
            .position(|k| *k == key)
            .map(|i| self.values[i])
    }
}

impl SlabConfig {
    /// Whether this run is a rim walk ([`BackingOrders::past_rim_only`]).
    pub fn is_rim_walk(&self) -> bool {
        self.backing_orders.is_some_and(|o| o.past_rim_only)
    }

    /// Check every field; messages name the field and its allowed range.
    pub fn validate(&self) -> Result<()> {
        if self.layers.is_empty() {
            return Err(Error::InvalidInput(
                "layers: at least one layer is needed".into(),
            ));
        }
        for (i, l) in self.layers.iter().enumerate() {
            let name = format!("layers[{i}].");
            Medium::new(
                &name,
                l.medium.sigma_a,
                l.medium.sigma_s,
                l.medium.eta,
                l.medium.phase,
            )?;
            check_positive(&format!("{name}thickness"), l.thickness, "mm")?;
        }
        check_range("n_above", self.n_above, 1.0, false, f64::INFINITY, true, "")?;
        check_range("n_below", self.n_below, 1.0, false, f64::INFINITY, true, "")?;
        if self.n_photons == 0 {
            return Err(Error::InvalidInput(
                "photons = 0 is out of range: allowed [1, 2^64)".into(),
            ));
        }
        if let Incidence::Angle(theta) = self.incidence {
            check_range(
                "incidence angle",
                theta.to_degrees(),
                0.0,
                false,
                90.0,
                true,
                "deg",
            )?;
        }
        let max = MAX_PROFILE_BINS;
        if let Some((bins, rmax)) = self.radial {
            if bins == 0 || bins > max {
                return Err(Error::InvalidInput(format!(
                    "radial bins = {bins} is out of range: allowed [1, {max}]"
                )));
            }
            check_positive("radial max", rmax, "mm")?;
        }
        if let Some(bins) = self.angular_bins {
            if bins == 0 || bins > max {
                return Err(Error::InvalidInput(format!(
                    "angular bins = {bins} is out of range: allowed [1, {max}]"
                )));
            }
        }
        if let Some(w) = &self.window {
            w.validate()?;
        }
        if let Some(o) = &self.backing_orders {
            if self.window.is_none() {
                return Err(Error::InvalidInput(
                    "backing orders need an instrument window".into(),
                ));
            }
            o.validate()?;
        }
        Ok(())
    }
}

/// Per-batch accumulators: per-photon sums and sums of squares of each scalar.
#[derive(Clone)]
struct Tally {
    sum: [f64; N_TALLIES],
    sumsq: [f64; N_TALLIES],
    absorbed: Vec<f64>,
    radial_r: Vec<f64>,
    radial_t: Vec<f64>,
    angle_r: Vec<f64>,
    angle_t: Vec<f64>,
    /// Window tallies by backing order, `[order][key]` (empty without [`BackingOrders`]).
    orders: Vec<f64>,
    /// Weight of walks cut at the highest backing order.
    truncated: f64,
    /// Backing order of the photon being traced.
    order: usize,
    /// With backing orders, the photon's entry point and the square of the farthest it has
    /// been from it (see [`Tracer::window_fraction`]).
    entry: (f64, f64),
    excursion2: f64,
    /// Whether the photon has crossed the specimen's rim ([`BackingOrders::past_rim_only`]).
    past_rim: bool,
    /// The rim walk's splitting level the photon has reached (see [`RIM_SPLIT_FRACTIONS`]).
    level: usize,
    /// Halves of split photons still to be walked.
    pending: Vec<Split>,
}

/// A split photon's half, walked after the rest of its family.
#[derive(Clone, Copy)]
struct Split {
    pos: Vec3,
    d: Vec3,
    layer: isize,
    w: f64,
    scattered: bool,
    roulette: bool,
    order: usize,
    entry: (f64, f64),
    excursion2: f64,
    past_rim: bool,
    level: usize,
}

impl Tally {
    fn new(cfg: &SlabConfig) -> Self {
        let rb = cfg.radial.map_or(0, |r| r.0);
        let ab = cfg.angular_bins.unwrap_or(0);
        Self {
            sum: [0.0; N_TALLIES],
            sumsq: [0.0; N_TALLIES],
            absorbed: vec![0.0; cfg.layers.len()],
            radial_r: vec![0.0; rb],
            radial_t: vec![0.0; rb],
            angle_r: vec![0.0; ab],
            angle_t: vec![0.0; ab],
            orders: vec![0.0; cfg.backing_orders.map_or(0, |o| o.max_order + 1) * N_WINDOW],
            truncated: 0.0,
            order: 0,
            entry: (0.0, 0.0),
            excursion2: 0.0,
            past_rim: false,
            level: 0,
            pending: Vec::new(),
        }
    }
    fn merge(&mut self, o: &Tally) {
        let add = |a: &mut [f64], b: &[f64]| a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        add(&mut self.sum, &o.sum);
        add(&mut self.sumsq, &o.sumsq);
        add(&mut self.absorbed, &o.absorbed);
        add(&mut self.radial_r, &o.radial_r);
        add(&mut self.radial_t, &o.radial_t);
        add(&mut self.angle_r, &o.angle_r);
        add(&mut self.angle_t, &o.angle_t);
        add(&mut self.orders, &o.orders);
        self.truncated += o.truncated;
    }
}

/// Run the slab simulation. Batches (see [`batch_size`]) run in parallel on the current
/// rayon pool and are reduced in batch order, so a seed gives the same numbers for any
/// thread count.
pub fn simulate(cfg: &SlabConfig, control: &Control) -> Result<SlabResult> {
    simulate_with(cfg, control, true)
}

/// [`simulate`], by the lanes walk where it applies (the weighted estimator with no lateral
/// tally, see slab_lanes.rs) when `lanes`, else by the walk of one photon at a time.
pub fn simulate_with(cfg: &SlabConfig, control: &Control, lanes: bool) -> Result<SlabResult> {
    cfg.validate()?;
    let batch = run_batch_size(cfg);
    let n_batches = cfg.n_photons.div_ceil(batch);
    let tracer = Tracer::new(cfg);
    let plan = if lanes { lanes::Plan::new(cfg) } else { None };
    // batches taken one at a time by each thread, results in batch order (crate::batches)
    let tallies: Result<Vec<Tally>> = batches::in_order(n_batches, |b| {
        control.check()?;
        let count = batch.min(cfg.n_photons - b * batch);
        let mut rng = Stream::new(cfg.seed, cfg.band, b);
        let mut tally = Tally::new(cfg);
        if let Some(plan) = &plan {
            lanes::run_batch(plan, &mut rng, count, &mut tally, control)?;
        } else {
            let mut photon = [0.0; N_TALLIES];
            for _ in 0..count {
                photon.fill(0.0);
                tracer.trace(&mut rng, &mut photon, &mut tally, control)?;
                for (k, x) in photon.iter().enumerate() {
                    tally.sum[k] += x;
                    tally.sumsq[k] += x * x;
                }
            }
        }
        control.add_done(count);
        Ok(tally)
    });
    let tallies = tallies?;
    let mut total = Tally::new(cfg);
    for t in &tallies {
        total.merge(t);
    }
    let mut res = tracer.finish(&total);
    res.lanes = plan.is_some();
    if cfg.backing_orders.is_some() {
        // consecutive batches pooled into at most REPLICATES groups: independent replicates
        // whose spread gives the standard error of anything computed from the polynomial
        let groups = (n_batches as usize).min(REPLICATES);
        let width = total.orders.len();
        res.order_sums = vec![0.0; groups * width];
        res.batch_photons = vec![0; groups];
        for (b, t) in tallies.iter().enumerate() {
            let g = b * groups / n_batches as usize;
            let slot = &mut res.order_sums[g * width..(g + 1) * width];
            slot.iter_mut().zip(&t.orders).for_each(|(x, y)| *x += y);
            res.batch_photons[g] += batch.min(cfg.n_photons - b as u64 * batch);
        }
    }
    Ok(res)
}

/// Run several slab configurations (a specimen's bands) on the current rayon pool; each
/// gives the numbers [`simulate`] gives it alone.
pub fn simulate_all(cfgs: &[SlabConfig], control: &Control) -> Result<Vec<SlabResult>> {
    for cfg in cfgs {
        cfg.validate()?;
    }
    cfgs.par_iter().map(|cfg| simulate(cfg, control)).collect()
}

/// Distance along a direction with z component `dz` from depth `z` to the face of the layer
/// [`z_top`, `z_bot`] it is heading for (+∞ when it runs parallel to them).
#[inline]
pub(crate) fn distance_to_faces(z: f64, dz: f64, z_top: f64, z_bot: f64) -> f64 {
    if dz > 0.0 {
        (z_bot - z) / dz
    } else if dz < 0.0 {
        (z_top - z) / dz
    } else {
        f64::INFINITY
    }
}

/// Count one event of a walk: every 65 536 events poll for cancellation, and refuse a walk
/// past [`MAX_EVENTS`] (`layer` names where it was, for the message).
#[inline]
pub(crate) fn count_event(
    events: &mut u64,
    control: &Control,
    layer: impl FnOnce() -> String,
) -> Result<()> {
    *events += 1;
    if *events & 0xFFFF == 0 {
        control.check()?;
        if *events > MAX_EVENTS {
            return Err(Error::InvalidInput(format!(
                "a photon exceeded {MAX_EVENTS} interactions: the slab is too thick optically \
                 for Monte Carlo ({})",
                layer()
            )));
        }
    }
    Ok(())
}

/// A Lambertian reflection off a backing in a medium of index `n_below`: a cosine-weighted
/// direction up, refracted into the bottom layer (index `eta`), or `None` when the Fresnel
/// roulette sends it back down onto the backing.
pub(crate) fn lambertian_up_into(rng: &mut Stream, n_below: f64, eta: f64) -> Option<Vec3> {
    let up = cosine_hemisphere(rng.uniform2());
    let (r, cos_t) = reflectance_and_cos_t(up.z, n_below, eta);
    if r >= 1.0 || (r > 0.0 && rng.uniform() < r) {
        return None;
    }
    let k = n_below / eta;
    Some(Vec3::new(up.x * k, up.y * k, -cos_t))
}

/// Per-layer constants of the walk, computed once per run instead of once per step.
#[derive(Clone, Copy)]
struct LayerConst {
    /// Extinction σt [1/mm].
    sigma_t: f64,
    /// 1/σt [mm]; +∞ for a non-interacting layer.
    mfp: f64,
    /// Single-scattering albedo σs/σt (eq. 3).
    albedo: f64,
    /// Refractive index.
    eta: f64,
    /// Depth of the layer's top and bottom [mm].
    z_top: f64,
    z_bot: f64,
    /// Whether the phase function needs a second uniform (lobe choice).
    two_uniforms: bool,
    /// Eq. 9 with its constants precomputed, for a plain HG phase function with |g| ≥ 1e-3
    /// (others go through [`PhaseFunction::sample_cos`]).
    hg: Option<HgSampler>,
}

/// Eq. 9, cos θ = (1 + g² − ((1 − g²)/(1 − g + 2gξ))²)/(2g), with the constants of one g.
#[derive(Clone, Copy)]
struct HgSampler {
    one_plus_g2: f64,
    one_minus_g2: f64,
    one_minus_g: f64,
    two_g: f64,
    inv_two_g: f64,
}

impl HgSampler {
    fn new(phase: &PhaseFunction) -> Option<Self> {
        match *phase {
            // small |g| is left to the phase function, which switches to isotropic sampling
            PhaseFunction::HenyeyGreenstein { g } if g.abs() >= 1e-3 => Some(Self {
                one_plus_g2: 1.0 + g * g,
                one_minus_g2: 1.0 - g * g,
                one_minus_g: 1.0 - g,
                two_g: 2.0 * g,
                inv_two_g: 0.5 / g,
            }),
            _ => None,
        }
    }

    #[inline]
    fn sample_cos(&self, xi: f64) -> f64 {
        let frac = self.one_minus_g2 / (self.one_minus_g + self.two_g * xi);
        ((self.one_plus_g2 - frac * frac) * self.inv_two_g).clamp(-1.0, 1.0)
    }
}

/// One photon's contributions to every per-photon tally.
/// A point uniform over the lit region of `win` (the origin for a pencil beam): over the
/// disc of radius a as r = a √u, over the ring [a₀, a] as r = √(a₀² + u (a² − a₀²)).
#[inline]
pub(crate) fn entry_point(win: &Window, rng: &mut Stream) -> Vec3 {
    if win.illuminated_radius <= 0.0 {
        return Vec3::ZERO;
    }
    let (c, s, rho) = sample_azimuth_scaled_bits(|| rng.next_bits());
    let a = win.illuminated_radius;
    let a0 = win.illuminated_inner_radius;
    let r = if a0 == 0.0 {
        a * rng.uniform().sqrt() / rho
    } else {
        (a0 * a0 + rng.uniform() * (a * a - a0 * a0)).sqrt() / rho
    };
    Vec3::new(r * c, r * s, 0.0)
}

type Photon = [f64; N_TALLIES];
/// Most Lambertian bounces of one visit to the backing before the photon is given up to it.
pub(crate) const MAX_BACKING_BOUNCES: usize = 10_000;

/// Precomputed geometry of the stack plus the photon walk.
struct Tracer<'a> {
    cfg: &'a SlabConfig,
    /// Constants of each layer, top to bottom.
    layers: Vec<LayerConst>,
    /// Squared specimen radius [mm²] (∞ without a window or rim).
    rim2: f64,
    /// Backing reflectance (0 without a window).
    backing: f64,
    /// 1 / the Lambertian fraction of the detector cone.
    inv_cone_fraction: f64,
    /// Backing-order tallies (the window's backing then unused).
    orders: Option<BackingOrders>,
    /// [`BackingOrders::past_rim_only`].
    past_rim_only: bool,
    /// Squared radii of [`RIM_SPLIT_FRACTIONS`] of the rim (∞ without a window), read only
    /// in a rim walk.
    split_r2: [f64; 3],
}

impl<'a> Tracer<'a> {
    fn new(cfg: &'a SlabConfig) -> Self {
        let mut z = 0.0;
        let layers = cfg
            .layers
            .iter()
            .map(|l| {
                let sigma_t = l.medium.sigma_t();
                let c = LayerConst {
                    sigma_t,
                    mfp: if sigma_t > 0.0 {
                        1.0 / sigma_t
                    } else {
                        f64::INFINITY
                    },
                    albedo: l.medium.albedo(),
                    eta: l.medium.eta,
                    z_top: z,
                    z_bot: z + l.thickness,
                    two_uniforms: l.medium.phase.uses_second_uniform(),
                    hg: HgSampler::new(&l.medium.phase),
                };
                z += l.thickness;
                c
            })
            .collect();
        let win = cfg.window;
        Self {
            cfg,
            layers,
            rim2: win.map_or(f64::INFINITY, |w| w.specimen_radius * w.specimen_radius),
            backing: win.map_or(0.0, |w| w.backing),
            inv_cone_fraction: win.map_or(1.0, |w| 1.0 / w.cone_fraction()),
            orders: cfg.backing_orders,
            past_rim_only: cfg.is_rim_walk(),
            split_r2: RIM_SPLIT_FRACTIONS
                .map(|f| win.map_or(f64::INFINITY, |w| (f * w.specimen_radius).powi(2))),
        }
    }

    /// The rim walk's splitting level at `pos`: how many of the split radii lie inside it
    /// before the rim is crossed; after, all of them and how many lie outside it.
    #[inline]
    fn rim_level(&self, pos: Vec3, past_rim: bool) -> usize {
        let r2 = pos.x * pos.x + pos.y * pos.y;
        if past_rim {
            self.split_r2.len() + self.split_r2.iter().filter(|&&b| r2 < b).count()
        } else {
            self.split_r2.iter().filter(|&&b| r2 > b).count()
        }
    }

    fn eta_of(&self, layer: isize) -> f64 {
        if layer < 0 {
            self.cfg.n_above
        } else if layer as usize >= self.layers.len() {
            self.cfg.n_below
        } else {
            self.layers[layer as usize].eta
        }
    }

    /// Record power `w` leaving the slab at `pos` along `d` (top if d.z < 0).
    fn exit(&self, pos: Vec3, d: Vec3, w: f64, scattered: bool, ph: &mut Photon, t: &mut Tally) {
        let top = d.z < 0.0;
        if top {
            ph[DIFF_R] += w;
            ph[TOT_R] += w;
        } else {
            ph[if scattered { DIFF_T } else { UNSC_T }] += w;
            ph[TOT_T] += w;
        }
        if let Some(win) = &self.cfg.window {
            self.exit_window(win, pos, d.z, w, top, ph, t);
        }
        if let Some((bins, rmax)) = self.cfg.radial {
            let r = (pos.x * pos.x + pos.y * pos.y).sqrt();
            let b = (r / rmax * bins as f64) as usize;
            if b < bins {
                let v = if top {
                    &mut t.radial_r
                } else {
                    &mut t.radial_t
                };
                v[b] += w;
            }
        }
        if let Some(bins) = self.cfg.angular_bins {
            let theta = d.z.abs().min(1.0).acos();
            let b = ((theta / (0.5 * PI)) * bins as f64).min(bins as f64 - 1.0) as usize;
            let v = if top { &mut t.angle_r } else { &mut t.angle_t };
            v[b] += w;
        }
    }

    /// Add `w` to window tally `key`, and to its slot of the photon's backing order.
    #[inline]
    fn window_add(&self, key: usize, w: f64, ph: &mut Photon, t: &mut Tally) {
        if self.past_rim_only && !t.past_rim {
            return;
        }
        ph[N_SCALARS + key] += w;
        if !t.orders.is_empty() {
            t.orders[t.order * N_WINDOW + key] += w;
        }
    }

    /// Tally power `w` leaving at `pos` (|cos θ| = `cos_exit` in the medium outside)
    /// against the window: inside or outside it on the top, inside it on the bottom.
    /// Returns the part of the exit the window reads ([`Tracer::window_fraction`]).
    #[allow(clippy::too_many_arguments)]
    fn exit_window(
        &self,
        win: &Window,
        pos: Vec3,
        cos_exit: f64,
        w: f64,
        top: bool,
        ph: &mut Photon,
        t: &mut Tally,
    ) -> f64 {
        let frac = self.window_fraction(win, pos, t);
        if frac == 1.0 || frac == 0.0 {
            let inside = frac == 1.0;
            if !top {
                if inside {
                    self.window_add(instrument::VIEWED_T, w, ph, t);
                }
            } else if inside {
                self.window_add(instrument::VIEWED_R, w, ph, t);
                if win.in_cone(cos_exit) {
                    self.window_add(instrument::VIEWED_CONE, w * self.inv_cone_fraction, ph, t);
                }
            } else {
                self.window_add(instrument::OUTSIDE_R, w, ph, t);
            }
            return frac;
        }
        let (w_in, w_out) = (w * frac, w * (1.0 - frac));
        if !top {
            self.window_add(instrument::VIEWED_T, w_in, ph, t);
        } else {
            self.window_add(instrument::VIEWED_R, w_in, ph, t);
            if win.in_cone(cos_exit) {
                self.window_add(
                    instrument::VIEWED_CONE,
                    w_in * self.inv_cone_fraction,
                    ph,
                    t,
                );
            }
            self.window_add(instrument::OUTSIDE_R, w_out, ph, t);
        }
        frac
    }

    /// The part of an exit at `pos` that the window reads: 1 inside, 0 outside, or, with
    /// backing orders, the exit's expectation over the entry point. The specimen is the same
    /// everywhere across, so a walk displaced by Δ from a uniform entry point x in the lit
    /// disc leaves inside the window with probability [`Window::overlap_fraction`](|Δ|); that
    /// conditional expectation replaces the sampled indicator (no noise from where the photon
    /// happened to enter). It holds while no entry point could have taken the walk past the
    /// specimen's rim (lit radius + farthest excursion < rim radius); otherwise the sampled
    /// entry point decides, as without backing orders. Both are unbiased given the walk.
    #[inline]
    fn window_fraction(&self, win: &Window, pos: Vec3, t: &Tally) -> f64 {
        if self.orders.is_some() {
            let (dx, dy) = (pos.x - t.entry.0, pos.y - t.entry.1);
            let reach = win.illuminated_radius + t.excursion2.sqrt();
            if reach * reach < self.rim2 {
                return win.overlap_fraction((dx * dx + dy * dy).sqrt());
            }
        }
        let r2 = pos.x * pos.x + pos.y * pos.y;
        if win.in_window(r2) {
            1.0
        } else {
            0.0
        }
    }

    /// Record how far the photon at `pos` has gone from its entry point (backing orders).
    #[inline]
    fn track_excursion(&self, pos: Vec3, t: &mut Tally) {
        if self.orders.is_some() {
            let (dx, dy) = (pos.x - t.entry.0, pos.y - t.entry.1);
            t.excursion2 = t.excursion2.max(dx * dx + dy * dy);
        }
    }

    /// The first-surface specular reflection of power `w` at the entry point `pos`.
    fn specular(&self, pos: Vec3, cos_in: f64, w: f64, ph: &mut Photon, t: &mut Tally) {
        ph[SPEC] += w;
        ph[TOT_R] += w;
        if let Some(win) = &self.cfg.window {
            let frac = self.exit_window(win, pos, cos_in, w, true, ph, t);
            if frac > 0.0 {
                self.window_add(instrument::VIEWED_SPEC, w * frac, ph, t);
            }
        }
    }

    /// Whether the walk at `pos` ends at the specimen's rim: beyond it, its power `w` is
    /// tallied as lost there; with [`BackingOrders::past_rim_only`] it goes on, marked, and
    /// its first crossing tallies −`w` (the infinite specimen loses nothing there, the
    /// finite one `w`: the run estimates infinite − finite).
    #[inline]
    fn ends_at_rim(&self, pos: Vec3, w: f64, ph: &mut Photon, t: &mut Tally) -> bool {
        if pos.x * pos.x + pos.y * pos.y <= self.rim2 {
            return false;
        }
        if self.past_rim_only {
            if !t.past_rim {
                t.past_rim = true;
                self.window_add(instrument::RIM, -w, ph, t);
            }
            return false;
        }
        self.window_add(instrument::RIM, w, ph, t);
        true
    }

    /// Trace one photon; its contributions go to `ph` (scalars) and `t` (profiles).
    fn trace(
        &self,
        rng: &mut Stream,
        ph: &mut Photon,
        t: &mut Tally,
        control: &Control,
    ) -> Result<()> {
        let cfg = self.cfg;
        let weighted = cfg.estimator == Estimator::Weighted;
        let n_layers = self.layers.len() as isize;
        t.order = 0;
        t.excursion2 = 0.0;
        t.past_rim = false;
        t.level = 0;
        t.pending.clear();
        // launch direction in the medium above
        let d_above = match cfg.incidence {
            Incidence::Normal => Vec3::Z,
            Incidence::Angle(theta) => Vec3::new(theta.sin(), 0.0, theta.cos()),
            Incidence::Diffuse => cosine_hemisphere(rng.uniform2()),
        };
        // entry point: uniform over the lit disc or ring of a window, else the origin
        let mut pos = Vec3::ZERO;
        if let Some(win) = &cfg.window {
            pos = entry_point(win, rng);
        }
        t.entry = (pos.x, pos.y);
        let eta0 = self.layers[0].eta;
        let (r0, cos_t0) = reflectance_and_cos_t(d_above.z, cfg.n_above, eta0);
        let mut w = 1.0;
        if weighted {
            self.specular(pos, d_above.z, r0, ph, t);
            w = 1.0 - r0;
            if w <= 0.0 {
                return Ok(());
            }
        } else if rng.uniform() < r0 {
            self.specular(pos, d_above.z, 1.0, ph, t);
            return Ok(());
        }
        let k = cfg.n_above / eta0;
        let mut d = Vec3::new(d_above.x * k, d_above.y * k, cos_t0);
        let mut layer: isize = 0;
        let mut scattered = false;
        // `roulette` is set once the weighted photon's weight fell below the threshold
        let mut roulette = !weighted;
        let mut events: u64 = 0;
        // the photon, then each half split off it (the rim walk's splitting), in turn
        loop {
            'walk: loop {
                let li = layer as usize;
                let lc = &self.layers[li];
                // free flight (eq. 2); +∞ in a non-interacting layer
                let s = -rng.uniform_open0().ln() * lc.mfp;
                let db = distance_to_faces(pos.z, d.z, lc.z_top, lc.z_bot);
                count_event(&mut events, control, || {
                    format!(
                        "layers[{li}] μt·d = {:.3e}",
                        lc.sigma_t * (lc.z_bot - lc.z_top)
                    )
                })?;
                if s < db {
                    // interaction inside layer li (eqs. 2–4)
                    pos += d * s;
                    self.track_excursion(pos, t);
                    if self.ends_at_rim(pos, w, ph, t) {
                        break 'walk;
                    }
                    if roulette {
                        if rng.uniform() >= lc.albedo {
                            t.absorbed[li] += w;
                            ph[ABS] += w;
                            break 'walk;
                        }
                    } else {
                        let dep = w * (1.0 - lc.albedo);
                        t.absorbed[li] += dep;
                        ph[ABS] += dep;
                        w -= dep;
                        if w < WEIGHT_THRESHOLD {
                            roulette = true;
                        }
                    }
                    // new direction from the phase function (eqs. 7–10); the second uniform
                    // is drawn only for mixtures, the azimuth without trigonometry
                    let u0 = rng.uniform();
                    let cos_theta = match &lc.hg {
                        Some(hg) => hg.sample_cos(u0),
                        None => {
                            let u1 = if lc.two_uniforms { rng.uniform() } else { 0.0 };
                            cfg.layers[li].medium.phase.sample_cos([u0, u1])
                        }
                    };
                    let (c, s, rho) = sample_azimuth_scaled_bits(|| rng.next_bits());
                    d = rotate_direction_scaled(d, cos_theta, c, s, rho);
                    scattered = true;
                    // split after the interaction: each half flies on from here
                    if self.past_rim_only {
                        let level = self.rim_level(pos, t.past_rim);
                        while t.level < level {
                            t.level += 1;
                            w *= 0.5;
                            t.pending.push(Split {
                                pos,
                                d,
                                layer,
                                w,
                                scattered,
                                roulette,
                                order: t.order,
                                entry: t.entry,
                                excursion2: t.excursion2,
                                past_rim: t.past_rim,
                                level: t.level,
                            });
                        }
                    }
                    continue;
                }
                // reach the interface
                let down = d.z > 0.0;
                pos += d * db;
                pos.z = if down { lc.z_bot } else { lc.z_top };
                self.track_excursion(pos, t);
                if self.ends_at_rim(pos, w, ph, t) {
                    break 'walk;
                }
                let next = if down { layer + 1 } else { layer - 1 };
                let eta_i = lc.eta;
                let eta_t = self.eta_of(next);
                let (r, cos_t) = reflectance_and_cos_t(d.z, eta_i, eta_t);
                let outside = next < 0 || next >= n_layers;
                let k = eta_i / eta_t;
                let d_t = Vec3::new(d.x * k, d.y * k, if down { cos_t } else { -cos_t });
                // Fresnel reflect-or-refract roulette at every interface, in both estimators
                if r >= 1.0 || (r > 0.0 && rng.uniform() < r) {
                    d.z = -d.z;
                    continue;
                }
                d = d_t;
                if outside && down && self.orders.is_some() {
                    match self.backing_orders_bounce(rng, pos, &mut d, &mut w, ph, t) {
                        Some(()) => {
                            scattered = true;
                            continue;
                        }
                        None => break 'walk,
                    }
                }
                if outside && down && self.backing > 0.0 {
                    // the backing under the stack (zero gap, in the medium below)
                    let hit = self.backing_bounce(
                        rng,
                        pos,
                        &mut d,
                        &mut w,
                        &mut roulette,
                        scattered,
                        ph,
                        t,
                    );
                    match hit {
                        Some(()) => {
                            scattered = true;
                            continue;
                        }
                        None => break 'walk,
                    }
                }
                if outside {
                    self.exit(pos, d, w, scattered, ph, t);
                    break 'walk;
                }
                layer = next;
            }
            let Some(h) = t.pending.pop() else {
                return Ok(());
            };
            (pos, d, layer, w, scattered, roulette) =
                (h.pos, h.d, h.layer, h.w, h.scattered, h.roulette);
            (t.order, t.entry, t.excursion2, t.past_rim, t.level) =
                (h.order, h.entry, h.excursion2, h.past_rim, h.level);
        }
    }

    /// Light reaching the Lambertian backing at `pos`: the backing absorbs 1 − Rb (tallied
    /// as transmitted) and sends the rest back up with a cosine-weighted direction, which
    /// re-enters the bottom layer by the Fresnel roulette (or falls back onto the backing).
    /// Returns `Some` with `d` pointing up inside the bottom layer, or `None` once absorbed.
    #[allow(clippy::too_many_arguments)]
    fn backing_bounce(
        &self,
        rng: &mut Stream,
        pos: Vec3,
        d: &mut Vec3,
        w: &mut f64,
        roulette: &mut bool,
        mut scattered: bool,
        ph: &mut Photon,
        t: &mut Tally,
    ) -> Option<()> {
        let rb = self.backing;
        for _ in 0..MAX_BACKING_BOUNCES {
            if *roulette {
                if rng.uniform() >= rb {
                    self.exit(pos, *d, *w, scattered, ph, t);
                    return None;
                }
            } else {
                self.exit(pos, *d, *w * (1.0 - rb), scattered, ph, t);
                *w *= rb;
                if *w < WEIGHT_THRESHOLD {
                    *roulette = true;
                }
            }
            scattered = true;
            if let Some(up) = self.reflect_off_backing(rng) {
                *d = up;
                return Some(());
            }
        }
        // a photon that keeps falling back (a near-white backing under total reflection)
        self.exit(pos, *d, *w, true, ph, t);
        None
    }

    /// A Lambertian reflection off the backing: a cosine-weighted direction up, refracted
    /// into the bottom layer, or `None` when the Fresnel roulette sends it back down onto
    /// the backing.
    fn reflect_off_backing(&self, rng: &mut Stream) -> Option<Vec3> {
        let eta = self.layers[self.layers.len() - 1].eta;
        lambertian_up_into(rng, self.cfg.n_below, eta)
    }

    /// Light reaching the backing at `pos` with backing orders: its arrival inside the window
    /// is the transmitted tally of the current order; it is always reflected (the factor R_b
    /// is the polynomial's), continuing to the next order by the survival roulette, and
    /// re-enters the bottom layer by the Fresnel roulette or falls back onto the backing.
    /// Returns `Some` with `d` pointing up inside the bottom layer, or `None` once ended.
    fn backing_orders_bounce(
        &self,
        rng: &mut Stream,
        pos: Vec3,
        d: &mut Vec3,
        w: &mut f64,
        ph: &mut Photon,
        t: &mut Tally,
    ) -> Option<()> {
        let (Some(orders), Some(win)) = (&self.orders, &self.cfg.window) else {
            return None;
        };
        for _ in 0..MAX_BACKING_BOUNCES {
            self.exit_window(win, pos, d.z, *w, false, ph, t);
            if t.order >= orders.max_order {
                t.truncated += *w;
                return None;
            }
            if orders.survival < 1.0 {
                if rng.uniform() >= orders.survival {
                    return None;
                }
                *w /= orders.survival;
            }
            t.order += 1;
            if let Some(up) = self.reflect_off_backing(rng) {
                *d = up;
                return Some(());
            }
        }
        t.truncated += *w;
        None
    }

    fn finish(&self, t: &Tally) -> SlabResult {
        let n = self.cfg.n_photons as f64;
        let mut values = [0.0; N_TALLIES];
        let mut stderr = [0.0; N_TALLIES];
        for k in 0..N_TALLIES {
            let mean = t.sum[k] / n;
            values[k] = mean;
            stderr[k] = if n > 1.0 {
                ((t.sumsq[k] / n - mean * mean).max(0.0) / (n - 1.0)).sqrt()
            } else {
                0.0
            };
        }
        let per_area = |v: &[f64]| -> Vec<f64> {
            let Some((bins, rmax)) = self.cfg.radial else {
                return vec![];
            };
            let dr = rmax / bins as f64;
            v.iter()
                .enumerate()
                .map(|(i, x)| x / n / (PI * dr * dr * ((i + 1) * (i + 1) - i * i) as f64))
                .collect()
        };
        let split = |v: [f64; N_TALLIES]| -> ([f64; 7], [f64; 6]) {
            let mut a = [0.0; 7];
            let mut b = [0.0; 6];
            a.copy_from_slice(&v[..N_SCALARS]);
            b.copy_from_slice(&v[N_SCALARS..]);
            (a, b)
        };
        let (values, window) = split(values);
        let (stderr, window_stderr) = split(stderr);
        SlabResult {
            values,
            stderr,
            window,
            window_stderr,
            absorbed_per_layer: t.absorbed.iter().map(|a| a / n).collect(),
            photons: self.cfg.n_photons,
            radial_reflectance: per_area(&t.radial_r),
            radial_transmittance: per_area(&t.radial_t),
            angular_reflectance: t.angle_r.iter().map(|x| x / n).collect(),
            angular_transmittance: t.angle_t.iter().map(|x| x / n).collect(),
            order_sums: Vec::new(),
            batch_photons: Vec::new(),
            truncated: t.truncated / n,
            lanes: false,
        }
    }
}

#[path = "slab_lanes.rs"]
mod lanes;

#[cfg(test)]
#[path = "slab_tests.rs"]
mod tests;
