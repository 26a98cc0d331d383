//! The spectral photon pass (`integrators::hero`): photons walking in a hero band, every band's
//! power weighted by the balance heuristic. Each band must still get its own answer: closed
//! forms of the energy ledger per band (an infinite medium of band-dependent albedo and
//! anisotropy, a closed sphere of band-dependent reflectance), and `vpm` images whose means
//! agree with the band-by-band render within 4 standard errors (spread over seeds). And the
//! point of it: the bands' noise is shared, so the colour (a band ratio) is less noisy than
//! with correlated per-band passes.

use dentalux_core::control::Control;
use dentalux_core::geometry::shapes::{Quad, Sphere};
use dentalux_core::geometry::Vec3;
use dentalux_core::integrators::aim::Aim;
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
use common::{air, camera, mean_se, medium, shape};

/// One pass of `n` photons over `scenes` (spectral for more than one) with `seed`.
fn passes_seeded(scenes: &[Scene], n: u64, mode: StoreMode, seed: u64) -> Vec<PhotonMaps> {
    let emission = Emission {
        photons: n,
        ..Emission::default()
    };
    let control = Control::new();
    trace_emission_bands(scenes, &emission, mode, Targets::BOTH, 0, seed, 0, &control).unwrap()
}

/// The power medium 1 stores in `runs` band-by-band analog passes of `n` photons of
/// `scene` (seeds 1..=runs).
fn analog_stored(scene: &Scene, n: u64, runs: u64) -> Vec<f64> {
    let one = std::slice::from_ref(scene);
    (1..=runs)
        .map(|seed| {
            passes_seeded(one, n, StoreMode::Paper, seed)[0]
                .ledger
                .stored_volume[1]
        })
        .collect()
}

/// `runs` spectral passes of `n` photons with seeds 1..=runs.
fn passes(scenes: &[Scene], n: u64, mode: StoreMode, runs: u64) -> Vec<Vec<PhotonMaps>> {
    (1..=runs)
        .map(|seed| passes_seeded(scenes, n, mode, seed))
        .collect()
}

/// Stored power Φ a/(1 − a) per band in an infinite medium whose albedo a, extinction σt
/// and anisotropy g differ between the bands (`vpm-full` stores every scattering);
/// everything is absorbed. A fourth band is clear (σt = 0): its photons fly to the far
/// speck or escape, so it stores nothing and absorbs nothing in the medium; the walks that
/// collided are ones it cannot draw.
#[test]
fn infinite_medium_ledger_per_band() {
    // (albedo, σt [1/mm], g); the last band clear
    let bands = [
        (0.9, 1.0, 0.3),
        (0.8, 2.5, 0.6),
        (0.95, 0.5, 0.0),
        (0.0, 0.0, 0.0),
    ];
    let scene = |(a, st, g): (f64, f64, f64)| vec![medium((1.0 - a) * st, a * st, g, 1.0)];
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
    for (b, &(a, st, _)) in bands.iter().enumerate() {
        let stored: Vec<f64> = runs.iter().map(|r| r[b].ledger.stored_volume[0]).collect();
        let absorbed: Vec<f64> = runs
            .iter()
            .map(|r| r[b].ledger.absorbed_medium[0])
            .collect();
        let gone: Vec<f64> = (runs.iter())
            .map(|r| r[b].ledger.escaped + r[b].ledger.absorbed_surface)
            .collect();
        let (expect_stored, expect_absorbed) = if st > 0.0 {
            (phi * a / (1.0 - a), phi)
        } else {
            (0.0, 0.0)
        };
        for (what, v, expect) in [
            ("stored", &stored, expect_stored),
            ("absorbed", &absorbed, expect_absorbed),
            ("escaped", &gone, phi - expect_absorbed),
        ] {
            let (m, se) = mean_se(v);
            assert!(
                (m - expect).abs() <= 4.0 * se + 1e-9 * phi,
                "band {b}: {what} {m} vs {expect} ± {se}"
            );
        }
        // one light: every band's emission weight is 1, so Φ_b is emitted exactly
        for r in &runs {
            assert!((r[b].ledger.emitted - phi).abs() < 1e-9 * phi);
            let map = r[b].volume[0].total_power();
            assert!((map - r[b].ledger.stored_volume[0]).abs() <= 1e-4 * map);
        }
    }
    // the bands' maps hold the same photons
    let r = &runs[0];
    assert!(r.iter().all(|m| m.volume[0].len() == r[0].volume[0].len()));
}

/// A sphere of radius 2 mm at the origin filled with `media(n)[1]` (a dielectric in air)
/// before an opaque wall (`surfaces[0]`) in the plane y = `wall_y`, lit by `light`: one
/// scene per index in `indices`, sharing their geometry.
fn sphere_before_wall(
    wall_y: f64,
    light: Light,
    surfaces: &[Surface],
    indices: &[f64],
    media: impl Fn(f64) -> Vec<Medium>,
) -> Vec<Scene> {
    let sphere = shape(
        Geometry::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 2.0,
        }),
        Boundary::Dielectric {
            inside: 1,
            outside: 0,
        },
    );
    let wall = shape(
        Geometry::Quad(Quad {
            corner: Vec3::new(-20.0, wall_y, -20.0),
            u: Vec3::new(40.0, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, 40.0),
        }),
        Boundary::Opaque { surface: 0 },
    );
    let first = Scene::new(
        camera(Vec3::new(0.0, -10.0, 5.0), Vec3::ZERO, 4, 4),
        media(indices[0]),
        surfaces.to_vec(),
        vec![sphere, wall],
        vec![light],
        0,
    )
    .unwrap();
    (indices.iter())
        .map(|&n| {
            first
                .with_band(media(n), surfaces.to_vec(), vec![light])
                .unwrap()
        })
        .collect()
}

/// A scattering sphere whose refractive index differs per band (1.5 / 1.4 / 1.6; walks
/// refracted in one band cannot be drawn in another) in front of a grey wall: each band's
/// ledger balances (emitted = absorbed + escaped + cut, within 4 SE over seeds), and its
/// stored power agrees with band-by-band analog passes within 4 SE.
#[test]
fn refraction_with_band_dependent_index() {
    let light = Light::Point {
        position: Vec3::new(0.0, -6.0, 1.0),
        intensity: 1.0,
    };
    let grey = vec![Surface::Lambertian { reflectance: 0.4 }];
    let scenes = sphere_before_wall(5.0, light, &grey, &[1.5, 1.4, 1.6], |n| {
        vec![air(), medium(0.3, 2.0, 0.5, n)]
    });
    let runs = passes(&scenes, 20_000, StoreMode::Paper, 10);
    for (b, scene) in scenes.iter().enumerate() {
        let balance: Vec<f64> = (runs.iter())
            .map(|r| {
                let l = &r[b].ledger;
                l.emitted
                    - l.absorbed_medium.iter().sum::<f64>()
                    - l.absorbed_surface
                    - l.escaped
                    - l.cut
            })
            .collect();
        let (m, se) = mean_se(&balance);
        assert!(m.abs() < 4.0 * se + 1e-9, "band {b}: balance {m} ± {se}");
        let spectral: Vec<f64> = runs.iter().map(|r| r[b].ledger.stored_volume[1]).collect();
        let analog = analog_stored(scene, 20_000, 10);
        let ((ms, ss), (ma, sa)) = (mean_se(&spectral), mean_se(&analog));
        let z = (ms - ma) / (ss * ss + sa * sa).sqrt();
        assert!(
            z.abs() < 4.0,
            "band {b}: stored {ms} ± {ss} vs analog {ma} ± {sa}"
        );
    }
}

/// An aimed spectral pass (80 % of the photons into the sphere's cone) splits the photons
/// that reach the sphere unaimed, off the wall behind it (about 46 × an aimed photon's
/// power), into walks of an aimed photon's power; each band's stored power agrees with
/// band-by-band unaimed passes within 4 SE, and no band's map holds a photon far heavier
/// than its mean (the balance weights allow up to 3 × between bands; the bound of 10 leaves
/// room for the aimed photons' own spread over the light's area).
#[test]
fn aimed_spectral_pass_splits_heavy_photons() {
    let light = Light::Point {
        position: Vec3::new(0.0, -6.0, 1.0),
        intensity: 1.0,
    };
    let grey = vec![Surface::Lambertian { reflectance: 0.7 }];
    let sphere_medium = |mus: f64| vec![air(), medium(0.1, mus, 0.5, 1.4)];
    let first = sphere_before_wall(5.0, light, &grey, &[1.4], |_| sphere_medium(2.0));
    let scenes: Vec<Scene> = [2.0, 3.0, 1.5]
        .iter()
        .map(|&mus| {
            first[0]
                .with_band(sphere_medium(mus), grey.clone(), vec![light])
                .unwrap()
        })
        .collect();
    let aim = Aim::new(&scenes[0], 0.8).expect("the sphere is a target");
    let run = |aim: &Aim, scenes: &[Scene], seed: u64| {
        let emission = Emission {
            photons: 20_000,
            aim: Some(aim.clone()),
            ..Emission::default()
        };
        let control = Control::new();
        trace_emission_bands(
            scenes,
            &emission,
            StoreMode::Paper,
            Targets::BOTH,
            0,
            seed,
            0,
            &control,
        )
        .unwrap()
    };
    let heaviest = |maps: &PhotonMaps| {
        let v = &maps.volume[1];
        let mean = v.total_power() / v.len() as f64;
        v.photons()
            .iter()
            .map(|p| p.power as f64)
            .fold(0.0, f64::max)
            / mean
    };
    let split: Vec<Vec<PhotonMaps>> = (1..=10).map(|seed| run(&aim, &scenes, seed)).collect();
    let whole = run(&aim.clone().without_splitting(), &scenes, 1);
    for (b, scene) in scenes.iter().enumerate() {
        let top_split = split.iter().map(|r| heaviest(&r[b])).fold(0.0, f64::max);
        let top_whole = heaviest(&whole[b]);
        assert!(
            top_split < 10.0,
            "band {b}: heaviest photon {top_split} × the mean"
        );
        assert!(
            top_whole > 30.0,
            "band {b}: unsplit heaviest {top_whole} × the mean"
        );
        let spectral: Vec<f64> = split.iter().map(|r| r[b].ledger.stored_volume[1]).collect();
        let analog = analog_stored(scene, 40_000, 10);
        let ((ms, ss), (ma, sa)) = (mean_se(&spectral), mean_se(&analog));
        let z = (ms - ma) / (ss * ss + sa * sa).sqrt();
        eprintln!(
            "band {b}: stored {ms:.5} ± {ss:.5} (split; heaviest {top_split:.1} × the mean, \
             unsplit {top_whole:.0}) vs unaimed {ma:.5} ± {sa:.5}"
        );
        assert!(
            z.abs() < 4.0,
            "band {b}: stored {ms} ± {ss} vs unaimed {ma} ± {sa}"
        );
    }
}

/// A clear glass ball lens whose index differs per band (1.4 / 1.5 / 1.6) focuses a narrow
/// spot light towards a wall 3 mm behind its centre: the power landing within 0.3 mm of
/// the axis differs between the bands by many standard errors. The spectral pass gives
/// each band its own within 4 SE of band-by-band passes, which it can only do by refusing
/// walks another band's index refracts elsewhere.
#[test]
fn ball_lens_focus_per_band() {
    let spot = Light::spot("spot", Vec3::new(0.0, -30.0, 0.0), Vec3::Y, 1.0, 4.0, 0.0).unwrap();
    let scenes = sphere_before_wall(3.0, spot, &[Surface::Black], &[1.4, 1.5, 1.6], |n| {
        vec![air(), medium(0.05, 0.0, 0.0, n)]
    });
    let focus = Vec3::new(0.0, 3.0, 0.0);
    let near_focus = |m: &PhotonMaps| {
        (m.surface.photons().iter())
            .filter(|p| (p.position() - focus).length() < 0.3)
            .map(|p| p.power as f64)
            .sum::<f64>()
    };
    let runs = 10;
    let spectral = passes(&scenes, 30_000, StoreMode::Paper, runs);
    let mut means: Vec<(f64, f64)> = Vec::new();
    for (b, scene) in scenes.iter().enumerate() {
        let s: Vec<f64> = spectral.iter().map(|r| near_focus(&r[b])).collect();
        let a: Vec<f64> = (1..=runs)
            .map(|seed| {
                let one = std::slice::from_ref(scene);
                near_focus(&passes_seeded(one, 30_000, StoreMode::Paper, seed + 100)[0])
            })
            .collect();
        let ((ms, ss), (ma, sa)) = (mean_se(&s), mean_se(&a));
        let z = (ms - ma) / (ss * ss + sa * sa).sqrt();
        assert!(
            z.abs() < 4.0,
            "band {b}: focus power {ms} ± {ss} vs analog {ma} ± {sa}"
        );
        means.push((ma, sa));
    }
    // the scene tells the indices apart: the lowest and highest differ by many SE
    let ((m0, s0), (m2, s2)) = (means[0], means[2]);
    assert!(
        (m0 - m2).abs() > 8.0 * (s0 * s0 + s2 * s2).sqrt(),
        "{means:?}"
    );
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
/// ratio of band 1 to band 0) is lower than with correlated per-band passes (the same
/// streams in every band, the best the per-band passes do) by more than 4 standard errors
/// of the pixels' paired differences.
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
    // each pixel's colour noise: the sd over seeds of ln(band 1 / band 0) (None where a
    // run left the pixel dark)
    let colour_noise = |rs: &[Vec<Vec<f32>>], p: usize| {
        let ratios: Vec<f64> = (rs.iter())
            .filter(|r| r[0][p] > 0.0 && r[1][p] > 0.0)
            .map(|r| (r[1][p] as f64 / r[0][p] as f64).ln())
            .collect();
        (ratios.len() == rs.len()).then(|| mean_se(&ratios).1 * (ratios.len() as f64).sqrt())
    };
    // paired over pixels: spectral minus correlated, its mean and standard error
    let diffs: Vec<f64> = (0..spectral[0][0].len())
        .filter_map(|p| Some(colour_noise(&spectral, p)? - colour_noise(&correlated, p)?))
        .collect();
    let (d, d_se) = mean_se(&diffs);
    let mean_of = |rs: &[Vec<Vec<f32>>]| {
        let v: Vec<f64> = (0..rs[0][0].len())
            .filter_map(|p| colour_noise(rs, p))
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (cs, cc) = (mean_of(&spectral), mean_of(&correlated));
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
    eprintln!(
        "colour noise: spectral {cs:.4}, correlated bands {cc:.4}; paired {d:.4} ± {d_se:.4}"
    );
    assert!(
        d < -4.0 * d_se,
        "colour noise not lower: {d} ± {d_se} (spectral {cs}, correlated {cc})"
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

/// Progress: a spectral render counts its photons once and every band's pixels (what
/// `dentalux.render`'s bar expects), where band-by-band passes count the photons per band.
#[test]
fn progress_counts_photons_once() {
    let scenes = disc_bands();
    let s = Settings {
        integrator: Integrator::Vpm,
        spp: 1,
        photons: 1_000,
        volume_photons: 3_000,
        ..Settings::default()
    };
    let pixels = (16 * 12 * scenes.len()) as u64;
    for (spectral, photon_passes) in [(true, 1), (false, scenes.len() as u64)] {
        let control = Control::new();
        let settings = Settings {
            spectral_photons: spectral,
            ..s
        };
        render_bands(&scenes, &settings, &[1, 2, 3], &control).unwrap();
        assert_eq!(
            control.done(),
            settings.photons_traced() * photon_passes + pixels,
            "spectral {spectral}"
        );
    }
}

/// A spectral pass needs every band's lights in the same places (a walk starts on the
/// hero's light); band-by-band passes do not.
#[test]
fn spectral_lights_must_stay_in_place() {
    let scenes = disc_bands();
    let moved: Vec<Light> = (scenes[2].lights.iter())
        .map(|l| match *l {
            Light::Quad {
                corner,
                u,
                v,
                radiance,
            } => Light::Quad {
                corner: corner + Vec3::new(1.0, 0.0, 0.0),
                u,
                v,
                radiance,
            },
            other => other,
        })
        .collect();
    let third = scenes[0]
        .with_band(scenes[2].media.clone(), scenes[2].surfaces.clone(), moved)
        .unwrap();
    let bands = vec![scenes[0].clone(), scenes[1].clone(), third];
    let s = Settings {
        integrator: Integrator::Vpm,
        spp: 1,
        photons: 500,
        volume_photons: 1_000,
        spectral_photons: true,
        ..Settings::default()
    };
    let err = render_bands(&bands, &s, &[1, 2, 3], &Control::new()).unwrap_err();
    assert!(
        err.to_string()
            .contains("bands[2].lights[0] is not the light bands[0].lights[0] is"),
        "{err}"
    );
    let plain = Settings {
        spectral_photons: false,
        ..s
    };
    assert!(render_bands(&bands, &plain, &[1, 2, 3], &Control::new()).is_ok());
}
