//! Tests of the beam radiance estimate: the tree walk against brute force, and the
//! estimate's mean against its closed form in a uniform medium, with flat and tilted faces.

use super::beam::{biweight, biweight_fraction_inside, BeamMap, Face, Segment};
use super::tree::{Photon, PhotonMap};
use crate::math::Vec3;
use crate::phase::PhaseFunction;
use crate::rng::Stream;
use std::f64::consts::PI;

fn unit(s: &mut Stream) -> Vec3 {
    let z = 2.0 * s.uniform() - 1.0;
    let phi = 2.0 * PI * s.uniform();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `n` photons of power `w`, uniform in the cube [−h, h]³ on the inner side of `faces`.
fn uniform_photons(seed: u64, n: usize, h: f64, w: f64, faces: &[Face]) -> PhotonMap {
    let mut s = Stream::new(seed, 0, 0);
    let mut v = Vec::with_capacity(n);
    while v.len() < n {
        let x = Vec3::new(
            h * (2.0 * s.uniform() - 1.0),
            h * (2.0 * s.uniform() - 1.0),
            h * (2.0 * s.uniform() - 1.0),
        );
        if faces.iter().all(|(q, nrm)| (x - *q).dot(*nrm) < 0.0) {
            v.push(Photon::new(x, unit(&mut s), w));
        }
    }
    PhotonMap::build(v)
}

#[test]
fn the_tree_walk_finds_what_brute_force_finds() {
    let map = uniform_photons(3, 4000, 1.0, 1.0, &[]);
    let beams = BeamMap::build(&map, 0.2);
    let hg = PhaseFunction::HenyeyGreenstein { g: 0.6 };
    let mut s = Stream::new(5, 0, 1);
    for _ in 0..60 {
        let o = Vec3::new(s.uniform() - 0.5, s.uniform() - 0.5, s.uniform() - 0.5) * 2.0;
        let d = unit(&mut s);
        let exit = (o + d * 0.7, (d + unit(&mut s) * 0.3).normalize());
        let seg = Segment {
            o,
            d,
            t_end: 0.7,
            entry: Some((o, -d)),
            exit: Some(exit),
            sigma_t: 1.5,
            phase: &hg,
            clip: None,
        };
        let got = beams.estimate(&map, &seg);
        // brute force over every photon, with the radii the map computed: the disc in the
        // plane of the nearer face, met where the ray is at the photon's height over it
        let (mut want, mut count) = (0.0, 0usize);
        let faces = [(o, -d), exit];
        for p in map.photons() {
            let r = beams.radius();
            let x = p.position();
            let height = |f: &Face| (x - f.0).dot(f.1);
            if faces.iter().any(|f| height(f) >= 0.0) {
                continue;
            }
            let f = if height(&faces[0]).abs() <= height(&faces[1]).abs() {
                faces[0]
            } else {
                faces[1]
            };
            let (n, dn) = if d.dot(f.1).abs() >= 0.25 {
                (f.1, d.dot(f.1))
            } else {
                (d, 1.0)
            };
            let s = (x - o).dot(n) / dn;
            let off = x - o - d * s;
            if (0.0..=0.7).contains(&s) && off.dot(off) < r * r {
                want += biweight(off.dot(off), r * r) * (-1.5 * s).exp() / dn.abs()
                    * hg.eval(p.direction().dot(-d))
                    * p.power as f64;
                count += 1;
            }
        }
        assert_eq!(got.count, count);
        assert!(
            (got.value - want).abs() <= 1e-9 * want.max(1e-30),
            "{} vs {want}",
            got.value
        );
    }
}

#[test]
fn the_biweight_kernel_integrates_to_one_over_its_disc() {
    let (r, n) = (0.3, 20_000);
    let h = r / n as f64;
    let sum: f64 = (0..n)
        .map(|i| {
            let rho = (i as f64 + 0.5) * h;
            biweight(rho * rho, r * r) * 2.0 * PI * rho * h
        })
        .sum();
    assert!((sum - 1.0).abs() < 1e-6, "{sum}");
}

#[test]
fn the_kernel_fraction_inside_a_cut_disc_matches_its_integral() {
    let r = 0.5;
    // no face: all of it; a face through the centre: half, whatever the rotation
    assert!((biweight_fraction_inside(&[], r, 0.3) - 1.0).abs() < 1e-12);
    for u in [0.0, 0.37, 0.81] {
        let half = [(Vec3::ZERO, Vec3::new(0.6, 0.8, 0.0))];
        assert!((biweight_fraction_inside(&half, r, u) - 0.5).abs() < 0.01);
    }
    // a face at distance r/2: the kernel's mass beyond it by a fine 1-D quadrature of the
    // chord integral (x from r/2 to r)
    let face = [(Vec3::new(0.25, 0.0, 0.0), Vec3::X)];
    let n = 4000;
    let mut beyond = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (
                0.25 + 0.25 * (i as f64 + 0.5) / n as f64,
                -r + 2.0 * r * (j as f64 + 0.5) / n as f64,
            );
            beyond += biweight(x * x + y * y, r * r) * (0.25 / n as f64) * (2.0 * r / n as f64);
        }
    }
    let got = biweight_fraction_inside(&face, r, 0.2);
    assert!(
        (got - (1.0 - beyond)).abs() < 0.01,
        "{got} vs {}",
        1.0 - beyond
    );
}

/// Mean and standard error of the estimate over `sets` independent photon sets in a uniform
/// isotropic medium between `faces`, for the segment `seg_of(faces)`.
fn mean_over_sets(
    sets: u64,
    faces: &[Face],
    seg: impl Fn(&PhaseFunction) -> Segment<'_>,
    radius: f64,
) -> (f64, f64) {
    let iso = PhaseFunction::Isotropic;
    let values: Vec<f64> = (0..sets)
        .map(|k| {
            let map = uniform_photons(100 + k, 12_000, 0.6, 1.0, faces);
            let beams = BeamMap::build(&map, radius);
            beams.estimate(&map, &seg(&iso)).value
        })
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn the_estimate_matches_its_closed_form_in_a_uniform_medium() {
    // density ρ of photons of power 1 in the box (photons per mm³), phase 1/(4π): the
    // estimate's mean is ρ/(4π) ∫_0^T e^(−σt t) dt for a ray from inside the medium
    let (t_end, sigma_t) = (0.4, 2.0);
    let d = Vec3::new(0.0, 0.6, 0.8);
    let exit: Face = (d * t_end, d);
    let rho = 12_000.0 / (1.2f64.powi(3) * photon_fraction(&[exit]));
    let (mean, se) = mean_over_sets(
        60,
        &[exit],
        |phase| Segment {
            o: Vec3::ZERO,
            d,
            t_end,
            entry: None,
            exit: Some(exit),
            sigma_t,
            phase,
            clip: None,
        },
        0.08,
    );
    let want = rho / (4.0 * PI) * (1.0 - (-sigma_t * t_end).exp()) / sigma_t;
    assert!(se < 0.05 * want, "{se} vs {want}");
    assert!((mean - want).abs() < 4.0 * se, "{mean} ± {se} vs {want}");
}

#[test]
fn tilted_faces_leave_no_bias_in_a_dense_medium() {
    // the medium between two planes through the segment's ends, each tilted 60° from the
    // ray, so dense (σt r = 2) that a disc facing the ray would reach 0.17 mm below the
    // entry face where the camera sees 0.05 mm: the discs lying in the faces' planes keep
    // the mean at ρ/(4π) ∫ e^(−σt s) ds
    let (t_end, sigma_t, r) = (0.5, 20.0, 0.1);
    let d = Vec3::new(1.0, 0.0, 0.0);
    let c = Vec3::new(-0.5, 0.0, 0.0);
    let entry: Face = (c, Vec3::new(-0.5, 0.75f64.sqrt(), 0.0));
    let exit: Face = (c + d * t_end, Vec3::new(0.5, -(0.75f64.sqrt()), 0.0));
    let rho = 12_000.0 / (1.2f64.powi(3) * photon_fraction(&[entry, exit]));
    let (mean, se) = mean_over_sets(
        60,
        &[entry, exit],
        |phase| Segment {
            o: c,
            d,
            t_end,
            entry: Some(entry),
            exit: Some(exit),
            sigma_t,
            phase,
            clip: None,
        },
        r,
    );
    let want = rho / (4.0 * PI) * (1.0 - (-sigma_t * t_end).exp()) / sigma_t;
    assert!(se < 0.05 * want, "{se} vs {want}");
    assert!((mean - want).abs() < 4.0 * se, "{mean} ± {se} vs {want}");
}

/// Fraction of the cube [−0.6, 0.6]³ on the inner side of `faces` (a 2 M-point grid).
fn photon_fraction(faces: &[Face]) -> f64 {
    let n = 128;
    let mut inside = 0usize;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let g = |a: usize| 1.2 * (a as f64 + 0.5) / n as f64 - 0.6;
                let x = Vec3::new(g(i), g(j), g(k));
                inside += faces.iter().all(|(q, m)| (x - *q).dot(*m) < 0.0) as usize;
            }
        }
    }
    inside as f64 / (n * n * n) as f64
}
