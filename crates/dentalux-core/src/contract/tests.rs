//! The decoder's rules (tests/test_render_band.py checks the same through the binding): a valid scene and settings decode; bad input is refused with the key
//! path, unknown keys with the list of allowed ones (the messages Python users see).

use super::*;
use crate::geometry::Vec3;
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
        (scene.media.len(), scene.shapes().len(), scene.lights.len()),
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
        (json!({"surface_radius": 0.0}), "settings.surface_radius"),
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
    assert_eq!(get("surface_radius")["default"], Value::Null);
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

/// `shape_contains` of `shape` at `points`, unwrapped.
fn inside(shape: &Value, points: &[[f64; 3]]) -> Vec<bool> {
    let pts: Vec<Vec3> = points.iter().map(|p| Vec3::from_array(*p)).collect();
    shape_contains(&shape.to_string(), &pts).unwrap()
}

/// The unit cube [0, 1]³, outward-wound (tests/test_scene.py's CUBE_OBJ).
fn cube(boundary: Value) -> Value {
    json!({"type": "mesh",
           "positions": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                         [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
           "triangles": [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                         [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]],
           "boundary": boundary})
}

#[test]
fn analytic_shapes_contain_strictly() {
    let opaque = json!({"kind": "opaque", "surface": 0});
    let sphere = json!({"type": "sphere", "center": [0, 0, 1], "radius": 1.0,
                        "boundary": opaque});
    let got = inside(
        &sphere,
        &[[0.0, 0.0, 1.0], [0.0, 0.0, 1.99], [0.0, 0.0, 2.0]],
    );
    assert_eq!(got, [true, true, false]);
    let b = json!({"type": "box", "min": [0, 0, 0], "max": [1, 2, 3], "boundary": opaque});
    let got = inside(&b, &[[0.5, 1.0, 1.5], [1.0, 1.0, 1.5], [0.5, 2.5, 1.5]]);
    assert_eq!(got, [true, false, false]);
    // a non-unit axis is normalised, as in the scene
    let cyl = json!({"type": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 2], "radius": 1.0,
                     "height": 2.0, "boundary": opaque});
    let got = inside(&cyl, &[[0.9, 0.0, 1.0], [0.0, 0.0, 2.1], [1.1, 0.0, 1.0]]);
    assert_eq!(got, [true, false, false]);
    let quad = json!({"type": "quad", "corner": [0, 0, 0], "u": [1, 0, 0], "v": [0, 1, 0],
                      "boundary": opaque});
    assert_eq!(inside(&quad, &[[0.5, 0.5, 0.0]]), [false]);
}

#[test]
fn transformed_shapes_contain_in_world_space() {
    // 90° about x (object z -> world -y), then 5 mm along x
    let rot = json!([[1, 0, 0, 5], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]);
    let cyl = json!({"type": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1], "radius": 1.0,
                     "height": 2.0, "boundary": {"kind": "dielectric", "inside": 1, "outside": 0},
                     "transform": rot});
    let got = inside(
        &cyl,
        &[
            [5.0, -1.0, 0.5],
            [5.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [5.0, -1.0, 1.5],
        ],
    );
    assert_eq!(got, [true, false, false, false]);
    // a sphere stretched twice along x: an ellipsoid
    let stretch = json!([[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]);
    let ell = json!({"type": "sphere", "center": [0, 0, 0], "radius": 1.0,
                     "boundary": {"kind": "opaque", "surface": 0}, "transform": stretch});
    assert_eq!(
        inside(&ell, &[[1.9, 0.0, 0.0], [0.0, 1.1, 0.0]]),
        [true, false]
    );
}

#[test]
fn meshes_contain_only_when_watertight() {
    let opaque = json!({"kind": "opaque", "surface": 0});
    let mut m = cube(opaque.clone());
    // as tests/test_scene.py places it: scale 4, then to [-2, 2] x [-32, -28] x [8, 12]
    m["transform"] = json!([[4, 0, 0, -2], [0, 4, 0, -32], [0, 0, 4, 8], [0, 0, 0, 1]]);
    let got = inside(
        &m,
        &[[0.5, -29.5, 10.5], [0.5, -33.0, 10.5], [0.5, 0.5, 0.5]],
    );
    assert_eq!(got, [true, false, false]);
    let centre = [[0.5, 0.5, 0.5]];
    let mut open = cube(opaque.clone());
    open["triangles"].as_array_mut().unwrap().truncate(10);
    assert_eq!(inside(&open, &centre), [false]);
    // a vertex duplicated as along a uv seam: still a solid, even as a dielectric (whose
    // closedness by index is the scene decoder's check, not this one's)
    let mut seam = cube(json!({"kind": "dielectric", "inside": 7, "outside": 0}));
    seam["positions"]
        .as_array_mut()
        .unwrap()
        .push(json!([1, 1, 1]));
    seam["triangles"][2] = json!([4, 5, 8]);
    assert_eq!(inside(&seam, &centre), [true]);
    assert_eq!(inside(&seam, &[]), Vec::<bool>::new());
}

#[test]
fn a_lone_shape_is_refused_with_its_key_path() {
    let err = |s: &str| shape_contains(s, &[Vec3::ZERO]).unwrap_err().to_string();
    let sphere = json!({"type": "sphere", "center": [0, 0, 0], "radius": 1.0,
                        "boundary": {"kind": "opaque", "surface": 0}, "colour": 1});
    assert_eq!(
        err(&sphere.to_string()),
        "shape.colour: unknown key; allowed: boundary, center, radius, transform, type"
    );
    assert!(err("{").starts_with("shape JSON is malformed"));
    let got = err(r#"{"type": "sphere", "center": [0, 0, 0], "radius": -1,
                      "boundary": {"kind": "opaque", "surface": 0}}"#);
    assert!(got.starts_with("shape.radius"), "{got}");
    let mut m = cube(json!({"kind": "opaque", "surface": 0}));
    m["triangles"][0] = json!([0, 2, 9]);
    let got = err(&m.to_string());
    assert!(
        got.starts_with("shape.triangles[0] = [0, 2, 9] refers to a vertex"),
        "{got}"
    );
    let got = err(r#"{"type": "torus", "boundary": {"kind": "opaque", "surface": 0}}"#);
    assert!(got.starts_with("shape.type: \"torus\": allowed"), "{got}");
}

/// `sphere_scene` in the multi-band form: the same shapes, one band per `mua` of the glass.
fn band_scene(muas: &[f64]) -> Value {
    let one = sphere_scene();
    let bands: Vec<Value> = muas
        .iter()
        .map(|&mua| {
            let mut media = one["media"].clone();
            media[1]["mua"] = json!(mua);
            json!({"media": media, "surfaces": one["surfaces"], "lights": one["lights"]})
        })
        .collect();
    json!({"camera": one["camera"], "shapes": one["shapes"], "bands": bands})
}

fn band_scene_error(scene: &Value) -> String {
    match band_scenes_from_json(&scene.to_string()) {
        Ok(_) => panic!("decoded: {scene}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn band_scenes_share_their_geometry() {
    let scenes = band_scenes_from_json(&band_scene(&[0.01, 0.02, 0.5]).to_string()).unwrap();
    assert_eq!(scenes.len(), 3);
    assert!(scenes.iter().all(|s| s.shares_geometry(&scenes[0])));
    assert_eq!(
        scenes
            .iter()
            .map(|s| s.media[1].sigma_a)
            .collect::<Vec<_>>(),
        [0.01, 0.02, 0.5]
    );
    let single = scene_from_json(&sphere_scene().to_string()).unwrap();
    assert!(!single.shares_geometry(&scenes[0]));
    assert_eq!(single.eps, scenes[2].eps);
    assert_eq!(single.primitive_count(), scenes[2].primitive_count());
}

#[test]
fn bad_band_scenes_name_the_band() {
    let cases: Vec<(Edit, &str)> = vec![
        (|s| s["bands"] = json!([]), "bands: empty; at least one band is needed"),
        (
            |s| s["bands"][1]["media"][1]["mua"] = json!(-1.0),
            "bands[1].media[1]",
        ),
        (
            |s| {
                s["bands"][2]["media"].as_array_mut().unwrap().pop();
            },
            "bands[2].media has 1 entries and bands[0].media has 2: every band lists the same media",
        ),
        (
            |s| s["bands"][1]["lights"] = json!([]),
            "bands[1].lights has 0 entries and bands[0].lights has 1: every band lists the same lights",
        ),
        (
            |s| s["bands"][0]["lights"][0]["radiance"] = json!(0.0),
            "bands[0]: lights: total power is 0",
        ),
        (
            |s| s["bands"][2]["surfaces"][0]["a"] = json!(1.5),
            "bands[2].surfaces[0].a",
        ),
        (
            |s| s["bands"][0]["shapes"] = json!([]),
            "bands[0].shapes: unknown key",
        ),
        (
            |s| s["media"] = json!([]),
            "media: unknown key",
        ),
    ];
    for (edit, want) in cases {
        let mut s = band_scene(&[0.01, 0.02, 0.03]);
        edit(&mut s);
        let got = band_scene_error(&s);
        assert!(got.contains(want), "want {want:?} in {got:?}");
    }
}
