//! The distribution of stored photon powers in each volume map of a `vpm` pass: heavy
//! photons (a few carrying much of the power) show as kernel-sized blotches in a render.
//!
//!     cargo run --release -p dentalux-core --example photon_powers -- SCENE.json SETTINGS.json
//!
//! (the scene and settings JSON of the render contract, e.g. from benchmarks/hash_renders.py
//! --inputs DIR).
use dentalux_core::contract::{scene_from_json, settings_from_json};
use dentalux_core::control::Control;
use dentalux_core::integrators::photon_trace::{trace_camera_maps, StoreMode};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, scene_path, settings_path] = &args[..] else {
        eprintln!("usage: photon_powers SCENE.json SETTINGS.json");
        std::process::exit(2);
    };
    let read = |p: &str| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{p}: {e}"));
    let scene = scene_from_json(&read(scene_path)).expect("scene");
    let (settings, _) = settings_from_json(&read(settings_path)).expect("settings");
    let maps = trace_camera_maps(&scene, &settings, StoreMode::Paper, 0, &Control::new())
        .expect("photon pass");
    for (medium, map) in maps.volume.iter().enumerate() {
        let mut powers: Vec<f64> = map.photons().iter().map(|p| p.power as f64).collect();
        if powers.is_empty() {
            continue;
        }
        powers.sort_by(f64::total_cmp);
        let n = powers.len();
        let total: f64 = powers.iter().sum();
        let mean = total / n as f64;
        let at = |q: f64| powers[((n - 1) as f64 * q) as usize] / mean;
        let heaviest = (n / 1000).max(1);
        let share = powers[n - heaviest..].iter().sum::<f64>() / total;
        println!(
            "medium {medium}: {n} photons, mean power {mean:.3e}; over the mean: 1 % {:.3}, \
             50 % {:.3}, 99 % {:.3}, 99.9 % {:.3}, max {:.3}; the heaviest {heaviest} carry \
             {:.2} % of the power",
            at(0.01),
            at(0.5),
            at(0.99),
            at(0.999),
            at(1.0),
            100.0 * share
        );
    }
}
