//! The decoder's rules (tests/test_render_band.py checks the same through the binding): a valid scene and settings decode; bad input is refused with the key
//! path, unknown keys with the list of allowed ones (the messages Python users see).

use super::*;
use serde_json::json;

/// A glass sphere in air on a checker floor under a disc light, camera looking down.
fn sphere_scene() -> Value {
    let camera = json!({"position": [0, 0, 10], "look_at": [0, 0, 0], "up": [0, 1, 0],
                        "fov_deg": 30.0, "width": 12, "height": 8});
    let glass = json!({"name": "glass", "mua": 0.01, "mus": 0.0, "n": 1.5});
    let sphere = json!({"type": "sphere", "center": [0, 0, 1], "radius": 1.0,
                        "boundary": {"kind": "dielectric", "inside": 1, "outside": 0}});
    let floor = json!({"type": "quad", "corner": [-50, -50, 0], "u": [100, 0, 0],
                       "v": [0, 100, 0], "boundary": {"kind": "opaque", "surface": 0}});
    let light = json!({"type": "disc", "center": [0, 0, 8], "normal": [0, 0, -1],
                       "radius": 2.0, "radiance": 5.0});
    json!({
        "camera": camera,
        "media": [{"mua": 0.0, "mus": 0.0, "n": 1.0}, glass],
        "surfaces": [{"type": "checker", "a": 0.8, "b": 0.1, "size": 2.0, "mapping": "xy"}],
        "shapes": [sphere, floor],
        "lights": [light],
    })
}

/// The error message of decoding `scene` (panics if it decodes).
fn scene_error(scene: &Value) -> String {
    match scene_from_json(&scene.to_string()) {
        Ok(_) => panic!("decoded: {scene}"),
        Err(e) => e.to_string(),
    }
}

/// The error message of decoding `settings` (panics if it decodes).
fn settings_error(settings: Value) -> String {
    match settings_from_json(&settings.to_string()) {
        Ok(_) => panic!("decoded: {settings}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_valid_scene_decodes() {
    let scene = scene_from_json(&sphere_scene().to_string()).unwrap();
    assert_eq!((scene.camera.width, scene.camera.height), (12, 8));
    assert_eq!(
        (scene.media.len(), scene.shapes.len(), scene.lights.len()),
        (2, 2, 1)
    );
}

/// A change to a valid scene.
type Edit = fn(&mut Value);

#[test]
fn bad_scenes_name_the_key() {
    let cases: Vec<(Edit, &str)> = vec![
        (
            |s| s["shapes"][0]["colour"] = json!(1),
            "shapes[0].colour: unknown key; allowed: boundary, center, radius, transform, type",
        ),
        (
            |s| s["shapes"][1]["boundary"]["surface"] = json!(3),
            "shapes[1].boundary.surface = 3 is out of range: 1 surfaces defined (indices 0..1)",
        ),
        (
            |s| s["camera"]["fov_deg"] = json!("wide"),
            "camera.fov_deg: expected a finite number, got a string",
        ),
        (
            |s| {
                s["camera"]
                    .as_object_mut()
                    .unwrap()
                    .remove("up")
                    .map(drop)
                    .unwrap()
            },
            "camera.up is missing (required)",
        ),
        (
            |s| s["lights"][0]["type"] = json!("laser"),
            "lights[0].type: \"laser\": allowed \"quad\", \"disc\", \"point\", \"spot\"",
        ),
        (
            |s| s["shapes"][1]["corner"] = json!([0, 0]),
            "shapes[1].corner: expected a list of 3 numbers, got 2 entries",
        ),
        (
            |s| s["ambient_medium"] = json!(2),
            "ambient_medium = 2 is out of range: 2 media defined",
        ),
        (
            |s| s["media"][1]["phase"] = json!({"g": 1.5}),
            "media[1].phase.g",
        ),
        (|s| s["media"][0]["mua"] = json!(-1.0), "media[0].mua"),
    ];
    for (edit, message) in cases {
        let mut scene = sphere_scene();
        edit(&mut scene);
        let got = scene_error(&scene);
        assert!(got.contains(message), "{got:?} lacks {message:?}");
    }
}

#[test]
fn malformed_json_is_refused() {
    let got = scene_from_json("{").err().unwrap().to_string();
    assert!(got.starts_with("scene JSON is malformed"), "{got}");
    let got = settings_from_json("[1").err().unwrap().to_string();
    assert!(got.starts_with("settings JSON is malformed"), "{got}");
    let got = camera_from_json("").err().unwrap().to_string();
    assert!(got.starts_with("camera JSON is malformed"), "{got}");
}

#[test]
fn settings_default_to_the_cores_and_name_bad_keys() {
    let (s, threads) = settings_from_json("{}").unwrap();
    assert_eq!((s, threads), (Settings::default(), None));
    let (s, threads) =
        settings_from_json(r#"{"integrator": "vpm-full", "spp": 3, "threads": 2}"#).unwrap();
    assert_eq!(
        (s.integrator, s.spp, threads),
        (Integrator::VpmFull, 3, Some(2))
    );
    for (settings, message) in [
        (
            json!({"integrator": "magic"}),
            "settings.integrator = \"magic\": allowed",
        ),
        (
            json!({"spp": 0}),
            "settings.spp = 0 is out of range: allowed ≥ 1",
        ),
        (json!({"radius": -1.0}), "settings.radius"),
        (
            json!({"sp": 3}),
            "settings.sp: unknown key; allowed: aim, alpha,",
        ),
        (
            json!({"kernel_clip": 1}),
            "settings.kernel_clip: expected true or false, got a number",
        ),
        (
            json!({"spp": 1u64 << 33}),
            "settings.spp = 8589934592 is too large",
        ),
        (
            json!({"seed": -1}),
            "settings.seed: expected a non-negative integer, got -1",
        ),
    ] {
        let got = settings_error(settings);
        assert!(got.contains(message), "{got:?} lacks {message:?}");
    }
}

#[test]
fn the_camera_decodes_alone() {
    let cam = camera_from_json(&sphere_scene()["camera"].to_string()).unwrap();
    assert_eq!((cam.width, cam.height), (12, 8));
    let got = camera_from_json(r#"{"position": [0, 0, 1]}"#)
        .err()
        .unwrap()
        .to_string();
    assert_eq!(got, "camera.look_at is missing (required)");
}

#[test]
fn the_schema_lists_every_key_with_the_cores_defaults() {
    let schema: Value = serde_json::from_str(&settings_schema()).unwrap();
    let keys = schema["keys"].as_array().unwrap();
    assert_eq!(keys.len(), KEYS.len());
    let get = |name: &str| keys.iter().find(|k| k["name"] == name).unwrap().clone();
    let d = Settings::default();
    assert_eq!(get("spp")["default"], json!(d.spp));
    assert_eq!(get("spp")["lo"], json!(1));
    assert_eq!(get("kernel_layer")["default"], json!(d.kernel_layer));
    assert_eq!(get("alpha")["lo_open"], json!(true));
    assert_eq!(get("radius")["default"], Value::Null);
    assert_eq!(schema["max_passes"], json!(MAX_PASSES));
    let names: Vec<&str> = (schema["integrators"].as_array().unwrap().iter())
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "pm",
            "path",
            "vpm",
            "vpm-full",
            "volpath",
            "volpath-nee",
            "ppm",
            "bre"
        ]
    );
    assert_eq!(get("volume_estimator")["default"], json!("points"));
    assert_eq!(get("volume_estimator")["values"], json!(["points", "beam"]));
    // every key the schema names is one the decoder reads: a settings object of all the
    // defaults decodes to the default settings
    let all: serde_json::Map<String, Value> = keys
        .iter()
        .map(|k| {
            (
                k["name"].as_str().unwrap().to_string(),
                k["default"].clone(),
            )
        })
        .collect();
    let (s, threads) = settings_from_json(&Value::Object(all).to_string()).unwrap();
    assert_eq!((s, threads), (d, None));
}

#[test]
fn photons_traced_follows_the_integrator() {
    let s = |integrator, volume_stored| Settings {
        integrator,
        photons: 10,
        volume_photons: 100,
        volume_stored,
        ..Settings::default()
    };
    assert_eq!(s(Integrator::Path, 0).photons_traced(), 0);
    assert_eq!(s(Integrator::Pm, 0).photons_traced(), 10);
    assert_eq!(s(Integrator::Vpm, 0).photons_traced(), 110);
    assert_eq!(s(Integrator::Ppm, 40).photons_traced(), 50);
}
