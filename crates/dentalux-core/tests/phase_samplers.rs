//! Eq. 9 is implemented twice: phase.rs samples every phase function, and the slab
//! simulator keeps its own Henyey–Greenstein sampler (slab.rs `HgSampler`, the constants of
//! one g precomputed: a measured speed-up). They must draw the same distribution. The slab
//! simulator uses its sampler for a `HenyeyGreenstein` medium and phase.rs for a one-lobe
//! `MultiLobe` of the same g, so two runs of a thin, index-matched, non-absorbing slab (most
//! photons scatter a few times, every photon leaves it) differ only in who samples cos θ.
//! Their exit-angle histograms are compared by a two-sample χ² test, its threshold the
//! χ² quantile at p = 1e-6 for the number of bins (the statistic is in units of the counts'
//! own Poisson noise, so the tolerance follows from the sample size), and the diffuse
//! reflectances by their standard errors. A g off by 0.05 must fail the same test.

use dentalux_core::control::Control;
use dentalux_core::integrators::slab::{
    simulate, Estimator, Incidence, SlabConfig, SlabLayer, SlabResult,
};
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;

const PHOTONS: u64 = 1_000_000;
const BINS: usize = 18;

/// A 1 mm slab, μs = 0.8/mm, no absorption, n = 1 everywhere, lit by a normal beam.
fn run(phase: PhaseFunction, seed: u64) -> SlabResult {
    let cfg = SlabConfig {
        layers: vec![SlabLayer {
            medium: Medium::new("slab.", 0.0, 0.8, 1.0, phase).unwrap(),
            thickness: 1.0,
        }],
        n_above: 1.0,
        n_below: 1.0,
        incidence: Incidence::Normal,
        estimator: Estimator::Analog,
        n_photons: PHOTONS,
        seed,
        band: 0,
        radial: None,
        angular_bins: Some(BINS),
        window: None,
        backing_orders: None,
    };
    simulate(&cfg, &Control::new()).unwrap()
}

/// Photon counts per exit-angle bin, reflected then transmitted (analog: weight 1 each).
fn counts(r: &SlabResult) -> Vec<f64> {
    let n = r.photons as f64;
    (r.angular_reflectance.iter().chain(&r.angular_transmittance))
        .map(|f| (f * n).round())
        .collect()
}

/// Two-sample χ² of equal-sized samples and its degrees of freedom (bins with counts − 1).
fn chi2(a: &[f64], b: &[f64]) -> (f64, usize) {
    let mut x2 = 0.0;
    let mut bins = 0;
    for (x, y) in a.iter().zip(b) {
        if x + y > 0.0 {
            x2 += (x - y).powi(2) / (x + y);
            bins += 1;
        }
    }
    (x2, bins - 1)
}

/// The χ² quantile at p = 1e-6 (z = 4.75), Wilson–Hilferty.
fn chi2_threshold(df: usize) -> f64 {
    let k = df as f64;
    let h = 2.0 / (9.0 * k);
    k * (1.0 - h + 4.75 * h.sqrt()).powi(3)
}

/// Whether two runs' histograms and diffuse reflectances agree.
fn agree(a: &SlabResult, b: &SlabResult) -> (bool, String) {
    let (x2, df) = chi2(&counts(a), &counts(b));
    let limit = chi2_threshold(df);
    let key = "diffuse_reflectance";
    let i = 1; // SCALAR_KEYS[1]
    let (ra, rb) = (a.get(key).unwrap(), b.get(key).unwrap());
    let se = (a.stderr[i].powi(2) + b.stderr[i].powi(2)).sqrt();
    let ok = x2 < limit && (ra - rb).abs() < 5.0 * se;
    (
        ok,
        format!("chi2 {x2:.1} (limit {limit:.1}, df {df}); Rd {ra:.5} vs {rb:.5} (se {se:.5})"),
    )
}

#[test]
fn slab_hg_sampler_draws_the_phase_functions_distribution() {
    for (j, g) in [0.9, 0.3, -0.5].into_iter().enumerate() {
        let seed = 10 * j as u64;
        let slab_sampler = run(PhaseFunction::HenyeyGreenstein { g }, seed + 1);
        let phase_rs = run(PhaseFunction::multi_lobe(&[(1.0, g)]).unwrap(), seed + 2);
        let (ok, why) = agree(&slab_sampler, &phase_rs);
        assert!(ok, "g = {g}: {why}");
        // the test has the power to see a g off by 0.05
        let off = run(
            PhaseFunction::multi_lobe(&[(1.0, g - 0.05)]).unwrap(),
            seed + 3,
        );
        let (ok, why) = agree(&slab_sampler, &off);
        assert!(!ok, "g = {g} vs {}: {why}", g - 0.05);
    }
}
