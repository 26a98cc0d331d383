//! Tests of the photon map: records, queries and estimates against brute force and known
//! densities.

use super::kernel::rotated_circle;
use super::tree::dist2;
use super::*;
use crate::math::Vec3;
use crate::phase::PhaseFunction;
use std::f64::consts::PI;

/// The rotated circle of the clip quadratures equals direct sin_cos at every point.
#[test]
fn rotated_circle_matches_sin_cos() {
    for u in [0.0, 0.37, 0.999] {
        for (j, [c, s]) in rotated_circle::<32>(u).into_iter().enumerate() {
            let (s1, c1) = (2.0 * PI * (j as f64 + u) / 32.0).sin_cos();
            assert!((c - c1).abs() < 1e-12 && (s - s1).abs() < 1e-12, "{u} {j}");
        }
    }
}
use crate::rng::Stream;
use crate::sampling::uniform_sphere;

/// Mean and its standard error.
fn mean_se(vals: &[f64]) -> (f64, f64) {
    let m = vals.iter().sum::<f64>() / vals.len() as f64;
    let var = vals.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (vals.len() - 1) as f64;
    (m, (var / vals.len() as f64).sqrt())
}

/// The wall x = 0 as a scene's `hit` would report it (for the clip tests).
fn wall_at_x0(o: Vec3, d: Vec3, t_max: f64) -> Option<(Vec3, Vec3)> {
    let t = -o.x / d.x;
    (t > 0.0 && t < t_max).then(|| (o + d * t, Vec3::X))
}

fn random_map(n: usize, seed: u64, clustered: bool) -> Vec<Photon> {
    let mut s = Stream::new(seed, 0, 0);
    (0..n)
        .map(|i| {
            let mut p = Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 10.0;
            if clustered && i % 3 == 0 {
                p = Vec3::new(5.0, 5.0, 5.0) + (p - Vec3::splat(5.0)) * 0.01;
            }
            if clustered && i % 7 == 0 {
                p = Vec3::new(1.0, 2.0, 3.0); // exact duplicates
            }
            Photon::new(p, uniform_sphere(s.uniform2()), 1.0)
        })
        .collect()
}

#[test]
fn photon_is_compact_and_direction_roundtrips_and_batches() {
    const { assert!(PHOTON_BYTES <= 20) };
    let mut s = Stream::new(9, 0, 0);
    let mut worst: f64 = 0.0;
    let w = Vec3::new(0.3, -0.5, 0.8).normalize();
    let mut bits = Vec::new();
    let mut dots = Vec::new();
    for i in 0..20_000 {
        let d = match i {
            0 => Vec3::Z,
            1 => -Vec3::Z,
            2 => Vec3::X,
            3 => -Vec3::Y,
            _ => uniform_sphere(s.uniform2()),
        };
        let mut p = Photon::new(Vec3::new(1.0, -2.0, 3.0), d, 0.5);
        p.set_axis(2);
        worst = worst.max(p.direction().angle_between(d));
        assert_eq!(p.axis(), 2);
        bits.push(p.direction_bits());
        dots.push(p.direction().dot(w));
    }
    assert!(worst < 2e-4, "worst direction error {worst} rad");
    // the batch form the layer kernel uses gives the same numbers, bit for bit
    let mut cos = vec![0.0; bits.len()];
    super::tree::direction_cosines(&bits, w, &mut cos);
    assert!(cos
        .iter()
        .zip(&dots)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn knn_and_radius_equal_brute_force() {
    for clustered in [false, true] {
        let raw = random_map(5_000, 1 + clustered as u64, clustered);
        let map = PhotonMap::build(raw.clone());
        assert_eq!(map.len(), raw.len());
        let mut s = Stream::new(77, 0, 0);
        let mut nb = Neighbours::new();
        for qi in 0..300 {
            let x = if qi % 5 == 0 {
                Vec3::new(5.0, 5.0, 5.0)
            } else {
                Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 12.0 - Vec3::ONE
            };
            let q = [x.x as f32, x.y as f32, x.z as f32];
            let (k, r_max) = (1 + qi % 50, 0.5 + (qi % 4) as f64);
            // brute force: sorted distances within r_max
            let mut all: Vec<f32> = map
                .photons()
                .iter()
                .map(|p| dist2(&p.pos, &q))
                .filter(|&d2| d2 <= (r_max * r_max) as f32)
                .collect();
            all.sort_by(|a, b| a.total_cmp(b));
            map.knn(x, k, r_max, &mut nb);
            let mut got: Vec<f32> = nb.items().iter().map(|h| h.0).collect();
            got.sort_by(|a, b| a.total_cmp(b));
            all.truncate(k);
            assert_eq!(got, all, "knn mismatch at query {qi}");
            let mut count = 0;
            map.for_each_within(x, r_max, |_, _| count += 1);
            let brute = map
                .photons()
                .iter()
                .filter(|p| dist2(&p.pos, &q) <= (r_max * r_max) as f32)
                .count();
            assert_eq!(count, brute, "radius mismatch at query {qi}");
            // the box walk visits exactly the sphere's photons inside the box, in the
            // sphere walk's order (the layer kernel's sums stay bit-identical)
            let half = [0.2 + 0.1 * (qi % 3) as f64, 1.5, 0.05 * (qi % 5) as f64];
            let inside = |p: &Photon| (0..3).all(|i| (p.pos[i] - q[i]).abs() as f64 <= half[i]);
            let (mut sphere, mut boxed) = (Vec::new(), Vec::new());
            map.for_each_within(x, r_max, |p, _| {
                if inside(p) {
                    sphere.push(p.pos)
                }
            });
            map.for_each_within_box(x, r_max, half, |p, _| {
                if inside(p) {
                    boxed.push(p.pos)
                }
            });
            assert_eq!(sphere, boxed, "box walk mismatch at query {qi}");
        }
    }
}

/// The 27 points of a 3 × 3 × 3 grid, 2.5 mm apart, inside the 10 mm cube (x fastest last:
/// the order the estimates are summed in).
fn grid_points() -> Vec<Vec3> {
    let at = |i: usize| 2.5 + 2.5 * i as f64;
    (0..27)
        .map(|n| Vec3::new(at(n / 9), at(n / 3 % 3), at(n % 3)))
        .collect()
}

#[test]
fn density_estimates_recover_uniform_density() {
    // N photons of power Φ/N uniform in a 10 mm cube: density Φ/1000 per mm³
    let n = 200_000;
    let total = 3.0;
    let mut raw = random_map(n, 5, false);
    for p in &mut raw {
        p.power = (total / n as f64) as f32;
    }
    let map = PhotonMap::build(raw);
    let rho = total / 1000.0;
    let iso = PhaseFunction::Isotropic;
    // fixed radius: photon count in a ball is Poisson; query balls on a grid do not overlap
    let r = 1.0;
    let mut sum = 0.0;
    let mut count = 0usize;
    let mut m = 0;
    for x in grid_points() {
        let e = map.volume_sphere_at_radius(x, Vec3::Z, &iso, r);
        sum += e.value;
        count += e.count;
        m += 1;
    }
    let mean = sum / m as f64;
    let expect = rho / (4.0 * PI);
    let rel_se = 1.0 / (count as f64).sqrt();
    assert!(
        ((mean - expect) / expect).abs() < 4.0 * rel_se,
        "radius estimate {mean} vs {expect}"
    );
    // k-nearest: the estimate uses (k−1)/V_k, unbiased for a Poisson process, with
    // relative standard deviation ≈ 1/sqrt(k − 2); estimates at the 27 grid points are
    // independent (balls of radius ≈ 0.5 mm do not overlap)
    let k = 100;
    let mut nb = Neighbours::new();
    let mut sum = 0.0;
    for x in grid_points() {
        let e = map.volume_sphere_knn(x, Vec3::Z, &iso, k, 5.0, &mut nb);
        assert_eq!(e.count, k);
        sum += e.value;
    }
    let mean = sum / 27.0;
    let rel_se = 1.0 / ((k - 2) as f64).sqrt() / 27f64.sqrt();
    assert!(
        ((mean - expect) / expect).abs() < 4.0 * rel_se,
        "knn estimate {mean} vs {expect}"
    );
}

#[test]
fn layer_knn_with_a_smaller_radius_query_is_unbiased_for_a_uniform_density() {
    // The layer kernel's radius comes from the k/4-th neighbour, scaled to hold k photons
    // (`radius_query_k`): over 16 maps × 27 grid points (kernels far from the cube's faces
    // and from each other) the mean is the density within 4 standard errors (0.4 % at
    // k 200), for a plane far away (no cut) and for one cutting the kernel.
    let n = 200_000;
    let maps: Vec<PhotonMap> = (0..16)
        .map(|seed| {
            let mut raw = random_map(n, 100 + seed, false);
            for p in &mut raw {
                p.power = (1.0 / n as f64) as f32;
            }
            PhotonMap::build(raw)
        })
        .collect();
    let expect = 1.0 / 1000.0 / (4.0 * PI);
    let iso = PhaseFunction::Isotropic;
    let mut nb = Neighbours::new();
    for k in [200, 64] {
        for plane_offset in [50.0, 0.05] {
            let mut vals = Vec::new();
            for map in &maps {
                for x in grid_points() {
                    let planes = Planes {
                        near: (x + Vec3::Z * plane_offset, Vec3::Z),
                        far: None,
                        clip: None,
                    };
                    let e = map.volume_layer_knn(x, Vec3::Z, &iso, k, 5.0, 0.3, planes, &mut nb);
                    vals.push(e.value);
                }
            }
            let (m, se) = mean_se(&vals);
            assert!(
                (m - expect).abs() < 4.0 * se,
                "k {k}, plane {plane_offset} mm away: {m} ± {se} vs {expect}"
            );
            // the k/4 query still gathers about k photons: its noise is near k's
            assert!(
                se / m < 2.0 / ((k * vals.len()) as f64).sqrt(),
                "k {k}: s.e. {se}"
            );
        }
    }
}

#[test]
fn layer_estimate_follows_a_density_that_rises_with_depth() {
    // photons in z < 0 with density ∝ 1 + 0.3 |z| (z ∈ [−10, 0], 10 mm square): at and
    // near the plane z = 0 the sphere sees about half the density; the layer kernel
    // (k-NN and fixed radius), fitted where the plane cuts it, is right at every depth.
    // 4 independent maps × 16 queries far enough apart not to share photons.
    let n = 400_000;
    let a = 0.3;
    let norm = 10.0 + 50.0 * a;
    let maps: Vec<PhotonMap> = (0..4)
        .map(|seed| {
            let mut s = Stream::new(29, 0, seed);
            // inverse CDF of 1 + a t on [0, 10]: F(t) = (t + a t²/2) / (10 + 50 a)
            PhotonMap::build(
                (0..n)
                    .map(|_| {
                        let c = s.uniform() * norm;
                        let t = ((1.0 + 2.0 * a * c).sqrt() - 1.0) / a;
                        let p = Vec3::new(s.uniform() * 10.0, s.uniform() * 10.0, -t);
                        Photon::new(p, uniform_sphere(s.uniform2()), 1.0 / n as f64)
                    })
                    .collect(),
            )
        })
        .collect();
    let iso = PhaseFunction::Isotropic;
    let mut nb = Neighbours::new();
    let planes = Planes {
        near: (Vec3::ZERO, Vec3::Z),
        far: None,
        clip: None,
    };
    for layer in [0.2, 0.5] {
        for depth in [0.0, 0.02, 0.1, 0.5] {
            // photons per mm³ at depth d: n (1 + a d) / (100 norm), each of power 1/n
            let expect = (1.0 + a * depth) / (100.0 * norm) / (4.0 * PI);
            let (mut knn, mut fixed, mut sphere) = (Vec::new(), Vec::new(), Vec::new());
            for map in &maps {
                for q in 0..16 {
                    let x = Vec3::new(
                        1.7 + 2.2 * (q % 4) as f64,
                        1.7 + 2.2 * (q / 4) as f64,
                        -depth,
                    );
                    let e =
                        map.volume_layer_knn(x, Vec3::Z, &iso, 100, 5.0, layer, planes, &mut nb);
                    knn.push(e.value);
                    fixed.push(
                        map.volume_layer_at_radius(x, Vec3::Z, &iso, 0.5, layer, planes)
                            .value,
                    );
                    sphere.push(
                        map.volume_sphere_knn(x, Vec3::Z, &iso, 100, 5.0, &mut nb)
                            .value,
                    );
                }
            }
            for (name, vals) in [("k-NN", &knn), ("fixed radius", &fixed)] {
                let (m, se) = mean_se(vals);
                assert!(
                    (m - expect).abs() < 4.0 * se,
                    "{name}, layer {layer}, depth {depth}: {m} ± {se} vs {expect}"
                );
            }
            if depth == 0.0 {
                let m = mean_se(&sphere).0;
                assert!(m < 0.7 * expect, "sphere at the plane: {m} vs {expect}");
            }
        }
    }
}

/// The clip tests' verdict: the clipped estimates' mean is `expect` within 4 standard
/// errors, the plain estimates' mean lies beyond 4 of theirs on the side `sign` (−1: too
/// dark, +1: too bright).
fn assert_clip_corrects(plain: &[f64], clipped: &[f64], expect: f64, sign: f64) {
    let (m, se) = mean_se(clipped);
    assert!(
        (m - expect).abs() < 4.0 * se,
        "clipped: {m} ± {se} vs {expect}"
    );
    let (m0, se0) = mean_se(plain);
    assert!(
        sign * (m0 - expect) > 4.0 * se0,
        "plain: {m0} ± {se0} vs {expect}"
    );
}

/// Four maps, map i built from `photons(Stream::new(seed, 0, i))`.
fn four_maps(seed: u64, photons: impl Fn(&mut Stream) -> Vec<Photon>) -> Vec<PhotonMap> {
    (0..4)
        .map(|i| PhotonMap::build(photons(&mut Stream::new(seed, 0, i))))
        .collect()
}

/// The clip tests' points: 16 per map, 0.05 mm outside the wall x = 0 ([`wall_at_x0`]),
/// y from −4 to 3.5 mm, height `z`; `estimate(map, x, clip)` returns the plain and the
/// clipped estimate there, the clip rotated by a uniform from `Stream::new(seed, 0, 0)`.
fn along_the_wall(
    maps: &[PhotonMap],
    z: f64,
    seed: u64,
    mut estimate: impl FnMut(&PhotonMap, Vec3, &KernelClip) -> (f64, f64),
) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Stream::new(seed, 0, 0);
    let (mut plain, mut clipped) = (Vec::new(), Vec::new());
    for map in maps {
        for q in 0..16 {
            let x = Vec3::new(0.05, -4.0 + 0.5 * q as f64, z);
            let clip = KernelClip {
                hit: &wall_at_x0,
                u: rng.uniform(),
            };
            let (a, b) = estimate(map, x, &clip);
            plain.push(a);
            clipped.push(b);
        }
    }
    (plain, clipped)
}

#[test]
fn clipped_layer_kernel_is_right_at_a_rim() {
    // uniform photons in the quarter-space x > 0, z < 0 (a disc's rim: top face z = 0,
    // side wall x = 0), 10 × 10 × 10 mm. At points 0.05 mm from both faces the layer
    // kernel, cut by the top plane only, counts over a volume of which about half lies
    // beyond the wall: too dark by far more than its noise. Clipped by the wall's plane
    // (found by the clip's rays) it is right within 4 standard errors (4 maps × 16
    // points).
    let n = 400_000;
    let maps = four_maps(31, |s| {
        (0..n)
            .map(|_| {
                let p = Vec3::new(s.uniform(), s.uniform() - 0.5, -s.uniform()) * 10.0;
                Photon::new(p, uniform_sphere(s.uniform2()), 1.0 / n as f64)
            })
            .collect()
    });
    let expect = 1.0 / 1000.0 / (4.0 * PI);
    let iso = PhaseFunction::Isotropic;
    let mut nb = Neighbours::new();
    let (plain, clipped) = along_the_wall(&maps, -0.05, 5, |map, x, clip| {
        let mut planes = Planes {
            near: (Vec3::new(x.x, x.y, 0.0), Vec3::Z),
            far: None,
            clip: None,
        };
        let e = map.volume_layer_knn(x, Vec3::Z, &iso, 100, 5.0, 0.3, planes, &mut nb);
        planes.clip = Some(*clip);
        let c = map.volume_layer_knn(x, Vec3::Z, &iso, 100, 5.0, 0.3, planes, &mut nb);
        (e.value, c.value)
    });
    // too dark unclipped
    assert_clip_corrects(&plain, &clipped, expect, -1.0);
}

#[test]
fn clipped_surface_estimate_ignores_light_beyond_a_standing_face() {
    // photons on the plane z = 0 arriving from above, 10× denser for x < 0 (under a disc
    // that stands on the plane; its wall is x = 0). 0.05 mm outside the wall the plain
    // k-NN disc takes in the dense side and reads high; clipped by the wall it is right
    // within 4 standard errors (4 maps × 16 points).
    let n_out = 200_000;
    let maps = four_maps(37, |s| {
        let mut v = Vec::new();
        for (x0, count) in [(0.0, n_out), (-10.0, 10 * n_out)] {
            for _ in 0..count {
                let p = Vec3::new(x0 + 10.0 * s.uniform(), 10.0 * s.uniform() - 5.0, 0.0);
                v.push(Photon::new(p, -Vec3::Z, 1.0 / n_out as f64));
            }
        }
        v
    });
    let expect = 1.0 / 100.0; // irradiance outside: power per mm²
    let mut nb = Neighbours::new();
    let (plain, clipped) = along_the_wall(&maps, 0.0, 6, |map, x, clip| {
        let e = map.irradiance_disc_knn(x, Vec3::Z, 100, 5.0, &mut nb).value;
        let c = map.irradiance_clipped_disc_knn(x, Vec3::Z, 100, 5.0, &mut nb, clip);
        (e, c.value)
    });
    // too bright unclipped
    assert_clip_corrects(&plain, &clipped, expect, 1.0);
}

#[test]
fn surface_irradiance_of_uniform_flux() {
    // photons hitting the plane z = 0 from above, flux density E per mm²
    let n = 100_000;
    let e_true = 2.0;
    let side = 10.0;
    let mut s = Stream::new(11, 0, 0);
    let power = e_true * side * side / n as f64;
    let raw: Vec<Photon> = (0..n)
        .map(|_| {
            let p = Vec3::new(s.uniform() * side, s.uniform() * side, 0.0);
            Photon::new(p, -Vec3::Z, power)
        })
        .collect();
    let map = PhotonMap::build(raw);
    let mut nb = Neighbours::new();
    let e = map.irradiance_disc_knn(Vec3::new(5.0, 5.0, 0.0), Vec3::Z, 400, 3.0, &mut nb);
    // relative sd ≈ 1/sqrt(k)
    let v = e.value;
    assert!(((v - e_true) / e_true).abs() < 4.0 / 398f64.sqrt(), "{v}");
    // back-facing photons are ignored
    let e_back = map.irradiance_disc_knn(Vec3::new(5.0, 5.0, 0.0), -Vec3::Z, 400, 3.0, &mut nb);
    assert_eq!(e_back.count, 0);
}

/// Throughput figures for the report (slow: run with `--ignored --nocapture`).
#[test]
#[ignore]
fn query_throughput() {
    let n = 4_000_000;
    let raw = random_map(n, 31, false);
    let t = std::time::Instant::now();
    let map = PhotonMap::build(raw);
    let build = t.elapsed().as_secs_f64();
    println!("{n} photons: build {build:.2} s");
    // r_max: twice the radius holding k photons at this density (the camera pass's default)
    for k in [64usize, 200] {
        let r_max = 2.0 * (3.0 * k as f64 * 1000.0 / (4.0 * PI * n as f64)).cbrt();
        let mut s = Stream::new(32, 0, 0);
        let mut nb = Neighbours::new();
        let q = 200_000;
        let t = std::time::Instant::now();
        let mut found = 0;
        for _ in 0..q {
            let x = Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 10.0;
            map.knn(x, k, r_max, &mut nb);
            found += nb.len();
        }
        let knn = t.elapsed().as_secs_f64();
        println!(
            "k = {k} (r_max {r_max:.3} mm) queries {:.2} µs each ({found} found)",
            knn / q as f64 * 1e6
        );
    }
    // the camera pass's volume estimate at the paper's k: the k-NN query, then the layer
    // kernel's phase-weighted sum (HG g = 0.75) over a face 0.2 mm above each point
    let (k, q) = (800usize, 50_000);
    let r_max = 2.0 * (3.0 * k as f64 * 1000.0 / (4.0 * PI * n as f64)).cbrt();
    let hg = PhaseFunction::HenyeyGreenstein { g: 0.75 };
    let mut nb = Neighbours::new();
    let points: Vec<Vec3> = {
        let mut s = Stream::new(33, 0, 0);
        (0..q)
            .map(|_| Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 8.0 + Vec3::splat(1.0))
            .collect()
    };
    let t = std::time::Instant::now();
    for &x in &points {
        map.knn(x, k, r_max, &mut nb);
    }
    let knn = t.elapsed().as_secs_f64() / q as f64;
    let t = std::time::Instant::now();
    let mut sum = 0.0;
    for &x in &points {
        let planes = Planes {
            near: (x + Vec3::Z * 0.2, Vec3::Z),
            far: None,
            clip: None,
        };
        sum += (map.volume_layer_knn(x, Vec3::Z, &hg, k, r_max, 0.3, planes, &mut nb)).value;
    }
    let layer = t.elapsed().as_secs_f64() / q as f64;
    println!(
        "k = {k}: k-NN {:.2} µs, k-NN + layer estimate {:.2} µs per query (mean {:.4})",
        knn * 1e6,
        layer * 1e6,
        sum / q as f64
    );
}

/// Photons scattered uniformly (a Poisson-like process) on the plane z = 0 with density
/// ρ: the estimate averages to ρ·ΔΦ. With k = 8, counting the k-th photon as well would be
/// k/(k − 1) = 14 % too high, far outside the 4 standard errors allowed here. Photons that
/// arrive from below (the back side) or lie off the plane (a wall) must not count.
#[test]
fn flattened_disc_irradiance_is_unbiased_on_a_uniform_plane() {
    let mut rng = Stream::new(21, 0, 0);
    let (side, n) = (100.0, 100_000);
    let down = Vec3::new(0.3, 0.0, -1.0).normalize();
    let mut photons: Vec<Photon> = (0..n)
        .map(|_| {
            Photon::new(
                Vec3::new(rng.uniform(), rng.uniform(), 0.0) * side,
                down,
                1.0,
            )
        })
        .collect();
    // the same number arriving at the back side, and a wall of photons at z ≥ 0.3 mm
    for _ in 0..n {
        let p = Vec3::new(rng.uniform(), rng.uniform(), 0.0) * side;
        photons.push(Photon::new(p, -down, 1.0));
        let w = Vec3::new(rng.uniform() * side, 50.0, 0.3 + rng.uniform() * 5.0);
        photons.push(Photon::new(w, down, 1.0));
    }
    let map = PhotonMap::build(photons);
    let density = n as f64 / (side * side);
    let k = 8;
    let mut nb = Neighbours::new();
    // a grid of query points 1.25 mm apart (r ≈ 0.5 mm): nearly independent estimates,
    // away from the wall at y = 50
    let mut vals = Vec::new();
    for i in 0..72 {
        for j in 0..72 {
            let y = 5.0 + j as f64 * 1.25;
            if (y - 50.0).abs() < 2.0 {
                continue;
            }
            let x = Vec3::new(5.0 + i as f64 * 1.25, y, 0.0);
            vals.push(
                map.irradiance_flattened_disc_knn(x, Vec3::Z, k, 10.0, &mut nb)
                    .value,
            );
        }
    }
    let (m, se) = mean_se(&vals);
    assert!((m - density).abs() < 4.0 * se, "{m} vs {density} ± {se}");
    assert!(se < 0.02 * density);
    // right at the foot of the wall (whose photons are 20× denser, from 0.3 mm up) the disc
    // filter keeps them out: the estimate still averages to the floor's density
    let foot: Vec<f64> = (0..360)
        .map(|i| {
            let x = Vec3::new(5.0 + i as f64 * 0.25, 50.0, 0.0);
            map.irradiance_flattened_disc_knn(x, Vec3::Z, k, 10.0, &mut nb)
                .value
        })
        .collect();
    let (m, se) = mean_se(&foot);
    assert!(
        (m - density).abs() < 4.0 * se,
        "at the wall: {m} vs {density} ± {se}"
    );
}

/// A build asked to stop (Ctrl-C during a large map's build) ends with `Cancelled`; one not
/// asked to stop is the plain build's tree.
#[test]
fn try_build_stops_when_cancelled_and_is_build_otherwise() {
    let mut rng = Stream::new(4, 0, 0);
    let photons: Vec<Photon> = (0..200_000)
        .map(|_| Photon::new(uniform_sphere(rng.uniform2()) * 3.0, Vec3::Z, 1.0))
        .collect();
    let control = crate::control::Control::new();
    let built = PhotonMap::try_build(photons.clone(), &control).unwrap();
    let plain = PhotonMap::build(photons.clone());
    assert!(built
        .photons()
        .iter()
        .zip(plain.photons())
        .all(|(a, b)| a.position() == b.position()));
    control.cancel();
    let e = PhotonMap::try_build(photons, &control).unwrap_err();
    assert!(matches!(e, crate::Error::Cancelled));
}
