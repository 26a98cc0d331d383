//! The weighted slab walk in lanes: [`LANES`] photons stepped together in f32, for the
//! laterally infinite slab with no lateral tally (no window, no radial or angular profile,
//! no backing orders). There only depth z and the direction cosine μz matter: after a
//! scattering μz' = μz cos θ + √((1 − μz²)(1 − cos²θ)) cos φ with φ uniform on [0, π]
//! (the z row of MCML's direction update), so a photon is (z, μz, weight, layer).
//!
//! Every lane runs the same straight-line arithmetic (both the scattering and the interface
//! outcome are computed and one is selected), which the compiler turns into vector code.
//! The logarithm and cos(πu) are polynomials written here, not libm, and no multiply-add is
//! fused, so the AVX-512, AVX2 and portable builds compute the same bits: a seed reads the
//! same on every machine. A lane whose photon ends takes the batch's next photon.
//!
//! f32 suffices for a photon's position and direction: uniforms carry 24 bits, so a free
//! path is cut at 16.6 mean free paths (e^-16.6 = 6e-8 of photons), and depths and cosines
//! carry 1e-7 relative error. Weights, the entry's Fresnel reflection and every tally are
//! f64 and computed as the scalar walk computes them, so energy adds up to 1 exactly.

// lanes are structure-of-arrays: one index runs over several arrays in every pass
#![allow(clippy::needless_range_loop)]

use super::{Estimator, Incidence, SlabConfig, WEIGHT_THRESHOLD};
use super::{Tally, ABS, DIFF_R, DIFF_T, MAX_EVENTS, SPEC, TOT_R, TOT_T, UNSC_T};
use crate::control::Control;
use crate::error::{Error, Result};
use crate::fresnel::reflectance_and_cos_t;
use crate::phase::PhaseFunction;
use crate::rng::Stream;

/// Photons stepped together: one AVX-512 register of f32.
pub const LANES: usize = 16;
/// Most layers the lanes walk takes (a thicker stack goes through the scalar walk).
const MAX_LAYERS: usize = 8;
/// Steps between polls for cancellation and the per-photon event limit.
const POLL_STEPS: u32 = 4096;

/// One layer's constants in f32, with its neighbours' indices for the interfaces.
#[derive(Clone, Copy, Default)]
struct LaneLayer {
    /// 1/σt [mm]; +∞ for a layer that does not interact.
    mfp: f32,
    albedo: f64,
    z_top: f32,
    z_bot: f32,
    /// This layer's index over the index below and above (the medium outside at the
    /// stack's faces).
    ratio_below: f32,
    ratio_above: f32,
    /// Whether the face below / above is the stack's own.
    last: bool,
    first: bool,
    /// Isotropic fraction of the phase function (1 for isotropic) and the HG part's g.
    fd: f32,
    g: f32,
}

/// What the lanes walk needs of a [`SlabConfig`], or `None` where it does not apply.
pub(super) struct Plan {
    layers: [LaneLayer; MAX_LAYERS],
    n_layers: usize,
    incidence: Incidence,
    n_above: f64,
    eta0: f64,
    /// Whether every face inside and around the stack joins equal indices: no Fresnel
    /// reflection anywhere, and a photon reaching a face crosses it unbent.
    matched: bool,
}

impl Plan {
    /// The plan for `cfg`, when its walk can be run in lanes: the weighted estimator, no
    /// lateral tally, at most [`MAX_LAYERS`] layers whose phase functions are HG, isotropic
    /// or HG mixed with isotropic.
    pub(super) fn new(cfg: &SlabConfig) -> Option<Self> {
        if cfg.estimator != Estimator::Weighted
            || cfg.window.is_some()
            || cfg.radial.is_some()
            || cfg.angular_bins.is_some()
            || cfg.backing_orders.is_some()
            || cfg.layers.len() > MAX_LAYERS
        {
            return None;
        }
        let mut layers = [LaneLayer::default(); MAX_LAYERS];
        let n = cfg.layers.len();
        let mut z = 0.0;
        for (i, l) in cfg.layers.iter().enumerate() {
            let (fd, g) = match l.medium.phase {
                PhaseFunction::Isotropic => (1.0, 0.0),
                PhaseFunction::HenyeyGreenstein { g } => (0.0, g),
                PhaseFunction::HgIsotropic { g, fd } => (fd, g),
                PhaseFunction::MultiLobe { .. } => return None,
            };
            let sigma_t = l.medium.sigma_t();
            layers[i] = LaneLayer {
                mfp: if sigma_t > 0.0 {
                    (1.0 / sigma_t) as f32
                } else {
                    f32::INFINITY
                },
                albedo: l.medium.albedo(),
                z_top: z as f32,
                z_bot: (z + l.thickness) as f32,
                ratio_below: (l.medium.eta
                    / if i + 1 < n {
                        cfg.layers[i + 1].medium.eta
                    } else {
                        cfg.n_below
                    }) as f32,
                ratio_above: (l.medium.eta
                    / if i > 0 {
                        cfg.layers[i - 1].medium.eta
                    } else {
                        cfg.n_above
                    }) as f32,
                last: i + 1 == n,
                first: i == 0,
                fd: fd as f32,
                g: g as f32,
            };
            z += l.thickness;
        }
        Some(Self {
            layers,
            n_layers: n,
            incidence: cfg.incidence,
            n_above: cfg.n_above,
            eta0: cfg.layers[0].medium.eta,
            matched: layers[..n]
                .iter()
                .all(|l| l.ratio_below == 1.0 && l.ratio_above == 1.0),
        })
    }
}

/// Walk `count` photons of one batch from `rng`, into `tally`'s scalars and per-layer
/// absorption, by the widest vector build this CPU runs (pulp's runtime dispatch: AVX-512,
/// AVX2 or portable), all of them giving the same bits.
pub(super) fn run_batch(
    plan: &Plan,
    rng: &mut Stream,
    count: u64,
    tally: &mut Tally,
    control: &Control,
) -> Result<()> {
    pulp::Arch::new().dispatch(Batch {
        plan,
        rng,
        count,
        tally,
        control,
    })
}

/// One batch's walk as a pulp operation, compiled once per instruction set.
pub(super) struct Batch<'a> {
    pub(super) plan: &'a Plan,
    pub(super) rng: &'a mut Stream,
    pub(super) count: u64,
    pub(super) tally: &'a mut Tally,
    pub(super) control: &'a Control,
}

impl pulp::WithSimd for Batch<'_> {
    type Output = Result<()>;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> Result<()> {
        // index-matched stacks skip the Fresnel terms (a tenth of a step's time), which
        // there give no reflection and the same cosine
        if self.plan.matched {
            walk::<true>(self)
        } else {
            walk::<false>(self)
        }
    }
}

type F = [f32; LANES];
type D = [f64; LANES];
type U = [u32; LANES];

/// xoshiro128++ per lane (Blackman & Vigna), seeded from the batch's stream.
struct LaneRng {
    s: [U; 4],
}

impl LaneRng {
    fn new(rng: &mut Stream) -> Self {
        let mut s = [[0u32; LANES]; 4];
        for i in 0..LANES {
            let (a, b) = (rng.next_bits(), rng.next_bits());
            s[0][i] = a as u32;
            s[1][i] = (a >> 32) as u32;
            s[2][i] = b as u32;
            // never the all-zero state
            s[3][i] = ((b >> 32) as u32) | 1;
        }
        Self { s }
    }

    /// 24-bit uniforms on [0, 1) (`open0`: on (0, 1]), one per lane.
    #[inline(always)]
    fn uniform(&mut self, open0: bool) -> F {
        let [s0, s1, s2, s3] = &mut self.s;
        let mut out = [0.0f32; LANES];
        let add = if open0 { 1 } else { 0 };
        for i in 0..LANES {
            let r = s0[i].wrapping_add(s3[i]).rotate_left(7).wrapping_add(s0[i]);
            let t = s1[i] << 9;
            s2[i] ^= s0[i];
            s3[i] ^= s1[i];
            s1[i] ^= s2[i];
            s0[i] ^= s3[i];
            s2[i] ^= t;
            s3[i] = s3[i].rotate_left(11);
            out[i] = (((r >> 8) + add) as i32) as f32 * (1.0 / 16_777_216.0);
        }
        out
    }
}

/// ln x for normal x > 0: x = m 2^e with m in [√½, √2), and with y = m − 1,
/// ln m = y − y²/2 + y³ q(y), q a degree-7 least-squares fit made for this walk (max error
/// 6e-8 over the range, the f32 rounding of ln m); no division.
#[inline(always)]
fn ln(x: f32) -> f32 {
    const Q: [f32; 8] = [
        -0.079_956_31,
        0.125_474_1,
        -0.129_409_26,
        0.142_204_03,
        -0.166_460_29,
        0.200_009_55,
        -0.250_002_25,
        0.333_333_3,
    ];
    let bits = x.to_bits();
    let e = ((bits >> 23) as i32) - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let big = m > std::f32::consts::SQRT_2;
    let m = if big { m * 0.5 } else { m };
    let e = if big { e + 1 } else { e };
    let y = m - 1.0;
    let mut q = Q[0];
    for c in &Q[1..] {
        q = q * y + c;
    }
    e as f32 * std::f32::consts::LN_2 + (y - y * y * 0.5 + y * y * y * q)
}

/// cos(πu) for u in [0, 1]: Taylor's series of cos a to a¹² on a = π min(u, 1 − u) ≤ π/2
/// (error below 1e-8), the sign by the reflection cos(π(1 − u)) = −cos(πu).
#[inline(always)]
fn cos_pi(u: f32) -> f32 {
    let hi = u > 0.5;
    let a = std::f32::consts::PI * if hi { 1.0 - u } else { u };
    let a2 = a * a;
    let c = 1.0
        - a2 * 0.5
            * (1.0
                - a2 * (1.0 / 12.0)
                    * (1.0
                        - a2 * (1.0 / 30.0)
                            * (1.0
                                - a2 * (1.0 / 56.0)
                                    * (1.0 - a2 * (1.0 / 90.0) * (1.0 - a2 * (1.0 / 132.0))))));
    if hi {
        -c
    } else {
        c
    }
}

/// Eq. 9 rearranged without cancellation at small g: with s = 2ξ − 1,
/// cos θ = (s + g(3 + s²)/2 + g²s + g³(s² − 1)/2) / (1 + gs)², exact at g = 0 (isotropic).
#[inline(always)]
fn hg_cos(g: f32, xi: f32) -> f32 {
    let s = 2.0 * xi - 1.0;
    let s2 = s * s;
    let d = 1.0 + g * s;
    let num = s + g * (0.5 * (3.0 + s2) + g * (s + g * (0.5 * (s2 - 1.0))));
    let c = num / (d * d);
    c.clamp(-1.0, 1.0)
}

/// Unpolarised Fresnel reflectance and the refracted cosine at incidence cosine `ci` ≥ 0
/// from a medium whose index is `k` times the other's (f32 twin of
/// [`crate::fresnel::reflectance_and_cos_t`]); rs² + rp² over one common denominator.
#[inline(always)]
fn fresnel(ci: f32, k: f32) -> (f32, f32) {
    // cos²θt = 1 − k² sin²θi, negative past the critical angle
    let cos2_t = 1.0 - k * k * (1.0 - ci * ci);
    let tir = cos2_t <= 0.0;
    let ct = if tir { 0.0 } else { cos2_t }.sqrt();
    // rs = (k ci − ct)/(k ci + ct), rp = (ci − k ct)/(ci + k ct)
    let (a, b) = (k * ci - ct, k * ci + ct);
    let (c, d) = (ci - k * ct, ci + k * ct);
    let r = if k == 1.0 {
        0.0
    } else if tir {
        1.0
    } else {
        0.5 * ((a * d) * (a * d) + (c * b) * (c * b)) / ((b * d) * (b * d))
    };
    (r, if k == 1.0 { ci } else { ct })
}

/// The lanes' photons: state, the constants of the layer each is in, and what each photon
/// has tallied so far (f64).
#[derive(Default)]
struct Lanes {
    z: F,
    uz: F,
    w: D,
    layer: U,
    /// 1.0 once scattered, 0.0 before (a float mask keeps every pass in f32 lanes).
    scattered: F,
    /// 1.0 once the weight fell below [`WEIGHT_THRESHOLD`]: absorption by roulette.
    roulette: F,
    /// 1.0 while the lane holds a photon.
    active: F,
    events: U,
    // the layer's constants, refreshed when the photon crosses into another
    mfp: F,
    albedo: D,
    /// The albedo in f32, for the roulette's comparisons (an f64 read would halve the
    /// vector width of the f32 pass).
    albedo32: F,
    z_top: F,
    z_bot: F,
    ratio_below: F,
    ratio_above: F,
    last: F,
    first: F,
    fd: F,
    g: F,
    // this photon's tallies so far (its exit is read off its state when it ends)
    spec: D,
    abs: D,
    /// Absorption per layer, summed over the lane's photons (no per-photon spread needed).
    abs_layer: [D; MAX_LAYERS],
    /// Per-lane sums and sums of squares of each photon's scalars.
    sum: [D; 7],
    sumsq: [D; 7],
}

/// What a photon starts with: the specular reflection it leaves at the entry, and its
/// weight and direction cosine inside the top layer.
#[inline(always)]
fn launch(plan: &Plan, cos_above: f64) -> (f64, f64, f32) {
    let (r0, ct) = reflectance_and_cos_t(cos_above, plan.n_above, plan.eta0);
    (r0, 1.0 - r0, ct as f32)
}

#[inline(always)]
fn walk<const MATCHED: bool>(batch: Batch<'_>) -> Result<()> {
    let Batch {
        plan,
        rng,
        count,
        tally,
        control,
    } = batch;
    let mut r = LaneRng::new(rng);
    let fixed = match plan.incidence {
        Incidence::Normal => Some(launch(plan, 1.0)),
        Incidence::Angle(theta) => Some(launch(plan, theta.cos())),
        Incidence::Diffuse => None,
    };
    // every lane in the top layer, idle, nothing tallied
    let mut s = Lanes::default();
    for i in 0..LANES {
        set_layer(&mut s, i, &plan.layers[0]);
    }
    // every lane starts "ended" with nothing tallied, so the first pass of `refill` launches
    let mut ended = [1.0f32; LANES];
    let mut launched: u64 = 0;
    let mut steps: u32 = 0;
    loop {
        launched = refill(plan, &mut s, &mut r, &mut ended, launched, count, fixed);
        if s.active.iter().all(|&a| a == 0.0) {
            break;
        }
        step::<MATCHED>(plan, &mut s, &mut r, &mut ended);
        steps += 1;
        if steps.is_multiple_of(POLL_STEPS) {
            control.check()?;
            if s.events.iter().any(|&e| u64::from(e) > MAX_EVENTS) {
                return Err(Error::InvalidInput(format!(
                    "a photon exceeded {MAX_EVENTS} interactions: the slab is too thick \
                     optically for Monte Carlo (layers' μt·d up to {:.3e})",
                    plan.layers[..plan.n_layers]
                        .iter()
                        .map(|l| f64::from(l.z_bot - l.z_top) / f64::from(l.mfp))
                        .fold(0.0, f64::max)
                )));
            }
        }
    }
    // lanes reduced in lane order: the same sums on every build
    for i in 0..LANES {
        for k in 0..7 {
            tally.sum[k] += s.sum[k][i];
            tally.sumsq[k] += s.sumsq[k][i];
        }
        if plan.n_layers == 1 {
            tally.absorbed[0] += s.sum[ABS][i];
        } else {
            for (j, a) in tally.absorbed.iter_mut().enumerate() {
                *a += s.abs_layer[j][i];
            }
        }
    }
    Ok(())
}

/// Close the photons of lanes that ended (their scalars into the sums) and start the
/// batch's next photons in them; a lane with none left goes idle. Returns photons launched.
#[inline(always)]
fn refill(
    plan: &Plan,
    s: &mut Lanes,
    r: &mut LaneRng,
    ended: &mut F,
    launched: u64,
    count: u64,
    fixed: Option<(f64, f64, f32)>,
) -> u64 {
    if ended.iter().all(|&e| e == 0.0) {
        return launched;
    }
    // close. A photon ends by leaving with its weight w (at the top face, z = 0: diffuse
    // reflection; at the bottom: diffuse or unscattered transmission) or absorbed by the
    // roulette with w = 0, so its exit is read off its state; TOT_R = SPEC + DIFF_R,
    // TOT_T = UNSC_T + DIFF_T (as the scalar walk tallies)
    for i in 0..LANES {
        let on = f64::from(ended[i] * s.active[i]);
        let w = s.w[i];
        let up = s.z[i] <= 0.0;
        let scattered = s.scattered[i] != 0.0;
        let diff_r = if up { w } else { 0.0 };
        let unsc_t = if !up && !scattered { w } else { 0.0 };
        let diff_t = if !up && scattered { w } else { 0.0 };
        let v = [
            s.spec[i],
            diff_r,
            s.spec[i] + diff_r,
            unsc_t,
            diff_t,
            unsc_t + diff_t,
            s.abs[i],
        ];
        for k in 0..7 {
            s.sum[k][i] += on * v[k];
            s.sumsq[k][i] += on * v[k] * v[k];
        }
    }
    debug_assert!([SPEC, DIFF_R, TOT_R, UNSC_T, DIFF_T, TOT_T, ABS] == [0, 1, 2, 3, 4, 5, 6]);
    // which lanes take a new photon: all that ended while enough are left, else the first
    let left = count - launched;
    let n_ended = ended.iter().filter(|&&e| e != 0.0).count() as u64;
    let mut take = [0.0f32; LANES];
    if n_ended <= left {
        take = *ended;
    } else {
        let mut k = 0;
        for i in 0..LANES {
            if ended[i] != 0.0 && k < left {
                take[i] = 1.0;
                k += 1;
            }
        }
    }
    let (mut r0, mut w0, mut uz0) = ([0.0f64; LANES], [0.0f64; LANES], [0.0f32; LANES]);
    match fixed {
        Some(f) => (r0, w0, uz0) = ([f.0; LANES], [f.1; LANES], [f.2; LANES]),
        None => {
            // a cosine-weighted direction from the upper hemisphere: cos θ = √u
            let u = r.uniform(false);
            for i in 0..LANES {
                (r0[i], w0[i], uz0[i]) = launch(plan, f64::from(u[i].sqrt()));
            }
        }
    }
    let l0 = plan.layers[0];
    // selects over every lane (a branch per lane would mispredict)
    for i in 0..LANES {
        let (t, e) = (take[i] != 0.0, ended[i] != 0.0);
        s.active[i] = if t {
            1.0
        } else if e {
            0.0
        } else {
            s.active[i]
        };
        s.z[i] = if e { 0.0 } else { s.z[i] };
        s.uz[i] = if e { uz0[i] } else { s.uz[i] };
        s.scattered[i] = if e { 0.0 } else { s.scattered[i] };
        s.roulette[i] = if e { 0.0 } else { s.roulette[i] };
        s.layer[i] = if e { 0 } else { s.layer[i] };
        s.events[i] = if e { 0 } else { s.events[i] };
    }
    for i in 0..LANES {
        let (t, e) = (take[i] != 0.0, ended[i] != 0.0);
        s.w[i] = if t {
            w0[i]
        } else if e {
            0.0
        } else {
            s.w[i]
        };
        s.spec[i] = if t {
            r0[i]
        } else if e {
            0.0
        } else {
            s.spec[i]
        };
        s.abs[i] = if e { 0.0 } else { s.abs[i] };
    }
    if plan.n_layers > 1 {
        for i in 0..LANES {
            if ended[i] != 0.0 {
                set_layer(s, i, &l0);
            }
        }
    }
    // a photon wholly reflected at the entry (grazing light) ends at once
    for i in 0..LANES {
        ended[i] = if take[i] != 0.0 && s.w[i] <= 0.0 {
            1.0
        } else {
            0.0
        };
    }
    launched + take.iter().filter(|&&t| t != 0.0).count() as u64
}

#[inline(always)]
fn set_layer(s: &mut Lanes, i: usize, l: &LaneLayer) {
    s.mfp[i] = l.mfp;
    s.albedo[i] = l.albedo;
    s.albedo32[i] = l.albedo as f32;
    s.z_top[i] = l.z_top;
    s.z_bot[i] = l.z_bot;
    s.ratio_below[i] = l.ratio_below;
    s.ratio_above[i] = l.ratio_above;
    s.last[i] = if l.last { 1.0 } else { 0.0 };
    s.first[i] = if l.first { 1.0 } else { 0.0 };
    s.fd[i] = l.fd;
    s.g[i] = l.g;
}

/// One event for every lane: a free flight that ends either in an interaction (weight
/// deposition, or absorption by roulette, then a new direction) or at the layer's face
/// (Fresnel reflection, or refraction into the next layer or out of the stack). Sets
/// `ended` for the lanes whose photon left or was absorbed. Each pass is one loop of
/// straight-line arithmetic over the lanes, which is what the vectoriser takes.
#[inline(always)]
fn step<const MATCHED: bool>(plan: &Plan, s: &mut Lanes, r: &mut LaneRng, ended: &mut F) {
    let u_path = r.uniform(true);
    // the second uniform is cos θ's at an interaction and the Fresnel roulette's at a face
    let u_cos = r.uniform(false);
    let u_phi = r.uniform(false);
    // the roulette's, then (rescaled) the phase function's isotropic-or-HG choice
    let u_pick = r.uniform(false);
    // where the flight ends, and the photon's new depth and direction (f32)
    let mut interacts = [false; LANES];
    let mut leaves = [false; LANES];
    let mut enters = [false; LANES];
    let mut killed = [false; LANES];
    let mut down = [false; LANES];
    // written to locals and copied back: a store into `s` inside the loop could alias (for
    // the vectoriser) the loads that select between two of its arrays
    let mut z_out = [0.0f32; LANES];
    let mut uz_out = [0.0f32; LANES];
    for i in 0..LANES {
        let (z, uz) = (s.z[i], s.uz[i]);
        // free flight (eq. 2); a layer that does not interact has mfp = ∞ and the product
        // is ∞ (or NaN at u = 1), which the comparison below sends to the face
        let path = -ln(u_path[i]) * s.mfp[i];
        let dn = uz > 0.0;
        // the flight stops short of the face it heads for: path |μz| < distance to it
        let (to_face, dz) = if dn {
            (s.z_bot[i] - z, uz)
        } else {
            (z - s.z_top[i], -uz)
        };
        let hit = path * dz < to_face;
        // under roulette the photon is absorbed with probability 1 − a; given survival
        // u_pick / a is uniform again, and picks isotropic scattering below fd
        let roulette = s.roulette[i] != 0.0;
        let albedo = s.albedo32[i];
        let below = if roulette { s.fd[i] * albedo } else { s.fd[i] };
        let cos_t = if u_pick[i] < below {
            2.0 * u_cos[i] - 1.0
        } else {
            hg_cos(s.g[i], u_cos[i])
        };
        let sin2 = (1.0 - uz * uz) * (1.0 - cos_t * cos_t);
        let uz_new = uz * cos_t + if sin2 > 0.0 { sin2 } else { 0.0 }.sqrt() * cos_pi(u_phi[i]);
        let uz_int = uz_new.clamp(-1.0, 1.0);
        // the face: Fresnel roulette between reflection and refraction
        let k = if dn {
            s.ratio_below[i]
        } else {
            s.ratio_above[i]
        };
        let (refl, ct) = if MATCHED { (0.0, dz) } else { fresnel(dz, k) };
        let reflects = u_cos[i] < refl;
        let outside = if dn { s.last[i] } else { s.first[i] } != 0.0;
        z_out[i] = if hit {
            z + uz * path
        } else if dn {
            s.z_bot[i]
        } else {
            s.z_top[i]
        };
        uz_out[i] = if hit {
            uz_int
        } else if reflects {
            -uz
        } else if dn {
            ct
        } else {
            -ct
        };
        let active = s.active[i] != 0.0;
        interacts[i] = hit && active;
        leaves[i] = !hit && !reflects && outside && active;
        enters[i] = !hit && !reflects && !outside && active;
        killed[i] = hit && active && roulette && u_pick[i] >= albedo;
        down[i] = dn;
    }
    s.z = z_out;
    s.uz = uz_out;
    // weights and tallies (f64): deposit w(1 − a), or all of w when the roulette absorbs
    let mut dep = [0.0f64; LANES];
    for i in 0..LANES {
        let w = s.w[i];
        let roulette = s.roulette[i] != 0.0;
        let d = if !interacts[i] {
            0.0
        } else if roulette {
            if killed[i] {
                w
            } else {
                0.0
            }
        } else {
            w * (1.0 - s.albedo[i])
        };
        let w_new = w - d;
        dep[i] = d;
        s.w[i] = w_new;
        s.abs[i] += d;
        s.roulette[i] = if interacts[i] && w_new < WEIGHT_THRESHOLD {
            1.0
        } else {
            s.roulette[i]
        };
        s.scattered[i] = if interacts[i] { 1.0 } else { s.scattered[i] };
        s.events[i] += u32::from(s.active[i] != 0.0);
        // (a lane the refill ended at its entry stays ended)
        ended[i] = if ended[i] != 0.0 || leaves[i] || killed[i] {
            1.0
        } else {
            0.0
        };
    }
    // (one layer's absorption is the photons' ABS, summed at the end)
    for (j, a) in s.abs_layer[..plan.n_layers]
        .iter_mut()
        .enumerate()
        .skip(usize::from(plan.n_layers == 1))
    {
        for i in 0..LANES {
            a[i] += if s.layer[i] == j as u32 { dep[i] } else { 0.0 };
        }
    }
    if plan.n_layers > 1 {
        for i in 0..LANES {
            if enters[i] {
                let next = if down[i] {
                    s.layer[i] + 1
                } else {
                    s.layer[i] - 1
                };
                s.layer[i] = next;
                set_layer(s, i, &plan.layers[next as usize]);
            }
        }
    }
}

#[cfg(test)]
#[path = "slab_lanes_tests.rs"]
mod tests;
