//! A multi-band render (one decode, one BVH shared by every band) gives, band for band, the
//! image an independent one-band render of the same scene and key gives: the same bits.

use dentalux_core::control::Control;
use dentalux_core::integrators::render::{render_band, render_bands};
use dentalux_core::integrators::settings::{Integrator, Settings};
use dentalux_core::medium::Medium;
use dentalux_core::scene::Scene;

mod common;

/// The disc scene with the disc's medium changed per band (absorption and scattering).
fn bands() -> Vec<Scene> {
    let base = common::disc_scene(1.5, 12, 9);
    [(0.2, 3.0), (0.05, 1.0), (1.0, 6.0)]
        .iter()
        .map(|&(mua, mus)| {
            let media: Vec<Medium> = vec![common::air(), common::medium(mua, mus, 0.6, 1.5)];
            base.with_band(media, base.surfaces.clone(), base.lights.clone())
                .unwrap()
        })
        .collect()
}

#[test]
fn each_band_equals_its_own_render() {
    let scenes = bands();
    assert!(scenes.iter().all(|s| s.shares_geometry(&scenes[0])));
    let keys = [540, 560, 600];
    for integrator in [
        Integrator::Vpm,
        Integrator::VpmFull,
        Integrator::Ppm,
        Integrator::VolpathNee,
    ] {
        let settings = Settings {
            integrator,
            spp: 2,
            photons: 2_000,
            volume_photons: 4_000,
            ..Settings::default()
        };
        let control = Control::new();
        let together = render_bands(&scenes, &settings, &keys, &control).unwrap();
        for (b, (scene, &band)) in scenes.iter().zip(&keys).enumerate() {
            // an independent scene: its own shapes and BVH
            let own = Scene::new(
                scene.camera,
                scene.media.clone(),
                scene.surfaces.clone(),
                scene.shapes().to_vec(),
                scene.lights.clone(),
                scene.ambient_medium,
            )
            .unwrap();
            assert!(!own.shares_geometry(scene));
            let (image, _) =
                render_band(&own, &Settings { band, ..settings }, &Control::new()).unwrap();
            assert!(image.iter().any(|&x| x > 0.0));
            assert_eq!(image, together[b].0, "{integrator:?}, band {b}");
        }
    }
}

#[test]
fn one_key_per_band() {
    let scenes = bands();
    let err = render_bands(&scenes, &Settings::default(), &[540], &Control::new()).unwrap_err();
    assert!(
        err.to_string()
            .contains("band_keys has 1 entries for 3 bands"),
        "{err}"
    );
}
