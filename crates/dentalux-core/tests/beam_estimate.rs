//! The beam radiance estimate (`bre`, `volume_estimator = "beam"`; photon_map/beam.rs)
//! against the unbiased `volpath-nee` on a refracting disc and on nested spheres (enamel
//! around dentin), against a closed form (a scattering medium in a furnace of uniform
//! radiance, where every ray sees that radiance), its bias shrinking with the radius, its
//! progressive form converging, determinism, and its refusals. Tolerances come from the
//! runs' standard errors.

use dentalux_core::control::Control;
use dentalux_core::geometry::shapes::BoxShape;
use dentalux_core::geometry::Vec3;
use dentalux_core::integrators::render::render_band;
use dentalux_core::integrators::settings::{Integrator, Settings, VolumeEstimator};
use dentalux_core::lights::Light;
use dentalux_core::scene::{Boundary, Geometry, Scene};
use dentalux_core::surface::Surface;

mod common;
use common::{air, camera, disc_scene, medium, nested_spheres, shape};

fn band(scene: &Scene, s: &Settings) -> Vec<f64> {
    let (img, _) = render_band(scene, s, &Control::new()).unwrap();
    img.iter().map(|&v| v as f64).collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Per-pixel mean of `runs` renders with seeds seed, seed + 1, …, the per-pixel variance
/// of that mean, and the standard error of its image mean.
fn runs(scene: &Scene, s: &Settings, n: u64) -> (Vec<f64>, Vec<f64>, f64) {
    let imgs: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            band(
                scene,
                &Settings {
                    seed: s.seed + i,
                    ..*s
                },
            )
        })
        .collect();
    let px = imgs[0].len();
    let m: Vec<f64> = (0..px)
        .map(|j| imgs.iter().map(|im| im[j]).sum::<f64>() / n as f64)
        .collect();
    let var: Vec<f64> = (0..px)
        .map(|j| imgs.iter().map(|im| (im[j] - m[j]).powi(2)).sum::<f64>() / ((n - 1) * n) as f64)
        .collect();
    let means: Vec<f64> = imgs.iter().map(|im| mean(im)).collect();
    let mm = mean(&means);
    let se = (means.iter().map(|v| (v - mm).powi(2)).sum::<f64>() / ((n - 1) * n) as f64).sqrt();
    (m, var, se)
}

fn reference(scene: &Scene, spp: u32, seed: u64) -> (Vec<f64>, Vec<f64>, f64) {
    let s = Settings {
        integrator: Integrator::VolpathNee,
        spp,
        seed,
        ..Settings::default()
    };
    runs(scene, &s, 4)
}

fn beam(integrator: Integrator, photons: u64, radius: f64, spp: u32, seed: u64) -> Settings {
    Settings {
        integrator,
        volume_estimator: VolumeEstimator::Beam,
        spp,
        photons: photons / 4,
        volume_photons: photons,
        radius: Some(radius),
        seed,
        ..Settings::default()
    }
}

/// Image-mean relative error and its standard error (both runs' errors combined).
fn compare(name: &str, a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let (e, se) = ((a.0 - b.0) / b.0, (a.1.hypot(b.1)) / b.0);
    eprintln!(
        "{name}: {:.5} ± {:.5} vs {:.5} ± {:.5}: {e:+.4} ± {se:.4}",
        a.0, a.1, b.0, b.1
    );
    (e, se)
}

/// Per-pixel bias of `img` (variance `var`) against the reference, the noise of both taken
/// out of the squared error, relative to the reference's mean.
fn pixel_bias(img: &[f64], var: &[f64], r: &[f64], r_var: &[f64]) -> f64 {
    let n = img.len() as f64;
    let sq: f64 = img.iter().zip(r).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / n;
    let noise = (var.iter().sum::<f64>() + r_var.iter().sum::<f64>()) / n;
    (sq - noise).max(0.0).sqrt() / mean(r)
}

/// `bre` and `vpm-full` with the beam converge to `volpath-nee` on the disc: index-matched
/// (eq. 13 exact, so `bre`'s shadow rays are too) and refracting (`vpm-full` with the beam:
/// single scattering from the map). Once the radius is small the image mean agrees within
/// 4 standard errors, with no bias budget.
#[test]
fn beam_estimate_agrees_with_volpath_nee_on_disc() {
    for (n, integrator) in [(1.0, Integrator::Bre), (1.4, Integrator::VpmFull)] {
        let scene = disc_scene(n, 20, 15);
        let (r, _, r_se) = reference(&scene, 256, 7);
        let (img, _, se) = runs(&scene, &beam(integrator, 400_000, 0.15, 8, 11), 4);
        let (e, s) = compare(
            &format!("{integrator:?} beam n={n}"),
            (mean(&img), se),
            (mean(&r), r_se),
        );
        assert!(e.abs() < 4.0 * s, "{integrator:?} n={n}: {e:+.4} ± {s:.4}");
    }
}

/// Nested spheres (enamel around dentin, both refracting), against `volpath-nee`.
#[test]
fn beam_estimate_agrees_with_volpath_nee_on_nested_spheres() {
    let scene = nested_spheres();
    let (r, _, r_se) = reference(&scene, 256, 41);
    let (img, _, se) = runs(&scene, &beam(Integrator::VpmFull, 400_000, 0.15, 8, 43), 4);
    let (e, s) = compare("vpm-full beam nested", (mean(&img), se), (mean(&r), r_se));
    assert!(e.abs() < 4.0 * s, "{e:+.4} ± {s:.4}");
}

/// The per-pixel bias against `volpath-nee` shrinks with the disc radius (the curve of
/// docs/notes/2026-12-06-bre.md): at 2 mm (half the disc's radius) it is well above its value at 0.25 mm.
#[test]
fn beam_bias_shrinks_with_radius() {
    let scene = disc_scene(1.0, 20, 15);
    let (r, r_var, _) = reference(&scene, 256, 61);
    let bias = |radius: f64| {
        let (img, var, _) = runs(&scene, &beam(Integrator::Bre, 400_000, radius, 8, 63), 4);
        let b = pixel_bias(&img, &var, &r, &r_var);
        eprintln!("radius {radius} mm: per-pixel bias {b:.4}");
        b
    };
    let (wide, narrow) = (bias(2.0), bias(0.25));
    assert!(wide > 2.0 * narrow && wide > 0.01, "{wide} vs {narrow}");
}

/// Closed form: a scattering, non-absorbing cube inside a closed box of inward-facing area
/// lights of radiance L (black, as emitters are). The radiance field is uniform, L in every
/// direction (fluence 4πL, in-scattered radiance σs φ/(4π) = σs L), so every camera ray,
/// through the cube or not, sees L.
#[test]
fn beam_estimate_sees_the_furnace_radiance() {
    let h = 10.0;
    // six faces of the cube [−h, h]³, each emitting towards u × v = inwards
    let face = |corner: Vec3, u: Vec3, v: Vec3| Light::Quad {
        corner,
        u,
        v,
        radiance: 1.0,
    };
    let (x, y, z) = (Vec3::X * 2.0 * h, Vec3::Y * 2.0 * h, Vec3::Z * 2.0 * h);
    let lo = Vec3::new(-h, -h, -h);
    let hi = Vec3::new(h, h, h);
    let lights = vec![
        face(lo, x, y),
        face(hi, -y, -x),
        face(lo, z, x),
        face(hi, -x, -z),
        face(lo, y, z),
        face(hi, -z, -y),
    ];
    let cube = shape(
        Geometry::Box(BoxShape {
            min: Vec3::new(-3.0, -3.0, -3.0),
            max: Vec3::new(3.0, 3.0, 3.0),
        }),
        Boundary::Dielectric {
            inside: 1,
            outside: 0,
        },
    );
    let scene = Scene::new(
        camera(Vec3::new(0.0, -9.0, 2.0), Vec3::ZERO, 12, 9),
        vec![air(), medium(0.0, 1.5, 0.5, 1.0)],
        vec![Surface::Lambertian { reflectance: 0.0 }],
        vec![cube],
        lights,
        0,
    )
    .unwrap();
    let (img, _, se) = runs(&scene, &beam(Integrator::Bre, 400_000, 0.5, 4, 71), 4);
    let (e, s) = compare("bre furnace", (mean(&img), se), (1.0, 0.0));
    assert!(e.abs() < 4.0 * s && s < 0.02, "{e:+.4} ± {s:.4}");
}

/// Progressive `ppm` with the beam: the discs shrink pass by pass, and the per-pixel error
/// against `volpath-nee` keeps falling (1, 4, 16 passes), its mean within 4 standard errors.
#[test]
fn progressive_beam_converges() {
    let scene = disc_scene(1.4, 20, 15);
    let (r, r_var, r_se) = reference(&scene, 256, 81);
    let err = |passes: u32| {
        let s = Settings {
            passes,
            radius: Some(1.0),
            ..beam(Integrator::Ppm, 50_000, 1.0, 4, 83)
        };
        let img = band(&scene, &s);
        let e = pixel_bias(&img, &vec![0.0; img.len()], &r, &r_var);
        eprintln!("ppm beam {passes} passes: per-pixel error {e:.4}");
        (e, img)
    };
    let (e1, _) = err(1);
    let (e4, _) = err(4);
    let (e16, img) = err(16);
    assert!(e16 < e4 && e4 < e1, "{e1} {e4} {e16}");
    // the mean of 16 passes: its spread estimated from the 16-pass error itself is not
    // independent, so judge it against the reference's error plus the per-pixel error / √px
    let s = r_se.hypot(e16 * mean(&r) / (img.len() as f64).sqrt());
    let (e, s) = compare("ppm beam 16", (mean(&img), 0.0), (mean(&r), s));
    assert!(e.abs() < 4.0 * s, "{e:+.4} ± {s:.4}");
}

/// Same seed, any thread count: the same image; the photon pass's ledger is the one `vpm`'s
/// photon pass keeps (the beam changes only the camera pass).
#[test]
fn beam_estimate_is_deterministic() {
    let scene = disc_scene(1.4, 16, 12);
    let s = beam(Integrator::Bre, 40_000, 0.3, 2, 5);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_band(&scene, &s, &Control::new()).unwrap())
    };
    let (one, stats) = run(1);
    let (two, _) = run(2);
    assert_eq!(one, two);
    assert_eq!(stats.integrator, "bre");
    assert_eq!(stats.estimator, "beam");
    let vpm = Settings {
        integrator: Integrator::Vpm,
        volume_estimator: VolumeEstimator::Points,
        ..s
    };
    let (_, vstats) = render_band(&scene, &vpm, &Control::new()).unwrap();
    let ledger = |st: &dentalux_core::integrators::settings::Stats| {
        [
            "emitted_power",
            "stored_volume_power",
            "stored_surface_power",
        ]
        .map(|k| st.extra.iter().find(|(n, _)| n == k).map(|e| e.1))
    };
    assert_eq!(ledger(&stats), ledger(&vstats));
}

/// Refusals: a radius ≤ 0 or NaN, an unknown estimator, the beam on an integrator without
/// volume photons, and the beam in a scene with no scattering medium, each naming the setting.
#[test]
fn beam_estimate_refuses_bad_settings() {
    use dentalux_core::contract::settings_from_json;
    for (json, key) in [
        (r#"{"integrator": "bre", "radius": 0}"#, "settings.radius"),
        (r#"{"integrator": "bre", "radius": -1}"#, "settings.radius"),
        (
            r#"{"volume_estimator": "beams"}"#,
            "settings.volume_estimator",
        ),
        (
            r#"{"integrator": "pm", "volume_estimator": "beam"}"#,
            "settings.volume_estimator",
        ),
    ] {
        let e = settings_from_json(json).unwrap_err().to_string();
        assert!(e.contains(key), "{json}: {e}");
    }
    let nan = Settings {
        radius: Some(f64::NAN),
        ..beam(Integrator::Bre, 1000, 0.1, 1, 1)
    };
    let scene = disc_scene(1.4, 4, 3);
    let e = render_band(&scene, &nan, &Control::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("settings.radius"), "{e}");
    // a scene whose media do not scatter
    let clear = Scene::new(
        camera(Vec3::new(0.0, -9.0, 2.0), Vec3::ZERO, 4, 3),
        vec![air(), medium(0.5, 0.0, 0.0, 1.4)],
        vec![Surface::Lambertian { reflectance: 0.5 }],
        vec![],
        vec![Light::Point {
            position: Vec3::new(0.0, 0.0, 10.0),
            intensity: 1.0,
        }],
        0,
    )
    .unwrap();
    let e = render_band(
        &clear,
        &beam(Integrator::Bre, 1000, 0.1, 1, 1),
        &Control::new(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("settings.integrator = \"bre\"") && e.contains("no scattering"),
        "{e}"
    );
}
