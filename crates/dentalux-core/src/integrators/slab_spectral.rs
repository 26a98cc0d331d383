//! Every band of a specimen reading from shared walks: the slab walk with a hero band.
//!
//! Each photon walks in the medium of one band, its hero, and is tallied for every band b
//! with the weight of the balance heuristic over the B ways (one per hero band) its walk
//! could have been drawn (hero-wavelength sampling, Wilkie, Nawaz, Droske, Weidlich &
//! Hanika, EGSR 2014; the renderer's photon pass does the same, [`super::hero`]):
//!
//!   W_b = f_b(walk) / ((1/B) Σ_k p_k(walk)),
//!
//! with heroes assigned in turn, so every band is hero to the same number of photons. The
//! walk flies with the hero's extinction σt and always scatters (no absorption in the walk),
//! so p_k, the density with which band k would draw it, is Π σt_k p_k(cos θ_i) at its
//! collisions times exp(−σt_k ℓ) over its path length in each layer, and f_b, what the walk
//! carries in band b, is the same with σs_b in place of σt_b (absorption as attenuation).
//! Both depend on a walk only through its collision count and path length per layer, and,
//! where the phase function differs between bands, the phase densities at its collisions,
//! so the walk keeps those and evaluates the B weights when it leaves. Refraction, Fresnel
//! choices, the backing's reflections and the lit spot are the same in every band (one
//! refractive index per layer for all bands: [`SpectralConfig::validate`] refuses
//! others). W_b ≤ B, so no band's weight explodes; a band whose extinction makes the walk
//! implausible gets a small weight for it and is carried by the walks it draws as hero.
//! The bands read from the same photons, so their noise is shared: a*, b* (differences
//! between bands) keep little of it.
//!
//! The window is tallied by backing order exactly as [`super::slab`] does with
//! [`BackingOrders`], so every backing is read from the same walk too. A walk whose every
//! band weight has fallen below [`ROULETTE_WEIGHT`] continues by Russian roulette.

use super::slab::{
    batch_size, count_event, distance_to_faces, entry_point, lambertian_up_into, BackingOrders,
    Incidence, SlabLayer, MAX_BACKING_BOUNCES, REPLICATES,
};
use crate::batches;
use crate::control::Control;
use crate::error::{check_range, Error, Result};
use crate::fresnel::reflectance_and_cos_t;
use crate::instrument::{self, Window};
use crate::math::{rotate_direction_scaled, Vec3};
use crate::phase::PhaseFunction;
use crate::rng::Stream;
use crate::sampling::sample_azimuth_scaled_bits;

/// Largest band weight below which a walk continues by Russian roulette (survival
/// probability its ratio to this, weights divided by it).
pub const ROULETTE_WEIGHT: f64 = 1e-3;
/// Collisions between two checks of the walk's band weights for the roulette.
const ROULETTE_EVERY: u32 = 64;
const N_KEYS: usize = instrument::WINDOW_KEYS.len();

/// A specimen read in every band by shared walks.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralConfig {
    /// Per band, the layers top to bottom (thicknesses and indices the same in every band).
    pub bands: Vec<Vec<SlabLayer>>,
    /// Refractive index above the slab.
    pub n_above: f64,
    /// Refractive index below the slab.
    pub n_below: f64,
    /// Illumination (normal or at an angle).
    pub incidence: Incidence,
    /// Photons in all (each band is hero to an equal share).
    pub n_photons: u64,
    /// Seed of the run.
    pub seed: u64,
    /// Stream key of the run.
    pub key: u64,
    /// The instrument's lit spot, window and specimen (its backing unused: see `orders`).
    pub window: Window,
    /// Backing orders tallied.
    pub orders: BackingOrders,
}

/// Sums of one replicate (a group of batches): `[band][order][key]` flattened.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralResult {
    /// Window tallies by band, backing order and key ([`instrument::WINDOW_KEYS`]), summed
    /// over each replicate's photons: `[replicate][band][order][key]` flattened.
    pub sums: Vec<f64>,
    /// Photons of each replicate.
    pub replicate_photons: Vec<u64>,
    /// Weight cut at the highest backing order, per band, per photon launched.
    pub truncated: Vec<f64>,
    /// Mean over photons of the largest band weight's share, Σ_b W_b² / (Σ_b W_b)², a
    /// diagnostic of how many bands a walk serves (1/B: all alike; 1: one band).
    pub concentration: f64,
}

impl SpectralConfig {
    /// Check every field; messages name the field and its allowed range.
    pub fn validate(&self) -> Result<()> {
        let Some(first) = self.bands.first() else {
            return Err(Error::InvalidInput(
                "bands: at least one band is needed".into(),
            ));
        };
        if first.is_empty() {
            return Err(Error::InvalidInput(
                "layers: at least one layer is needed".into(),
            ));
        }
        for (b, layers) in self.bands.iter().enumerate() {
            if layers.len() != first.len() {
                return Err(Error::InvalidInput(format!(
                    "bands[{b}]: {} layers, band 0 has {}",
                    layers.len(),
                    first.len()
                )));
            }
            for (i, (l, l0)) in layers.iter().zip(first).enumerate() {
                if l.thickness != l0.thickness || l.medium.eta != l0.medium.eta {
                    return Err(Error::InvalidInput(format!(
                        "bands[{b}].layers[{i}]: thickness and refractive index must be the \
                         same in every band of a shared walk"
                    )));
                }
                if !(l.thickness > 0.0 && l.thickness.is_finite()) {
                    return Err(Error::InvalidInput(format!(
                        "bands[{b}].layers[{i}].thickness = {} is out of range: allowed a \
                         finite number > 0 mm",
                        l.thickness
                    )));
                }
            }
        }
        check_range("n_above", self.n_above, 1.0, false, f64::INFINITY, true, "")?;
        check_range("n_below", self.n_below, 1.0, false, f64::INFINITY, true, "")?;
        if self.n_photons == 0 {
            return Err(Error::InvalidInput(
                "photons = 0 is out of range: allowed [1, 2^64)".into(),
            ));
        }
        if matches!(self.incidence, Incidence::Diffuse) {
            return Err(Error::InvalidInput(
                "incidence: a shared walk is lit by a beam (normal or at an angle)".into(),
            ));
        }
        self.window.validate()?;
        if self.orders.past_rim_only {
            return Err(Error::InvalidInput(
                "backing past_rim_only: the rim correction is read by per-band walks".into(),
            ));
        }
        self.orders.validate()
    }
}

/// Per-layer constants of every band.
struct LayerBands {
    /// ln σt and ln σs per band (−∞ where 0), σt per band.
    ln_sigma_t: Vec<f64>,
    ln_sigma_s: Vec<f64>,
    sigma_t: Vec<f64>,
    /// Phase function per band, and whether they differ between bands.
    phase: Vec<PhaseFunction>,
    phase_varies: bool,
    /// Where every band's phase is a plain Henyey-Greenstein lobe: per band (1 + g², 2g,
    /// ln((1 − g²)/4π)), so that ln p_g(c) = ln((1 − g²)/4π) − 1.5 ln(1 + g² − 2gc) costs one
    /// logarithm per band and collision, the constant added once per collision count.
    hg: Option<Vec<(f64, f64, f64)>>,
    eta: f64,
    z_top: f64,
    z_bot: f64,
}

/// One walk's band-dependent record: collisions and path length per layer, and the phase
/// log-densities per band where the phase differs.
struct WalkRecord {
    collisions: Vec<f64>,
    length: Vec<f64>,
    /// `[layer][band]`, used only for layers whose phase varies: Σ ln p_b(cos θ_i), or for
    /// plain HG layers Σ ln(1 + g_b² − 2 g_b cos θ_i) (see [`LayerBands::hg`]).
    ln_phase: Vec<Vec<f64>>,
    /// Scratch: per band ln p_k and ln f_k, then the weights.
    ln_p: Vec<f64>,
    weights: Vec<f64>,
}

struct Tracer<'a> {
    cfg: &'a SpectralConfig,
    layers: Vec<LayerBands>,
    n_bands: usize,
    inv_cone_fraction: f64,
    rim2: f64,
}

impl<'a> Tracer<'a> {
    fn new(cfg: &'a SpectralConfig) -> Self {
        let n_layers = cfg.bands[0].len();
        let mut z = 0.0;
        let layers = (0..n_layers)
            .map(|i| {
                let of = |f: &dyn Fn(&SlabLayer) -> f64| -> Vec<f64> {
                    cfg.bands.iter().map(|b| f(&b[i])).collect()
                };
                let sigma_t = of(&|l| l.medium.sigma_t());
                let ln = |v: Vec<f64>| v.into_iter().map(f64::ln).collect::<Vec<_>>();
                let phase: Vec<PhaseFunction> =
                    cfg.bands.iter().map(|b| b[i].medium.phase).collect();
                let phase_varies = phase.iter().any(|p| *p != phase[0]);
                let hg = phase
                    .iter()
                    .map(|p| match *p {
                        PhaseFunction::HenyeyGreenstein { g } => Some((
                            1.0 + g * g,
                            2.0 * g,
                            ((1.0 - g * g) / (4.0 * std::f64::consts::PI)).ln(),
                        )),
                        _ => None,
                    })
                    .collect::<Option<Vec<_>>>();
                let l0 = &cfg.bands[0][i];
                let out = LayerBands {
                    ln_sigma_t: ln(sigma_t.clone()),
                    ln_sigma_s: ln(of(&|l| l.medium.sigma_s)),
                    sigma_t,
                    phase,
                    phase_varies,
                    hg,
                    eta: l0.medium.eta,
                    z_top: z,
                    z_bot: z + l0.thickness,
                };
                z += l0.thickness;
                out
            })
            .collect();
        let w = cfg.window;
        Self {
            cfg,
            layers,
            n_bands: cfg.bands.len(),
            inv_cone_fraction: 1.0 / w.cone_fraction(),
            rim2: w.specimen_radius * w.specimen_radius,
        }
    }

    fn record(&self) -> WalkRecord {
        let n = self.layers.len();
        WalkRecord {
            collisions: vec![0.0; n],
            length: vec![0.0; n],
            ln_phase: self
                .layers
                .iter()
                .map(|l| {
                    if l.phase_varies {
                        vec![0.0; self.n_bands]
                    } else {
                        Vec::new()
                    }
                })
                .collect(),
            ln_p: vec![0.0; self.n_bands],
            weights: vec![0.0; self.n_bands],
        }
    }

    /// The walk's weight W_b in every band (module doc) into `rec.weights`; returns the
    /// largest.
    fn weights(&self, rec: &mut WalkRecord) -> f64 {
        let b_count = self.n_bands;
        let mut max_p = f64::NEG_INFINITY;
        for k in 0..b_count {
            let mut ln_p = 0.0;
            let mut ln_f = 0.0;
            for (l, lb) in self.layers.iter().enumerate() {
                let n = rec.collisions[l];
                let flight = -lb.sigma_t[k] * rec.length[l];
                let phase = match (&lb.hg, lb.phase_varies) {
                    (_, false) => 0.0,
                    (Some(hg), true) => n * hg[k].2 - 1.5 * rec.ln_phase[l][k],
                    (None, true) => rec.ln_phase[l][k],
                };
                if n > 0.0 {
                    ln_p += n * lb.ln_sigma_t[k] + flight + phase;
                    ln_f += n * lb.ln_sigma_s[k] + flight + phase;
                } else {
                    ln_p += flight;
                    ln_f += flight;
                }
            }
            rec.ln_p[k] = ln_p;
            rec.weights[k] = ln_f;
            if ln_p > max_p {
                max_p = ln_p;
            }
        }
        // (1/B) Σ_k p_k relative to the largest, then W_b = f_b / that
        let mix: f64 = rec.ln_p.iter().map(|p| (p - max_p).exp()).sum::<f64>() / b_count as f64;
        let ln_mix = max_p + mix.ln();
        let mut largest = 0.0f64;
        for w in rec.weights.iter_mut() {
            *w = (*w - ln_mix).exp();
            largest = largest.max(*w);
        }
        largest
    }

    /// Tally common weight `w` to window key `key` at backing order `order` for every band,
    /// with the band weights of the last [`Tracer::weights`].
    fn tally(&self, rec: &WalkRecord, sums: &mut [f64], key: usize, order: usize, w: f64) {
        let stride = (self.cfg.orders.max_order + 1) * N_KEYS;
        for (b, wb) in rec.weights.iter().enumerate() {
            sums[b * stride + order * N_KEYS + key] += w * wb;
        }
    }

    /// Tally an exit at `pos` (top if `top`) with |cos θ| `cos_exit` outside.
    #[allow(clippy::too_many_arguments)]
    fn exit(
        &self,
        rec: &mut WalkRecord,
        sums: &mut [f64],
        pos: Vec3,
        cos_exit: f64,
        top: bool,
        order: usize,
        w: f64,
    ) -> bool {
        let win = &self.cfg.window;
        let inside = win.in_window(pos.x * pos.x + pos.y * pos.y);
        if top || inside {
            self.weights(rec);
        }
        if !top {
            if inside {
                self.tally(rec, sums, instrument::VIEWED_T, order, w);
            }
        } else if inside {
            self.tally(rec, sums, instrument::VIEWED_R, order, w);
            if win.in_cone(cos_exit) {
                self.tally(
                    rec,
                    sums,
                    instrument::VIEWED_CONE,
                    order,
                    w * self.inv_cone_fraction,
                );
            }
        } else {
            self.tally(rec, sums, instrument::OUTSIDE_R, order, w);
        }
        inside
    }

    /// Trace one photon with hero band `hero`; returns its weight concentration.
    fn trace(
        &self,
        rng: &mut Stream,
        hero: usize,
        rec: &mut WalkRecord,
        sums: &mut [f64],
        truncated: &mut [f64],
        control: &Control,
    ) -> Result<f64> {
        let cfg = self.cfg;
        rec.collisions.iter_mut().for_each(|x| *x = 0.0);
        rec.length.iter_mut().for_each(|x| *x = 0.0);
        for v in rec.ln_phase.iter_mut() {
            v.iter_mut().for_each(|x| *x = 0.0);
        }
        let d_above = match cfg.incidence {
            Incidence::Angle(theta) => Vec3::new(theta.sin(), 0.0, theta.cos()),
            _ => Vec3::Z,
        };
        let mut pos = entry_point(&cfg.window, rng);
        let n_layers = self.layers.len() as isize;
        let eta0 = self.layers[0].eta;
        let (r0, cos_t0) = reflectance_and_cos_t(d_above.z, cfg.n_above, eta0);
        // the first-surface specular reflection, exact (the same in every band)
        if self.exit(rec, sums, pos, d_above.z, true, 0, r0) {
            self.tally(rec, sums, instrument::VIEWED_SPEC, 0, r0);
        }
        let mut w = 1.0 - r0;
        if w <= 0.0 {
            return Ok(1.0 / self.n_bands as f64);
        }
        let k = cfg.n_above / eta0;
        let mut d = Vec3::new(d_above.x * k, d_above.y * k, cos_t0);
        let mut layer: isize = 0;
        let mut order = 0usize;
        let mut events: u64 = 0;
        let mut since_check = 0u32;
        loop {
            let li = layer as usize;
            let lb = &self.layers[li];
            let sigma_t = lb.sigma_t[hero];
            let s = if sigma_t > 0.0 {
                -rng.uniform_open0().ln() / sigma_t
            } else {
                f64::INFINITY
            };
            let db = distance_to_faces(pos.z, d.z, lb.z_top, lb.z_bot);
            count_event(&mut events, control, || format!("layers[{li}]"))?;
            if s < db {
                pos += d * s;
                rec.length[li] += s;
                if pos.x * pos.x + pos.y * pos.y > self.rim2 {
                    self.weights(rec);
                    self.tally(rec, sums, instrument::RIM, order, w);
                    return Ok(self.concentration(rec));
                }
                rec.collisions[li] += 1.0;
                let phase = &lb.phase[hero];
                let u0 = rng.uniform();
                let u1 = if phase.uses_second_uniform() {
                    rng.uniform()
                } else {
                    0.0
                };
                let cos_theta = phase.sample_cos([u0, u1]);
                if lb.phase_varies {
                    match &lb.hg {
                        Some(hg) => {
                            for (acc, (a, b, _)) in rec.ln_phase[li].iter_mut().zip(hg) {
                                *acc += (a - b * cos_theta).ln();
                            }
                        }
                        None => {
                            for (acc, p) in rec.ln_phase[li].iter_mut().zip(&lb.phase) {
                                *acc += p.eval(cos_theta).ln();
                            }
                        }
                    }
                }
                let (c, sn, rho) = sample_azimuth_scaled_bits(|| rng.next_bits());
                d = rotate_direction_scaled(d, cos_theta, c, sn, rho);
                since_check += 1;
                if since_check == ROULETTE_EVERY {
                    since_check = 0;
                    let largest = self.weights(rec) * w;
                    if largest < ROULETTE_WEIGHT {
                        let q = largest / ROULETTE_WEIGHT;
                        if rng.uniform() >= q {
                            return Ok(self.concentration(rec));
                        }
                        w /= q;
                    }
                }
                continue;
            }
            let down = d.z > 0.0;
            pos += d * db;
            rec.length[li] += db;
            pos.z = if down { lb.z_bot } else { lb.z_top };
            if pos.x * pos.x + pos.y * pos.y > self.rim2 {
                self.weights(rec);
                self.tally(rec, sums, instrument::RIM, order, w);
                return Ok(self.concentration(rec));
            }
            let next = if down { layer + 1 } else { layer - 1 };
            let eta_t = if next < 0 {
                cfg.n_above
            } else if next >= n_layers {
                cfg.n_below
            } else {
                self.layers[next as usize].eta
            };
            let (r, cos_t) = reflectance_and_cos_t(d.z, lb.eta, eta_t);
            if r >= 1.0 || (r > 0.0 && rng.uniform() < r) {
                d.z = -d.z;
                continue;
            }
            let k = lb.eta / eta_t;
            d = Vec3::new(d.x * k, d.y * k, if down { cos_t } else { -cos_t });
            if next < 0 {
                self.exit(rec, sums, pos, d.z.abs(), true, order, w);
                return Ok(self.concentration(rec));
            }
            if next >= n_layers {
                // the backing: arrival tallied, always reflected (the polynomial's R_b)
                let mut reflected = false;
                for _ in 0..MAX_BACKING_BOUNCES {
                    self.exit(rec, sums, pos, d.z.abs(), false, order, w);
                    if order >= cfg.orders.max_order {
                        self.weights(rec);
                        for (t, wb) in truncated.iter_mut().zip(&rec.weights) {
                            *t += w * wb;
                        }
                        return Ok(self.concentration(rec));
                    }
                    let q = cfg.orders.survival;
                    if q < 1.0 {
                        if rng.uniform() >= q {
                            return Ok(self.concentration(rec));
                        }
                        w /= q;
                    }
                    order += 1;
                    let eta = self.layers[self.layers.len() - 1].eta;
                    if let Some(up) = lambertian_up_into(rng, cfg.n_below, eta) {
                        d = up;
                        reflected = true;
                        break;
                    }
                }
                if !reflected {
                    return Ok(self.concentration(rec));
                }
                continue;
            }
            layer = next;
        }
    }

    /// Σ_b W_b² / (Σ_b W_b)² of the walk's last weights.
    fn concentration(&self, rec: &WalkRecord) -> f64 {
        let s: f64 = rec.weights.iter().sum();
        let s2: f64 = rec.weights.iter().map(|w| w * w).sum();
        if s > 0.0 {
            s2 / (s * s)
        } else {
            1.0
        }
    }
}

/// Run the shared walks: batches in parallel, reduced in batch order into at most
/// [`REPLICATES`] replicates, so a seed gives the same numbers for any thread count. Photon
/// i of the run has hero band i mod B.
pub fn simulate_spectral(cfg: &SpectralConfig, control: &Control) -> Result<SpectralResult> {
    cfg.validate()?;
    let tracer = Tracer::new(cfg);
    let n_bands = cfg.bands.len();
    let width = n_bands * (cfg.orders.max_order + 1) * N_KEYS;
    let batch = batch_size(cfg.n_photons);
    let n_batches = cfg.n_photons.div_ceil(batch);
    type Batch = (Vec<f64>, Vec<f64>, f64);
    let batches: Result<Vec<Batch>> = batches::in_order(n_batches, |b| {
        control.check()?;
        let first = b * batch;
        let count = batch.min(cfg.n_photons - first);
        let mut rng = Stream::new(cfg.seed, cfg.key, b);
        let mut rec = tracer.record();
        let mut sums = vec![0.0; width];
        let mut truncated = vec![0.0; n_bands];
        let mut conc = 0.0;
        for i in 0..count {
            let hero = ((first + i) % n_bands as u64) as usize;
            conc += tracer.trace(&mut rng, hero, &mut rec, &mut sums, &mut truncated, control)?;
        }
        control.add_done(count);
        Ok((sums, truncated, conc))
    });
    let batches = batches?;
    let groups = (n_batches as usize).min(REPLICATES);
    let mut out = SpectralResult {
        sums: vec![0.0; groups * width],
        replicate_photons: vec![0; groups],
        truncated: vec![0.0; n_bands],
        concentration: 0.0,
    };
    for (b, (sums, truncated, conc)) in batches.iter().enumerate() {
        let g = b * groups / n_batches as usize;
        let slot = &mut out.sums[g * width..(g + 1) * width];
        slot.iter_mut().zip(sums).for_each(|(x, y)| *x += y);
        out.replicate_photons[g] += batch.min(cfg.n_photons - b as u64 * batch);
        out.truncated
            .iter_mut()
            .zip(truncated)
            .for_each(|(x, y)| *x += y);
        out.concentration += conc;
    }
    let n = cfg.n_photons as f64;
    out.truncated.iter_mut().for_each(|x| *x /= n);
    out.concentration /= n;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::Medium;

    fn layer(mua: f64, mus: f64, g: f64, n: f64, d: f64) -> SlabLayer {
        SlabLayer {
            medium: Medium::new("", mua, mus, n, PhaseFunction::HenyeyGreenstein { g }).unwrap(),
            thickness: d,
        }
    }

    fn config(bands: Vec<Vec<SlabLayer>>) -> SpectralConfig {
        SpectralConfig {
            bands,
            n_above: 1.0,
            n_below: 1.0,
            incidence: Incidence::Normal,
            n_photons: 4_000,
            seed: 3,
            key: 0,
            window: Window {
                illuminated_radius: 1.5,
                illuminated_inner_radius: 0.0,
                viewed_radius: 1.5,
                viewed_inner_radius: 0.0,
                specimen_radius: f64::INFINITY,
                backing: 0.0,
                cone: None,
            },
            orders: BackingOrders {
                max_order: 16,
                survival: 0.9,
                past_rim_only: false,
            },
        }
    }

    #[test]
    fn identical_bands_read_identically_with_weight_one() {
        // every band alike: each walk's weights are 1 in every band, so the sums are equal
        let stack = vec![
            layer(0.05, 10.0, 0.9, 1.6, 0.5),
            layer(0.1, 20.0, 0.93, 1.5, 1.0),
        ];
        let res = simulate_spectral(&config(vec![stack.clone(), stack]), &Control::new()).unwrap();
        let width = 17 * N_KEYS;
        for rep in res.sums.chunks(2 * width) {
            assert_eq!(rep[..width], rep[width..]);
        }
        assert!((res.concentration - 0.5).abs() < 1e-12);
    }

    #[test]
    fn bands_must_share_thickness_and_index() {
        let a = vec![layer(0.05, 10.0, 0.9, 1.6, 0.5)];
        let b = vec![layer(0.05, 12.0, 0.9, 1.5, 0.5)];
        let err = config(vec![a.clone(), b])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(err.contains("refractive index"), "{err}");
        let c = vec![layer(0.05, 12.0, 0.9, 1.6, 0.6)];
        assert!(config(vec![a, c]).validate().is_err());
    }
}
