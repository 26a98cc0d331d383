//! The spectral photon pass (`integrators::hero`): photons walking in a hero band, every band's
//! power weighted by the balance heuristic. Each band must still get its own answer: closed
//! forms of the energy ledger per band (an infinite medium of band-dependent albedo and
//! anisotropy, a closed sphere of band-dependent reflectance), and `vpm` images whose means
//! agree with the band-by-band render within 4 standard errors (spread over seeds). And the
//! point of it: the bands' noise is shared, so the colour (a band ratio) is less noisy than
//! with correlated per-band passes.

use dentalux_core::control::Control;
use dentalux_core::geometry::shapes::Sphere;
use dentalux_core::geometry::Vec3;
use dentalux_core::integrators::photon_trace::{
    trace_emission_bands, Emission, PhotonMaps, StoreMode, Targets,
};
use dentalux_core::integrators::render::render_bands;
use dentalux_core::integrators::settings::{Integrator, Settings};
use dentalux_core::lights::Light;
use dentalux_core::medium::Medium;
use dentalux_core::scene::{Boundary, Geometry, Scene};
use dentalux_core::surface::Surface;
use std::f64::consts::PI;

mod common;
use common::{air, camera, medium, shape};

/// Mean and standard error over independent runs.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// `runs` spectral passes of `n` photons with seeds 1..=runs.
fn passes(scenes: &[Scene], n: u64, mode: StoreMode, runs: u64) -> Vec<Vec<PhotonMaps>> {
    (1..=runs)
        .map(|seed| {
            let emission = Emission {
                photons: n,
                ..Emission::default()
            };
            trace_emission_bands(
                scenes,
                &emission,
                mode,
                Targets::BOTH,
                0,
                seed,
                0,
                &Control::new(),
            )
            .unwrap()
        })
        .collect()
}

/// Stored power Φ a/(1 − a) per band in an infinite medium whose albedo a and anisotropy g
/// differ between the bands (`vpm-full` stores every scattering); everything is absorbed.
#[test]
fn infinite_medium_ledger_per_band() {
    let bands = [(0.9, 0.3), (0.8, 0.6), (0.95, 0.0)];
    let scene = |(a, g): (f64, f64)| vec![medium(1.0 - a, a, g, 1.0)];
    let first = common::point_in_infinite_medium(scene(bands[0]));
    let scenes: Vec<Scene> = (bands.iter())
        .map(|&b| {
            let m: Vec<Medium> = scene(b);
            first
                .with_band(m, first.surfaces.clone(), first.lights.clone())
                .unwrap()
        })
        .collect();
    let phi = 4.0 * PI * 2.0;
    let runs = passes(&scenes, 20_000, StoreMode::All, 10);
    for (b, &(a, _)) in bands.iter().enumerate() {
        let stored: Vec<f64> = runs.iter().map(|r| r[b].ledger.stored_volume[0]).collect();
        let absorbed: Vec<f64> = runs
            .iter()
            .map(|r| r[b].ledger.absorbed_medium[0])
            .collect();
        let (m, se) = mean_se(&stored);
        let expect = phi * a / (1.0 - a);
        assert!(
            (m - expect).abs() < 4.0 * se,
            "band {b}: stored {m} vs {expect} ± {se}"
        );
        assert!(se < 0.02 * expect, "band {b}: se {se}");
        let (m, se) = mean_se(&absorbed);
        assert!(
            (m - phi).abs() < 4.0 * se.max(1e-9 * phi),
            "band {b}: absorbed {m} ± {se}"
        );
        // one light: every band's emission weight is 1, so Φ_b is emitted exactly
        for r in &runs {
            assert!((r[b].ledger.emitted - phi).abs() < 1e-9 * phi);
            let map = r[b].volume[0].total_power();
            assert!((map - r[b].ledger.stored_volume[0]).abs() < 1e-4 * map);
        }
    }
    // the bands' maps hold the same photons
    let r = &runs[0];
    assert!(r.iter().all(|m| m.volume[0].len() == r[0].volume[0].len()));
}

/// A point light inside a closed sphere whose reflectance ρ differs per band: all but the
/// first (direct) hit are stored, Φ ρ/(1 − ρ) per band, and all power is absorbed.
#[test]
fn closed_sphere_ledger_per_band() {
    let rhos = [0.6, 0.3, 0.75];
    let wall = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 10.0,
        }),
        Boundary::Opaque { surface: 0 },
    );
    let light = Light::Point {
        position: Vec3::new(1.0, 2.0, 0.5),
        intensity: 1.0,
    };
    let lamb = |rho: f64| vec![Surface::Lambertian { reflectance: rho }];
    let first = Scene::new(
        camera(Vec3::new(0.0, -50.0, 0.0), Vec3::ZERO, 4, 4),
        vec![air()],
        lamb(rhos[0]),
        vec![wall],
        vec![light],
        0,
    )
    .unwrap();
    let scenes: Vec<Scene> = (rhos.iter())
        .map(|&rho| {
            first
                .with_band(vec![air()], lamb(rho), vec![light])
                .unwrap()
        })
        .collect();
    let phi = 4.0 * PI;
    let runs = passes(&scenes, 20_000, StoreMode::Paper, 10);
    for (b, &rho) in rhos.iter().enumerate() {
        let stored: Vec<f64> = runs.iter().map(|r| r[b].ledger.stored_surface).collect();
        let absorbed: Vec<f64> = runs.iter().map(|r| r[b].ledger.absorbed_surface).collect();
        let (m, se) = mean_se(&stored);
        let expect = phi * rho / (1.0 - rho);
        assert!(
            (m - expect).abs() < 4.0 * se,
            "band {b}: stored {m} vs {expect} ± {se}"
        );
        let (m, se) = mean_se(&absorbed);
        assert!(
            (m - phi).abs() < 4.0 * se.max(1e-9 * phi),
            "band {b}: absorbed {m} ± {se}"
        );
    }
}

/// Three bands of the disc scene whose disc differs a little between them (as a tooth's
/// coefficients do between neighbouring bands).
fn disc_bands() -> Vec<Scene> {
    let base = common::disc_scene(1.5, 16, 12);
    [(0.2, 3.0), (0.3, 3.3), (0.12, 2.7)]
        .iter()
        .map(|&(mua, mus)| {
            let media = vec![air(), medium(mua, mus, 0.6, 1.5)];
            base.with_band(media, base.surfaces.clone(), base.lights.clone())
                .unwrap()
        })
        .collect()
}

/// Per-band images of `runs` renders (seeds 1..=runs).
fn renders(scenes: &[Scene], spectral: bool, keys: &[u64], runs: u64) -> Vec<Vec<Vec<f32>>> {
    (1..=runs)
        .map(|seed| {
            let s = Settings {
                integrator: Integrator::Vpm,
                spp: 2,
                photons: 4_000,
                volume_photons: 12_000,
                k: 32,
                seed,
                spectral_photons: spectral,
                ..Settings::default()
            };
            let out = render_bands(scenes, &s, keys, &Control::new()).unwrap();
            out.into_iter().map(|(image, _)| image).collect()
        })
        .collect()
}

fn image_mean(image: &[f32]) -> f64 {
    image.iter().map(|&x| x as f64).sum::<f64>() / image.len() as f64
}

/// `vpm` with the spectral pass against band-by-band passes: every band's image mean agrees
/// within 4 standard errors; and the colour noise (the spread over seeds of each pixel's
/// ratio of band 1 to band 0, averaged over the pixels) is lower than with correlated
/// per-band passes (the same streams in every band), the best the per-band passes do.
#[test]
fn vpm_spectral_agrees_and_shares_noise() {
    let scenes = disc_bands();
    let runs = 12;
    let spectral = renders(&scenes, true, &[540, 560, 600], runs);
    let per_band = renders(&scenes, false, &[540, 560, 600], runs);
    for b in 0..3 {
        let (ms, ss) = mean_se(
            &spectral
                .iter()
                .map(|r| image_mean(&r[b]))
                .collect::<Vec<_>>(),
        );
        let (mp, sp) = mean_se(
            &per_band
                .iter()
                .map(|r| image_mean(&r[b]))
                .collect::<Vec<_>>(),
        );
        let z = (ms - mp) / (ss * ss + sp * sp).sqrt();
        assert!(
            z.abs() < 4.0,
            "band {b}: spectral {ms} ± {ss}, per band {mp} ± {sp}"
        );
    }
    let correlated = renders(&scenes, false, &[0, 0, 0], runs);
    let colour_noise = |rs: &[Vec<Vec<f32>>]| {
        let pixels = rs[0][0].len();
        let mut sum = 0.0;
        let mut count = 0;
        for p in 0..pixels {
            let ratios: Vec<f64> = (rs.iter())
                .filter(|r| r[0][p] > 0.0 && r[1][p] > 0.0)
                .map(|r| (r[1][p] as f64 / r[0][p] as f64).ln())
                .collect();
            if ratios.len() == rs.len() {
                sum += mean_se(&ratios).1 * (ratios.len() as f64).sqrt();
                count += 1;
            }
        }
        sum / count as f64
    };
    let (cs, cc) = (colour_noise(&spectral), colour_noise(&correlated));
    // per-pixel noise of each band (relative sd over seeds, mean over pixels)
    let band_noise = |rs: &[Vec<Vec<f32>>], b: usize| {
        let pixels = rs[0][b].len();
        let mut sum = 0.0;
        for p in 0..pixels {
            let v: Vec<f64> = rs.iter().map(|r| r[b][p] as f64).collect();
            let (m, se) = mean_se(&v);
            sum += if m > 0.0 {
                se * (v.len() as f64).sqrt() / m
            } else {
                0.0
            };
        }
        sum / pixels as f64
    };
    for b in 0..3 {
        eprintln!(
            "band {b}: per-pixel noise spectral {:.4}, per band {:.4}, correlated {:.4}",
            band_noise(&spectral, b),
            band_noise(&per_band, b),
            band_noise(&correlated, b)
        );
    }
    eprintln!("colour noise: spectral {cs:.4}, correlated bands {cc:.4}");
    assert!(
        cs < 0.9 * cc,
        "colour noise: spectral {cs}, correlated bands {cc}"
    );
}

/// A one-band render is unchanged by the setting, and it is refused where it cannot apply.
#[test]
fn one_band_and_refusals() {
    let scenes = disc_bands();
    let s = Settings {
        integrator: Integrator::Vpm,
        spp: 1,
        photons: 2_000,
        volume_photons: 4_000,
        ..Settings::default()
    };
    let on = Settings {
        spectral_photons: true,
        ..s
    };
    let one = &scenes[..1];
    let a = render_bands(one, &s, &[540], &Control::new()).unwrap();
    let b = render_bands(one, &on, &[540], &Control::new()).unwrap();
    assert_eq!(a[0].0, b[0].0);
    let pm = Settings {
        integrator: Integrator::Pm,
        ..on
    };
    let err = render_bands(&scenes, &pm, &[1, 2, 3], &Control::new()).unwrap_err();
    assert!(
        err.to_string()
            .contains("settings.spectral_photons = true applies to vpm, vpm-full, bre"),
        "{err}"
    );
}
