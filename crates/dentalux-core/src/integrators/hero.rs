//! Spectral photon tracing with a hero band (hero-wavelength sampling, Wilkie, Nawaz, Droske,
//! Weidlich & Hanika, EGSR 2014, applied to the photon pass): each photon's walk is drawn in
//! the scene of one band, its hero, picked uniformly from the B bands of the render, and every
//! photon it stores carries a power for each band b,
//!
//!   ΔΦ_b = ΔΦ_b^analog · p_b(walk) / ((1/B) Σ_j p_j(walk)),
//!
//! the balance heuristic over the B ways (one per hero) the same walk could have been drawn.
//! ΔΦ_b^analog = W_b / (P_b(light) N) is what band b's own analog pass would give the photon
//! (W_b its emission weight), and p_j the walk's density when band j draws it: the light
//! pick, every free flight (σt e^{−σt s}, or e^{−σt t} to a boundary), every survival of the
//! albedo or reflectance roulette, every phase-function turn (eqs. 2–4, 7–10) and every
//! Fresnel choice. The geometric factors every band shares cancel in the ratio, so only the
//! band-dependent ones are tracked, as log ratios to the hero's. The weight is at most B, so
//! no band's photon power explodes, and a band that cannot draw a walk (a refraction its
//! index would bend elsewhere, σt = 0 where the hero collided) gets weight 0 for it; the
//! walks that band draws as hero then carry its light there. Each band stays unbiased: the
//! B weights of a walk sum to one (balance), per band.
//!
//! All bands' maps then hold photons at the same places, so their density estimates share
//! their noise: it shows as grain in lightness instead of coloured blotches.

use super::ledger::Ledger;
use crate::scene::Scene;

/// The band-dependent part of one photon walk's density, per band, relative to the hero.
#[derive(Debug, Clone)]
pub struct HeroWalk {
    /// ln p_j − ln p_hero of the walk so far (0 for the hero, −∞ where band j cannot draw it).
    log_ratio: Vec<f64>,
    /// ΔΦ_j^analog: band j's analog photon power.
    analog: Vec<f64>,
    /// Scratch: the weighted powers of the last [`HeroWalk::powers`].
    powers: Vec<f64>,
    /// Scratch: the log ratios kept across [`HeroWalk::book_with`].
    saved: Vec<f64>,
}

/// ln x − ln y, −∞ when x is 0 (band j cannot do what the hero did); as a difference of
/// logarithms, so a subnormal y cannot overflow x / y.
#[inline]
fn log_ratio(x: f64, y: f64) -> f64 {
    if x > 0.0 {
        x.ln() - y.ln()
    } else {
        f64::NEG_INFINITY
    }
}

impl HeroWalk {
    /// A walk state for `bands` bands.
    pub fn new(bands: usize) -> Self {
        Self {
            log_ratio: vec![0.0; bands],
            analog: vec![0.0; bands],
            powers: vec![0.0; bands],
            saved: vec![0.0; bands],
        }
    }

    /// Start a photon from light `light`, picked by the hero with probability `p_hero`;
    /// `weight(j)` is band j's emission weight for the same emitted ray and `n` the photons
    /// of the pass.
    pub fn start(
        &mut self,
        scenes: &[Scene],
        light: usize,
        p_hero: f64,
        n: u64,
        weight: impl Fn(usize) -> f64,
    ) {
        for (j, s) in scenes.iter().enumerate() {
            let p = s.light_probability(light);
            self.log_ratio[j] = log_ratio(p, p_hero);
            self.analog[j] = if p > 0.0 {
                weight(j) / (p * n as f64)
            } else {
                0.0
            };
        }
    }

    /// Multiply band j's density by `f(j)` where the hero's is multiplied by `hero` (> 0).
    #[inline]
    pub fn scale(&mut self, hero: f64, f: impl Fn(usize) -> f64) {
        for (j, l) in self.log_ratio.iter_mut().enumerate() {
            *l += log_ratio(f(j), hero);
        }
    }

    /// Multiply band j's density by e^{ln_f(j)} where the hero's is multiplied by
    /// e^{hero} (for factors such as e^{−σt s} that may underflow).
    #[inline]
    pub fn scale_ln(&mut self, hero: f64, ln_f: impl Fn(usize) -> f64) {
        for (j, l) in self.log_ratio.iter_mut().enumerate() {
            *l += ln_f(j) - hero;
        }
    }

    /// Every band's power becomes 1/`m` of it (the walk is split into `m` walks).
    pub fn divide_power(&mut self, m: u32) {
        for a in &mut self.analog {
            *a /= m as f64;
        }
    }

    /// Band j cannot draw the walk from here on where `impossible(j)`.
    #[inline]
    pub fn forbid(&mut self, impossible: impl Fn(usize) -> bool) {
        for (j, l) in self.log_ratio.iter_mut().enumerate() {
            if impossible(j) {
                *l = f64::NEG_INFINITY;
            }
        }
    }

    /// Each band's power of the walk's current event: ΔΦ_b^analog · p_b / mean_j p_j.
    pub fn powers(&mut self) -> &[f64] {
        let top = self
            .log_ratio
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let sum: f64 = self.log_ratio.iter().map(|l| (l - top).exp()).sum();
        let b = self.log_ratio.len() as f64;
        for ((p, l), a) in self
            .powers
            .iter_mut()
            .zip(&self.log_ratio)
            .zip(&self.analog)
        {
            let w = (l - top).exp() * b / sum;
            *p = if w > 0.0 { a * w } else { 0.0 };
        }
        &self.powers
    }

    /// Add the current event's powers to one entry of each band's ledger.
    pub fn book(&mut self, ledgers: &mut [Ledger], entry: impl Fn(&mut Ledger) -> &mut f64) {
        self.powers();
        for (led, p) in ledgers.iter_mut().zip(&self.powers) {
            *entry(led) += p;
        }
    }

    /// Like [`HeroWalk::book`] for an event that band j reaches with density factor `f(j)`
    /// where the hero's is `hero` (an absorption: 1 − albedo), without changing the walk.
    pub fn book_with(
        &mut self,
        ledgers: &mut [Ledger],
        hero: f64,
        f: impl Fn(usize) -> f64,
        entry: impl Fn(&mut Ledger) -> &mut f64,
    ) {
        self.saved.copy_from_slice(&self.log_ratio);
        self.scale(hero, f);
        self.book(ledgers, entry);
        std::mem::swap(&mut self.saved, &mut self.log_ratio);
    }
}
