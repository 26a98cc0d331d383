//! How the volume pass emits: aimed emission (integrators/aim.rs) must keep every map's
//! expected power while putting more photons into small media, and a stored-photon budget
//! (`Emission::stored_cap`) must normalise powers by the photons actually emitted and give
//! the same maps whatever the thread count.

use dentalux_core::camera::Camera;
use dentalux_core::control::Control;
use dentalux_core::geometry::shapes::{Quad, Sphere};
use dentalux_core::geometry::Vec3;
use dentalux_core::integrators::aim::Aim;
use dentalux_core::integrators::photon_trace::{
    trace_camera_maps, trace_emission, Emission, PhotonMaps, StoreMode, Targets,
};
use dentalux_core::integrators::settings::Settings;
use dentalux_core::lights::Light;
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::photon_map::PhotonMap;
use dentalux_core::scene::{Boundary, Geometry, Scene, ShapeInstance};
use dentalux_core::surface::Surface;
use std::f64::consts::PI;

mod common;
use common::mean_se;

const VOLUME: Targets = Targets {
    volume: true,
    surface: false,
};

const SURFACE: Targets = Targets {
    volume: false,
    surface: true,
};

fn medium(mua: f64, mus: f64, g: f64, n: f64) -> Medium {
    let phase = PhaseFunction::hg_with_isotropic(g, 0.0).unwrap();
    Medium::new("", mua, mus, n, phase).unwrap()
}

fn shape(g: Geometry, b: Boundary) -> ShapeInstance {
    ShapeInstance::new("shape", g, None, b).unwrap()
}

/// A 2 mm sphere of a refracting scattering medium standing 30 mm from a quad light over a
/// large grey floor: few of the light's photons reach it directly, some by the floor.
fn small_medium_scene() -> Scene {
    let floor = shape(
        Geometry::Quad(Quad {
            corner: Vec3::new(-100.0, -100.0, 0.0),
            u: Vec3::new(200.0, 0.0, 0.0),
            v: Vec3::new(0.0, 200.0, 0.0),
        }),
        Boundary::Opaque { surface: 0 },
    );
    let ball = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::new(10.0, 0.0, 2.0),
            radius: 2.0,
        }),
        Boundary::Dielectric {
            inside: 1,
            outside: 0,
        },
    );
    let light = Light::Quad {
        corner: Vec3::new(-5.0, 5.0, 30.0),
        u: Vec3::new(10.0, 0.0, 0.0),
        v: Vec3::new(0.0, -10.0, 0.0),
        radiance: 1.0,
    };
    let camera = Camera::new(Vec3::new(0.0, -40.0, 20.0), Vec3::ZERO, Vec3::Z, 40.0, 4, 4).unwrap();
    Scene::new(
        camera,
        vec![medium(0.0, 0.0, 0.0, 1.0), medium(0.05, 2.0, 0.5, 1.4)],
        vec![Surface::Lambertian { reflectance: 0.7 }],
        vec![floor, ball],
        vec![light],
        0,
    )
    .unwrap()
}

fn trace(scene: &Scene, emission: &Emission, tag: u64) -> PhotonMaps {
    trace_targets(scene, emission, tag, VOLUME)
}

fn trace_targets(scene: &Scene, emission: &Emission, tag: u64, targets: Targets) -> PhotonMaps {
    trace_emission(
        scene,
        emission,
        StoreMode::All,
        targets,
        tag << 32,
        9,
        0,
        &Control::new(),
    )
    .unwrap()
}

/// `reps` independent traces of `emission` (stream tags `tag0`, `tag0 + 1`, ...).
fn repeat(
    scene: &Scene,
    emission: &Emission,
    targets: Targets,
    reps: u64,
    tag0: u64,
) -> Vec<PhotonMaps> {
    (0..reps)
        .map(|r| trace_targets(scene, emission, tag0 + r, targets))
        .collect()
}

/// Aimed emission (80 % into the sphere's cone) stores the same expected power in the
/// medium as the light's own emission, with many more photons per emitted photon.
#[test]
fn aimed_emission_keeps_the_stored_power() {
    let scene = small_medium_scene();
    let aim = Aim::new(&scene, 0.8).expect("the ball is a target");
    assert_eq!(aim.targets(), 1);
    let run = |aim: Option<Aim>, photons: u64| {
        let e = Emission {
            photons,
            aim,
            ..Emission::default()
        };
        let all = repeat(&scene, &e, VOLUME, 12, 1);
        for maps in &all {
            assert!(
                (maps.volume[1].total_power() - maps.ledger.stored_volume[1]).abs()
                    < 1e-4 * maps.ledger.stored_volume[1]
            );
        }
        let power: Vec<f64> = all.iter().map(|m| m.ledger.stored_volume[1]).collect();
        (
            mean_se(&power),
            all.iter().map(|m| m.volume[1].len()).sum::<usize>(),
        )
    };
    let ((plain, se_p), n_plain) = run(None, 200_000);
    let ((aimed, se_a), n_aimed) = run(Some(aim), 50_000);
    let se = (se_p * se_p + se_a * se_a).sqrt();
    eprintln!(
        "stored power: light's emission {plain:.5} ± {se_p:.5} ({n_plain} photons), \
         aimed {aimed:.5} ± {se_a:.5} ({n_aimed} photons from a quarter of the emission)"
    );
    assert!(
        (aimed - plain).abs() < 4.0 * se,
        "{aimed} vs {plain} ± {se}"
    );
    // a quarter of the photons emitted, yet more stored: the point of aiming
    assert!(n_aimed > 2 * n_plain, "{n_aimed} vs {n_plain}");
    // without a scattering medium there is nothing to aim at
    let mut clear = scene.clone();
    clear.media[1] = medium(0.05, 0.0, 0.0, 1.4);
    assert!(Aim::new(&clear, 0.9).is_none());
    assert!(Aim::new(&scene, 0.0).is_none());
}

/// Aimed emission splits the photons that reach the medium unaimed (off the floor: power
/// 1/(1 − w) against an aimed photon's p_light/(w p_cone)) into walks of an aimed photon's
/// power: the ball's map holds no photon far heavier than the rest, its stored power is the
/// same as without splitting (within 4 s.e. of independent repetitions), and every walk's
/// power is booked (the ledger balances).
#[test]
fn aimed_emission_splits_heavy_photons() {
    let scene = small_medium_scene();
    let aim = Aim::new(&scene, 0.8).expect("the ball is a target");
    // independent streams for the two (tags 300.. and 400..), so their errors add
    let run = |aim: Aim, tag0: u64| {
        let e = Emission {
            photons: 50_000,
            aim: Some(aim),
            ..Emission::default()
        };
        let all = repeat(&scene, &e, VOLUME, 12, tag0);
        let mut ratio: f64 = 0.0;
        for maps in &all {
            let l = &maps.ledger;
            let out =
                l.absorbed_medium.iter().sum::<f64>() + l.absorbed_surface + l.escaped + l.cut;
            assert!(
                (out - l.emitted).abs() < 1e-9 * l.emitted,
                "{out} vs {}",
                l.emitted
            );
            ratio = ratio.max(heaviest_over_mean(&maps.volume[1]));
        }
        let power: Vec<f64> = all.iter().map(|m| m.ledger.stored_volume[1]).collect();
        (mean_se(&power), ratio)
    };
    let (split, top_split) = run(aim.clone(), 300);
    let (whole, top_whole) = run(aim.without_splitting(), 400);
    split_matches_unsplit("the ball", split, whole);
    weights_even_out("the ball", top_split, top_whole);
}

/// The heaviest stored photon's power over the map's mean.
fn heaviest_over_mean(map: &PhotonMap) -> f64 {
    let mean = map.total_power() / map.len() as f64;
    let top = map
        .photons()
        .iter()
        .map(|p| p.power as f64)
        .fold(0.0, f64::max);
    top / mean
}

/// Stored power (mean, s.e.) of split and unsplit emissions on independent streams: equal
/// within 4 s.e. of the two.
fn split_matches_unsplit(what: &str, (split, se_s): (f64, f64), (whole, se_w): (f64, f64)) {
    let se = (se_s * se_s + se_w * se_w).sqrt();
    eprintln!("{what}: stored power split {split:.5} ± {se_s:.5}, whole {whole:.5} ± {se_w:.5}");
    assert!(
        (split - whole).abs() < 4.0 * se,
        "{what}: {split} vs {whole} ± {se}"
    );
}

/// The heaviest photon over the mean, split and unsplit: heavy unsplit (> 10×), alike split
/// (< 3×).
fn weights_even_out(what: &str, top_split: f64, top_whole: f64) {
    eprintln!("{what}: heaviest photon {top_split:.2} × the mean split, {top_whole:.2} whole");
    assert!(
        top_whole > 10.0,
        "{what}: unsplit photons should be heavy: {top_whole}"
    );
    assert!(
        top_split < 3.0,
        "{what}: split photons should weigh alike: {top_split}"
    );
}

/// Two targets of different sizes: the 2 mm ball of `small_medium_scene` and an 8 mm ball of
/// another medium as far from the light, with a cone about 16 times wider. A photon that
/// reaches the small ball off the floor is split against the photons sent straight at its
/// entry point, the small ball's own aimed photons, not against the wide cone's (which
/// would leave it about as many times heavier as the cones' densities differ); the stored
/// power of each ball is the unsplit emission's.
#[test]
fn split_heavy_photons_match_the_target_they_enter() {
    let base = small_medium_scene();
    let big = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::new(-20.0, 0.0, 8.0),
            radius: 8.0,
        }),
        Boundary::Dielectric {
            inside: 2,
            outside: 0,
        },
    );
    let mut shapes = base.shapes().to_vec();
    shapes.push(big);
    let mut media = base.media.clone();
    media.push(medium(0.05, 2.0, 0.5, 1.4));
    let scene = Scene::new(
        base.camera,
        media,
        base.surfaces.clone(),
        shapes,
        base.lights.clone(),
        0,
    )
    .unwrap();
    let aim = Aim::new(&scene, 0.8).expect("two targets");
    assert_eq!(aim.targets(), 2);
    let run = |aim: Aim, tag0: u64| {
        let e = Emission {
            photons: 40_000,
            aim: Some(aim),
            ..Emission::default()
        };
        let all = repeat(&scene, &e, VOLUME, 12, tag0);
        let ratio = all
            .iter()
            .map(|maps| heaviest_over_mean(&maps.volume[1]))
            .fold(0.0, f64::max);
        let stored = |i: usize| {
            let v: Vec<f64> = all.iter().map(|m| m.ledger.stored_volume[i]).collect();
            mean_se(&v)
        };
        (stored(1), stored(2), ratio)
    };
    let (small, large, top_split) = run(aim.clone(), 500);
    let (small_whole, large_whole, top_whole) = run(aim.without_splitting(), 600);
    split_matches_unsplit("small ball", small, small_whole);
    split_matches_unsplit("large ball", large, large_whole);
    weights_even_out("small ball", top_split, top_whole);
}

/// The surface pass aimed the same way: the power its map stores (light on the floor that
/// came through the ball, or off the floor again) is the light's own emission's, from far
/// more photons per photon emitted.
#[test]
fn aimed_emission_keeps_the_surface_power() {
    let scene = small_medium_scene();
    let run = |aim: Option<Aim>, photons: u64| {
        let e = Emission {
            photons,
            aim,
            ..Emission::default()
        };
        let all = repeat(&scene, &e, SURFACE, 12, 100);
        let power: Vec<f64> = all.iter().map(|m| m.ledger.stored_surface).collect();
        (
            mean_se(&power),
            all.iter().map(|m| m.surface.len()).sum::<usize>(),
        )
    };
    let ((plain, se_p), n_plain) = run(None, 400_000);
    let ((aimed, se_a), n_aimed) = run(Aim::new(&scene, 0.8), 100_000);
    let se = (se_p * se_p + se_a * se_a).sqrt();
    eprintln!(
        "surface power: light's emission {plain:.5} ± {se_p:.5} ({n_plain} photons), \
         aimed {aimed:.5} ± {se_a:.5} ({n_aimed} photons)"
    );
    assert!(
        (aimed - plain).abs() < 4.0 * se,
        "{aimed} vs {plain} ± {se}"
    );
    assert!(n_aimed > n_plain, "{n_aimed} vs {n_plain}");
}

/// A point light in an infinite medium of albedo a: the maps hold Φ a/(1 − a) of stored
/// power whatever the number of photons (closed form). With a budget of stored photons the
/// emission stops at the first batch that reaches it, the powers are normalised by the
/// photons emitted, and the maps are the same with 1, 2 or 3 threads.
#[test]
fn stored_budget_normalises_and_ignores_threads() {
    let a = 0.9;
    let speck = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::splat(1e4),
            radius: 1.0,
        }),
        Boundary::Opaque { surface: 0 },
    );
    let camera = Camera::new(Vec3::new(0.0, -5.0, 0.0), Vec3::ZERO, Vec3::Z, 40.0, 4, 4).unwrap();
    let scene = Scene::new(
        camera,
        vec![medium(1.0 - a, a, 0.3, 1.0)],
        vec![Surface::Black],
        vec![speck],
        vec![Light::Point {
            position: Vec3::ZERO,
            intensity: 2.0,
        }],
        0,
    )
    .unwrap();
    let cap = 300_000u64;
    let emission = Emission {
        photons: 10_000_000,
        stored_cap: Some(cap),
        ..Emission::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| trace(&scene, &emission, 0))
    };
    let one = run(1);
    let stored = one.volume[0].len() as u64;
    // the chunks traced in parallel follow the thread count and the rate of storing
    for other in [run(2), run(3)] {
        assert_eq!(one.volume[0].photons(), other.volume[0].photons());
        assert_eq!(one.emitted, other.emitted);
        assert_eq!(one.ledger, other.ledger);
    }
    // stopped at the photon that reached the budget: over by less than one photon's events
    // (P(more than 300 events) = 0.9³⁰⁰ ≈ 2e-14)
    assert!(stored >= cap && stored < cap + 300, "{stored}");
    assert!(one.emitted < emission.photons && one.emitted % 4096 != 0);
    let phi = 4.0 * PI * 2.0;
    let expect = phi * a / (1.0 - a);
    let se = phi * a.sqrt() / (1.0 - a) / (one.emitted as f64).sqrt();
    let got = one.volume[0].total_power();
    eprintln!(
        "budget {cap}: {stored} stored from {} photons; power {got:.3} vs {expect:.3} ± {se:.3}",
        one.emitted
    );
    assert!((got - expect).abs() < 4.0 * se, "{got} vs {expect} ± {se}");
    assert!((one.ledger.emitted - phi).abs() < 1e-6 * phi);
}

/// The camera pass's surface map comes from `photons` emitted photons: the volume pass's
/// own first `photons` when it emits that many (no second emission), and a surface pass for
/// the rest when a stored budget stops the volume pass earlier. Either way its stored power
/// matches a surface-only pass's, and so does its photon count.
#[test]
fn camera_maps_take_surface_photons_from_the_volume_pass() {
    let scene = small_medium_scene();
    let plain = Emission {
        photons: 400_000,
        ..Emission::default()
    };
    let reference = repeat(&scene, &plain, SURFACE, 12, 300);
    let power: Vec<f64> = reference.iter().map(|m| m.ledger.stored_surface).collect();
    let (p_ref, se_ref) = mean_se(&power);
    let n_ref = reference.iter().map(|m| m.surface.len()).sum::<usize>() as f64 / 12.0;
    let camera = |seed: u64, volume_stored: u64| {
        let s = Settings {
            volume_photons: 600_000,
            volume_stored,
            photons: 400_000,
            seed,
            ..Settings::default()
        };
        trace_camera_maps(&scene, &s, StoreMode::All, 0, &Control::new()).unwrap()
    };
    // 0: the volume pass emits 600 k, its first 400 k make the surface map; 20 000 stored:
    // it stops after about 90 k and a surface pass emits the other 310 k
    for budget in [0, 20_000] {
        let maps: Vec<PhotonMaps> = (0..12).map(|seed| camera(seed, budget)).collect();
        let power: Vec<f64> = maps.iter().map(|m| m.ledger.stored_surface).collect();
        let (p, se_p) = mean_se(&power);
        let in_map: f64 = maps[0]
            .surface
            .photons()
            .iter()
            .map(|p| p.power as f64)
            .sum();
        let n = maps.iter().map(|m| m.surface.len()).sum::<usize>() as f64 / 12.0;
        let se = (se_ref * se_ref + se_p * se_p).sqrt();
        eprintln!(
            "budget {budget}: surface power {p:.5} ± {se_p:.5} vs a surface pass {p_ref:.5} ± \
             {se_ref:.5}; photons {n:.0} vs {n_ref:.0}; emitted {}",
            maps[0].emitted
        );
        assert!((p - p_ref).abs() < 4.0 * se, "{p} vs {p_ref} ± {se}");
        assert!(
            (in_map / power[0] - 1.0).abs() < 1e-4,
            "{in_map} vs {}",
            power[0]
        );
        // photon counts are Poisson-like: 4 standard errors of the two means
        assert!(
            (n - n_ref).abs() < 4.0 * (n / 12.0 + n_ref / 12.0).sqrt(),
            "{n} vs {n_ref}"
        );
        let volume: usize = maps[0].volume.iter().map(|m| m.len()).sum();
        if budget == 0 {
            assert_eq!(maps[0].emitted, 600_000, "no second emission");
        } else {
            // the volume pass stopped at its budget; with the surface pass's photons the two
            // emitted exactly `photons`
            assert!((20_000..21_000).contains(&volume), "{volume}");
            assert_eq!(maps[0].emitted, 400_000);
        }
    }
}
