//! The lanes walk against the scalar walk, a closed form, and its own portable build.

#![allow(clippy::needless_range_loop)]

use super::super::tests::one_layer;
use super::super::{
    simulate_with, SlabLayer, SlabResult, ABS, N_SCALARS, SCALAR_KEYS, TOT_R, TOT_T,
};
use super::*;
use crate::medium::Medium;

fn layer(mua: f64, mus: f64, phase: PhaseFunction, n: f64, d: f64) -> SlabLayer {
    SlabLayer {
        medium: Medium::new("", mua, mus, n, phase).unwrap(),
        thickness: d,
    }
}

fn weighted(mut cfg: SlabConfig) -> SlabConfig {
    cfg.estimator = Estimator::Weighted;
    cfg
}

/// A three-layer stack with every phase function the lanes take, a clear layer and
/// index steps, lit diffusely.
fn mixed_stack(photons: u64) -> SlabConfig {
    let mut cfg = weighted(one_layer(0.3, 15.0, 0.8, 1.62, 0.4, photons));
    cfg.layers
        .push(layer(0.0, 0.0, PhaseFunction::Isotropic, 1.45, 0.1));
    cfg.layers.push(layer(
        0.05,
        25.0,
        PhaseFunction::HgIsotropic { g: 0.9, fd: 0.3 },
        1.54,
        0.8,
    ));
    cfg.n_below = 1.33;
    cfg.incidence = Incidence::Diffuse;
    cfg
}

#[test]
fn lanes_take_only_what_they_can_walk() {
    let cfg = weighted(one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 10));
    assert!(Plan::new(&cfg).is_some());
    assert!(Plan::new(&mixed_stack(10)).is_some());
    let mut analog = cfg.clone();
    analog.estimator = Estimator::Analog;
    assert!(Plan::new(&analog).is_none());
    let mut radial = cfg.clone();
    radial.radial = Some((10, 1.0));
    assert!(Plan::new(&radial).is_none());
    let mut angular = cfg.clone();
    angular.angular_bins = Some(9);
    assert!(Plan::new(&angular).is_none());
}

/// One batch of 3000 photons of `cfg` (stream 5, 2, 7), walked by `run`.
fn one_batch(cfg: &SlabConfig, run: impl FnOnce(Batch<'_>) -> Result<()>) -> Tally {
    let plan = Plan::new(cfg).unwrap();
    let control = Control::new();
    let mut tally = Tally::new(cfg);
    run(Batch {
        plan: &plan,
        rng: &mut Stream::new(5, 2, 7),
        count: 3000,
        tally: &mut tally,
        control: &control,
    })
    .unwrap();
    tally
}

#[test]
fn every_build_gives_the_same_bits() {
    let cfg = mixed_stack(3000);
    let mut archs = vec![pulp::Arch::Scalar, pulp::Arch::new()];
    #[cfg(target_arch = "x86_64")]
    archs.extend(pulp::x86::V3::try_new().map(pulp::Arch::V3));
    let tallies: Vec<Tally> = archs
        .into_iter()
        .map(|arch| one_batch(&cfg, |batch| arch.dispatch(batch)))
        .collect();
    assert!(tallies[0].sum[TOT_R] > 0.0);
    for t in &tallies[1..] {
        assert_eq!(t.sum, tallies[0].sum);
        assert_eq!(t.sumsq, tallies[0].sumsq);
        assert_eq!(t.absorbed, tallies[0].absorbed);
    }
}

#[test]
fn an_index_matched_stack_skips_fresnel_with_the_same_bits() {
    // MCML's classic slab and a two-layer stack of index 1 in air, lit normally and
    // diffusely: the walk without the Fresnel terms tallies what the general walk does
    let mut two = weighted(one_layer(0.5, 20.0, 0.9, 1.0, 0.3, 3000));
    two.layers
        .push(layer(0.1, 5.0, PhaseFunction::Isotropic, 1.0, 0.5));
    let mut diffuse = two.clone();
    diffuse.incidence = Incidence::Diffuse;
    for cfg in [
        weighted(one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 3000)),
        two,
        diffuse,
    ] {
        assert!(Plan::new(&cfg).unwrap().matched);
        let fast = one_batch(&cfg, walk::<true>);
        let general = one_batch(&cfg, walk::<false>);
        assert!(fast.sum[TOT_R] > 0.0 && fast.sum[TOT_T] > 0.0);
        assert_eq!(fast.sum, general.sum);
        assert_eq!(fast.sumsq, general.sumsq);
        assert_eq!(fast.absorbed, general.absorbed);
    }
    // an index step anywhere, the media outside included, takes the general walk
    let mut below = weighted(one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 3000));
    below.n_below = 1.33;
    for cfg in [
        mixed_stack(10),
        below,
        weighted(one_layer(0.04, 26.0, 0.9, 1.54, 2.0, 10)),
    ] {
        assert!(!Plan::new(&cfg).unwrap().matched);
    }
}

#[test]
fn energy_adds_up_and_the_batch_count_is_exact() {
    for n in [1, 15, 16, 17, 1000] {
        let cfg = mixed_stack(n);
        let r = simulate_with(&cfg, &Control::new(), true).unwrap();
        let sum = r.values[TOT_R] + r.values[TOT_T] + r.values[ABS];
        assert!((sum - 1.0).abs() < 1e-12, "{n} photons: {sum}");
        let per_layer: f64 = r.absorbed_per_layer.iter().sum();
        assert!((per_layer - r.values[ABS]).abs() < 1e-12);
    }
}

/// Every scalar of the lanes walk within 4 s.e. of the scalar walk's, and each layer's
/// absorption within 4 times a bound on its s.e. (√(E[A²]/n) of the total absorption A).
fn agree(cfg: &SlabConfig) {
    let c = Control::new();
    let a = simulate_with(cfg, &c, true).unwrap();
    let b = simulate_with(cfg, &c, false).unwrap();
    for k in 0..N_SCALARS {
        let se = a.stderr[k].hypot(b.stderr[k]);
        let z = (a.values[k] - b.values[k]) / se.max(1e-300);
        assert!(
            z.abs() < 4.0 || (a.values[k] - b.values[k]).abs() < 1e-12,
            "{}: lanes {} ± {} vs scalar {} ± {} (z {z:.1})",
            SCALAR_KEYS[k],
            a.values[k],
            a.stderr[k],
            b.values[k],
            b.stderr[k]
        );
    }
    let n = cfg.n_photons as f64;
    let bound = |r: &SlabResult| (r.stderr[ABS].powi(2) + r.values[ABS].powi(2) / n).sqrt();
    for (j, (x, y)) in a
        .absorbed_per_layer
        .iter()
        .zip(&b.absorbed_per_layer)
        .enumerate()
    {
        assert!(
            (x - y).abs() < 4.0 * bound(&a).hypot(bound(&b)),
            "layer {j}: {x} vs {y}"
        );
    }
}

#[test]
fn lanes_agree_with_the_scalar_walk() {
    // MCML's classic slab, a dentin-like thick slab, the mixed stack, oblique light
    agree(&weighted(one_layer(1.0, 9.0, 0.75, 1.0, 0.2, 400_000)));
    agree(&weighted(one_layer(0.04, 26.0, 0.9, 1.54, 2.0, 40_000)));
    agree(&mixed_stack(100_000));
    let mut oblique = weighted(one_layer(0.5, 5.0, -0.3, 1.4, 0.3, 200_000));
    oblique.incidence = Incidence::Angle(1.1);
    oblique.n_above = 1.2;
    agree(&oblique);
}

#[test]
fn absorbing_slab_matches_its_closed_form() {
    // no scattering: R and T of a slab between equal media by every order of internal
    // reflection, R = ρ + (1 − ρ)² ρ τ² / (1 − ρ² τ²), T = (1 − ρ)² τ / (1 − ρ² τ²),
    // τ = exp(−μa d), ρ the normal-incidence Fresnel reflectance
    let (mua, n, d) = (1.3, 1.5, 0.5);
    let cfg = weighted(one_layer(mua, 0.0, 0.0, n, d, 200_000));
    let r = simulate_with(&cfg, &Control::new(), true).unwrap();
    let rho = ((n - 1.0) / (n + 1.0)).powi(2);
    let tau = (-mua * d).exp();
    let den = 1.0 - rho * rho * tau * tau;
    let want_r = rho + (1.0 - rho).powi(2) * rho * tau * tau / den;
    let want_t = (1.0 - rho).powi(2) * tau / den;
    for (k, want) in [(TOT_R, want_r), (TOT_T, want_t)] {
        let z = (r.values[k] - want) / r.stderr[k];
        assert!(
            z.abs() < 4.0,
            "{}: {} ± {} vs {want}",
            SCALAR_KEYS[k],
            r.values[k],
            r.stderr[k]
        );
    }
}

#[test]
fn cancellation_stops_the_lanes() {
    let cfg = weighted(one_layer(0.01, 100.0, 0.9, 1.5, 10.0, 10_000_000));
    let c = Control::new();
    c.cancel();
    assert_eq!(
        simulate_with(&cfg, &c, true).unwrap_err(),
        crate::error::Error::Cancelled
    );
}

#[test]
fn f32_helpers_match_their_references() {
    for i in 0..=1000 {
        let u = i as f32 / 1000.0;
        let x = (u as f64 * std::f64::consts::PI).cos();
        assert!((f64::from(cos_pi(u)) - x).abs() < 3e-7, "cos_pi({u})");
        if u > 0.0 {
            assert!(
                (f64::from(ln(u)) - (u as f64).ln()).abs() < 3e-7 * (1.0 + (u as f64).ln().abs())
            );
        }
        for g in [-0.7f32, 0.0, 1e-5, 0.5, 0.95] {
            // at g = 0 eq. 9's limit 2ξ − 1 (the scalar walk's isotropic draw is 1 − 2ξ)
            let want = if g == 0.0 {
                2.0 * f64::from(u) - 1.0
            } else {
                crate::phase::sample_hg_cos(f64::from(g), f64::from(u))
            };
            assert!(
                (f64::from(hg_cos(g, u)) - want).abs() < 1e-4,
                "hg({g}, {u})"
            );
        }
        for (ni, nt) in [(1.0, 1.54), (1.54, 1.0), (1.4, 1.4)] {
            let (r, ct) = fresnel(u, (ni / nt) as f32);
            let (r64, ct64) = crate::fresnel::reflectance_and_cos_t(f64::from(u), ni, nt);
            assert!((f64::from(r) - r64).abs() < 1e-5 && (f64::from(ct) - ct64).abs() < 1e-5);
        }
    }
}
