//! Print the distribution of stored photon powers per volume map (diagnostics).
use dentalux_core::contract::{scene_from_json, settings_from_json};
use dentalux_core::control::Control;
use dentalux_core::integrators::photon_trace::{trace_camera_maps, StoreMode};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = scene_from_json(&std::fs::read_to_string(&a[1]).unwrap()).unwrap();
    let (s, _) = settings_from_json(&std::fs::read_to_string(&a[2]).unwrap()).unwrap();
    let maps = trace_camera_maps(&scene, &s, StoreMode::Paper, 0, &Control::new()).unwrap();
    for (i, m) in maps.volume.iter().enumerate() {
        let mut p: Vec<f32> = m.photons().iter().map(|p| p.power).collect();
        if p.is_empty() {
            continue;
        }
        p.sort_by(|a, b| a.total_cmp(b));
        let n = p.len();
        let tot: f64 = p.iter().map(|&x| x as f64).sum();
        let mean = tot / n as f64;
        let q = |f: f64| p[((n as f64 - 1.0) * f) as usize] as f64 / mean;
        let top: f64 = p[n - n / 1000..].iter().map(|&x| x as f64).sum::<f64>() / tot;
        println!(
            "medium {i}: n {n} mean {mean:.3e}  p1 {:.3} p50 {:.3} p99 {:.3} p99.9 {:.3} max {:.3} (x mean); top 0.1% carry {:.3}",
            q(0.01), q(0.5), q(0.99), q(0.999), q(1.0), top
        );
    }
    let sp = maps.surface.photons();
    println!("surface: n {}", sp.len());
}
