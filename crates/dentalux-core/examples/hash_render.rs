//! Render a scene JSON + settings JSON and print a hash of the image bits (bit-identity checks).
use dentalux_core::contract::{scene_from_json, settings_from_json};
use dentalux_core::control::Control;
use dentalux_core::integrators::render::render_band;
use std::hash::{Hash, Hasher};
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = scene_from_json(&std::fs::read_to_string(&a[1]).unwrap()).unwrap();
    let (s, _) = settings_from_json(&std::fs::read_to_string(&a[2]).unwrap()).unwrap();
    let (img, _) = render_band(&scene, &s, &Control::new()).unwrap();
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for v in &img {
        v.to_bits().hash(&mut h);
    }
    println!("{} {:016x}", a[2], h.finish());
}
