//! Profiling driver for the slab simulator's hot loop (run it under
//! `valgrind --tool=callgrind`, which counts instructions repeatably on a busy machine):
//!
//! ```text
//! cargo build --release --example slab_profile
//! valgrind --tool=callgrind target/release/examples/slab_profile dentin analog 20000 [threads]
//! ```
//!
//! Cases: `classic` (μa 1, μs 9, g 0.75, n 1, d 0.2 mm) and `dentin` (μa 0.04, μs 26,
//! g 0.9, n 1.54, d 2 mm). Runs on one thread (or the count given after the photons) and prints the totals with their standard errors and photons per second.

use dentalux_core::control::Control;
use dentalux_core::integrators::slab::{
    simulate, Estimator, Incidence, SlabConfig, SlabLayer, SCALAR_KEYS,
};
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let case = args.get(1).map_or("classic", String::as_str);
    let estimator = match args.get(2).map_or("analog", String::as_str) {
        "weighted" => Estimator::Weighted,
        _ => Estimator::Analog,
    };
    let photons: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let threads: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1);
    let (mua, mus, g, n, d) = match case {
        "dentin" => (0.04, 26.0, 0.9, 1.54, 2.0),
        _ => (1.0, 9.0, 0.75, 1.0, 0.2),
    };
    let phase = PhaseFunction::HenyeyGreenstein { g };
    let cfg = SlabConfig {
        layers: vec![SlabLayer {
            medium: Medium::new("", mua, mus, n, phase).expect("valid medium"),
            thickness: d,
        }],
        n_above: 1.0,
        n_below: 1.0,
        incidence: Incidence::Normal,
        estimator,
        n_photons: photons,
        seed: 1,
        band: 0,
        radial: None,
        angular_bins: None,
        window: None,
        backing_orders: None,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let start = Instant::now();
    let res = pool
        .install(|| simulate(&cfg, &Control::new()))
        .expect("simulation");
    let secs = start.elapsed().as_secs_f64();
    for (i, k) in SCALAR_KEYS.iter().enumerate() {
        println!("{k:28} {:.6} ± {:.6}", res.values[i], res.stderr[i]);
    }
    println!(
        "{photons} photons in {secs:.3} s: {:.0} photons/s",
        photons as f64 / secs
    );
}
