//! kd-tree build speed: `--photons` photons (default 4 M) spread like Fig. 3's disc maps (two
//! cylinders, density falling off from their tops), built on one thread and on all threads,
//! then `--queries` k-nearest queries (k = 300), then as many layer-kernel estimates (eq. 11
//! within 1 mm under the cylinders' tops, HG g = 0.75, the radius of the 300th neighbour).
//! Prints one JSON line; the build times are the best of `--reps`.
//!
//!     cargo run --release -p dentalux-core --example kd_bench -- [--photons 4000000]
//!         [--queries 100000] [--reps 5]
use dentalux_core::math::Vec3;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::photon_map::{Neighbours, Photon, PhotonMap, Planes};
use dentalux_core::rng::Stream;
use std::time::Instant;

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn photons(n: usize) -> Vec<Photon> {
    let mut rng = Stream::new(7, 0, 0);
    (0..n)
        .map(|i| {
            let cx = if i % 2 == 0 { -8.0 } else { 8.0 };
            let (r, phi) = (
                5.0 * rng.uniform().sqrt(),
                std::f64::consts::TAU * rng.uniform(),
            );
            let depth = -(1.0 - rng.uniform() * 0.99).ln() * 1.2;
            let pos = Vec3::new(cx + r * phi.cos(), r * phi.sin(), 5.0 - depth.min(5.0));
            let d = Vec3::new(
                rng.uniform() - 0.5,
                rng.uniform() - 0.5,
                rng.uniform() - 0.5,
            );
            Photon::new(pos, d.normalize(), 1e-6)
        })
        .collect()
}

fn main() {
    let n = arg("--photons", 4_000_000) as usize;
    let reps = arg("--reps", 5);
    let src = photons(n);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut best1 = f64::INFINITY;
    let mut best_all = f64::INFINITY;
    let mut map = PhotonMap::default();
    for _ in 0..reps {
        let v = src.clone();
        let t = Instant::now();
        let single = one.install(|| PhotonMap::build(v));
        assert_eq!(single.len(), n);
        best1 = best1.min(t.elapsed().as_secs_f64());
        let v = src.clone();
        let t = Instant::now();
        map = PhotonMap::build(v);
        best_all = best_all.min(t.elapsed().as_secs_f64());
    }
    let mut rng = Stream::new(9, 0, 0);
    let mut nb = Neighbours::new();
    let q = arg("--queries", 100_000);
    let t = Instant::now();
    let mut s = 0.0;
    for _ in 0..q {
        let x = Vec3::new(
            8.0 * (2.0 * rng.uniform() - 1.0),
            4.0 * (2.0 * rng.uniform() - 1.0),
            5.0 - rng.uniform(),
        );
        map.knn(x, 300, 10.0, &mut nb);
        s += nb.max_dist2() as f64;
    }
    let knn = t.elapsed().as_secs_f64() / q as f64;
    let mut rng = Stream::new(9, 0, 0);
    let queries: Vec<(Vec3, f64)> = (0..q)
        .map(|i| {
            // inside the cylinders, within a millimetre of their tops
            let cx = if i % 2 == 0 { -8.0 } else { 8.0 };
            let (r, phi) = (
                4.5 * rng.uniform().sqrt(),
                std::f64::consts::TAU * rng.uniform(),
            );
            let x = Vec3::new(cx + r * phi.cos(), r * phi.sin(), 5.0 - rng.uniform());
            map.knn(x, 300, 10.0, &mut nb);
            (x, (nb.max_dist2() as f64).sqrt())
        })
        .collect();
    let phase = PhaseFunction::HenyeyGreenstein { g: 0.75 };
    let wo = Vec3::new(0.3, -0.2, 0.9).normalize();
    let t = Instant::now();
    let mut layer_sum = 0.0;
    for &(x, r) in &queries {
        let planes = Planes {
            near: (Vec3::new(x.x, x.y, 5.0), Vec3::Z),
            far: None,
            clip: None,
        };
        layer_sum += map
            .volume_layer_at_radius(x, wo, &phase, r, 0.3, planes)
            .value;
    }
    let layer = t.elapsed().as_secs_f64() / q as f64;
    println!(
        "{{\"photons\": {n}, \"build_s_1thread\": {best1:.4}, \"build_s_all\": {best_all:.4}, \"knn_us\": {:.3}, \"layer_us\": {:.3}, \"check\": {s:.6e}, \"layer_check\": {layer_sum:.9e}}}",
        knn * 1e6,
        layer * 1e6
    );
}
