//! Hero-wavelength camera paths (`integrators::hero_camera`, `settings.hero_camera`): one
//! camera path for every band of a render. With one band the pass is `vpm`'s, bit for bit;
//! over several bands, given the same photon maps, each band's image agrees with its own
//! band-by-band camera pass within 4 standard errors (paired per pixel: both passes read the
//! same maps, so only camera noise differs), with and without dispersion (a path that forks
//! at every refraction into the disc), for the march, the beam estimate and `vpm-full`.

use dentalux_core::control::Control;
use dentalux_core::integrators::hero_camera;
use dentalux_core::integrators::photon_trace::{trace_camera_maps, PhotonMaps};
use dentalux_core::integrators::render::render_bands;
use dentalux_core::integrators::settings::{Integrator, Settings, VolumeEstimator};
use dentalux_core::integrators::vpm;
use dentalux_core::scene::Scene;

mod common;
use common::{air, mean_se, medium};

/// Three bands of the disc scene with band-dependent coefficients (as a tooth's differ
/// between bands) and, with `dispersion`, band-dependent refractive indices.
fn bands(dispersion: bool) -> Vec<Scene> {
    let eta = |e: f64| if dispersion { e } else { 1.5 };
    disc_bands(&[
        (0.2, 3.0, eta(1.55)),
        (0.3, 4.5, eta(1.54)),
        (0.12, 2.2, eta(1.537)),
    ])
}

/// The disc scene once per band, its disc of (μa, μs, n) = `coefficients[b]` in band b.
fn disc_bands(coefficients: &[(f64, f64, f64)]) -> Vec<Scene> {
    let base = common::disc_scene(1.5, 48, 36);
    (coefficients.iter())
        .map(|&(mua, mus, eta)| {
            let media = vec![air(), medium(mua, mus, 0.6, eta)];
            base.with_band(media, base.surfaces.clone(), base.lights.clone())
                .unwrap()
        })
        .collect()
}

fn settings(integrator: Integrator, estimator: VolumeEstimator, seed: u64) -> Settings {
    Settings {
        integrator,
        volume_estimator: estimator,
        spp: 32,
        photons: 6_000,
        volume_photons: 20_000,
        k: 32,
        seed,
        ..Settings::default()
    }
}

/// Each band's photon maps, traced once with `s`.
fn maps(scenes: &[Scene], s: &Settings) -> Vec<PhotonMaps> {
    let full = s.integrator == Integrator::VpmFull;
    (scenes.iter())
        .map(|sc| trace_camera_maps(sc, s, vpm::store_mode(full), 0, &Control::new()).unwrap())
        .collect()
}

const CASES: [(Integrator, VolumeEstimator); 3] = [
    (Integrator::Vpm, VolumeEstimator::Points),
    (Integrator::Vpm, VolumeEstimator::Beam),
    (Integrator::VpmFull, VolumeEstimator::Points),
];

#[test]
fn one_band_is_the_vpm_pass_bit_for_bit() {
    let scenes = bands(true);
    let one = &scenes[..1];
    for (integrator, estimator) in CASES {
        let s = settings(integrator, estimator, 3);
        let full = integrator == Integrator::VpmFull;
        let m = maps(one, &s);
        let (a, _) = vpm::render_with_maps(&one[0], &s, &Control::new(), full, &m[0]).unwrap();
        let b = hero_camera::render_with_maps(one, &s, &Control::new(), full, &m).unwrap();
        assert_eq!(a, b[0].0, "{integrator:?} / {estimator:?}");
    }
}

/// Each band of `scenes` through the hero pass against its own camera pass over the same
/// maps: the paired pixel differences' mean within 4 standard errors of 0.
fn agree(scenes: &[Scene], what: &str) {
    for (integrator, estimator) in CASES {
        let photon = settings(integrator, estimator, 5);
        let full = integrator == Integrator::VpmFull;
        let m = maps(scenes, &photon);
        // camera passes over the same maps, with other streams than each other's
        let hero = settings(integrator, estimator, 11);
        let own = settings(integrator, estimator, 12);
        let together =
            hero_camera::render_with_maps(scenes, &hero, &Control::new(), full, &m).unwrap();
        for (b, (scene, maps)) in scenes.iter().zip(&m).enumerate() {
            let (alone, _) =
                vpm::render_with_maps(scene, &own, &Control::new(), full, maps).unwrap();
            assert!(together[b].0.iter().all(|x| x.is_finite()));
            let d: Vec<f64> = (together[b].0.iter().zip(&alone))
                .map(|(&h, &a)| h as f64 - a as f64)
                .collect();
            let (dm, se) = mean_se(&d);
            let level = alone.iter().map(|&x| x as f64).sum::<f64>() / alone.len() as f64;
            eprintln!(
                "{what}, {integrator:?}/{estimator:?}, band {b}: hero − own {dm:.3e} ± {se:.3e} \
                 (mean {level:.4})"
            );
            assert!(level > 0.0);
            assert!(
                dm.abs() < 4.0 * se,
                "{what}, {integrator:?}/{estimator:?}, band {b}: {dm} ± {se} of {level}"
            );
        }
    }
}

#[test]
fn bands_agree_with_their_own_camera_passes() {
    agree(&bands(false), "no dispersion");
    agree(&bands(true), "dispersion");
}

/// A band in which the disc is clear (μa = μs = 0) rides along a scattering one: it keeps
/// its weight through the disc, and both agree with their own passes.
#[test]
fn a_band_clear_in_the_disc() {
    agree(
        &disc_bands(&[(0.2, 3.0, 1.5), (0.0, 0.0, 1.5)]),
        "one band clear",
    );
}

/// Through `render_bands`: the setting is read, one band is unchanged by it, the maps are the
/// band-by-band render's, and it is refused where it cannot apply.
#[test]
fn render_bands_with_hero_camera() {
    let scenes = bands(false);
    let s = settings(Integrator::Vpm, VolumeEstimator::Points, 7);
    let on = Settings {
        hero_camera: true,
        ..s
    };
    let one = &scenes[..1];
    let a = render_bands(one, &s, &[540], &Control::new()).unwrap();
    let b = render_bands(one, &on, &[540], &Control::new()).unwrap();
    assert_eq!(a[0].0, b[0].0);
    let keys = [0, 0, 0];
    let all = render_bands(&scenes, &on, &keys, &Control::new()).unwrap();
    let per_band = render_bands(&scenes, &s, &keys, &Control::new()).unwrap();
    for (h, p) in all.iter().zip(&per_band) {
        assert_eq!(h.1.photons_stored, p.1.photons_stored);
        assert!(h
            .1
            .extra
            .iter()
            .any(|(k, v)| k == "hero_camera" && *v == 1.0));
        assert!(h.0.iter().all(|x| x.is_finite()));
    }
    let pm = Settings {
        integrator: Integrator::Pm,
        ..on
    };
    let err = render_bands(&scenes, &pm, &[1, 2, 3], &Control::new()).unwrap_err();
    assert!(
        err.to_string()
            .contains("settings.hero_camera = true applies to vpm, vpm-full, bre"),
        "{err}"
    );
}
