//! Binding of `render_band`: the resolved scene and the settings arrive as JSON strings
//! (docs/render-contract.md), are read into core types with every error naming its key path
//! (`shapes[2].radius`), and the band is rendered off the GIL through [`runner::run`].

use crate::runner;
use dentalux_core::camera::Camera;
use dentalux_core::geometry::mesh::TriangleMesh;
use dentalux_core::geometry::shapes::{BoxShape, Cylinder, Quad, Sphere};
use dentalux_core::geometry::transform::Transform;
use dentalux_core::geometry::Vec3;
use dentalux_core::integrators::render::render_band as core_render;
use dentalux_core::integrators::settings::{Integrator, Settings, Stats};
use dentalux_core::lights::Light;
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::scene::{Boundary, Geometry, Scene, ShapeInstance};
use dentalux_core::surface::{Mapping, Surface};
use dentalux_core::Error;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::{Map, Value};

type R<T> = Result<T, Error>;

fn bad<T>(msg: String) -> R<T> {
    Err(Error::InvalidInput(msg))
}

/// A JSON value with the key path that led to it.
#[derive(Clone, Copy)]
struct Node<'a> {
    v: &'a Value,
    path: &'a str,
}

/// An object whose keys are read one by one; unknown keys are refused at the end.
struct Obj<'a> {
    map: &'a Map<String, Value>,
    path: String,
    seen: Vec<&'static str>,
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

impl<'a> Node<'a> {
    fn num(self) -> R<f64> {
        match self.v.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => bad(format!(
                "{}: expected a finite number, got {}",
                self.path,
                kind(self.v)
            )),
        }
    }
    fn uint(self) -> R<u64> {
        self.v.as_u64().map_or_else(
            || {
                bad(format!(
                    "{}: expected a non-negative integer, got {}",
                    self.path, self.v
                ))
            },
            Ok,
        )
    }
    fn boolean(self) -> R<bool> {
        self.v.as_bool().map_or_else(
            || {
                bad(format!(
                    "{}: expected true or false, got {}",
                    self.path,
                    kind(self.v)
                ))
            },
            Ok,
        )
    }
    fn string(self) -> R<&'a str> {
        self.v.as_str().map_or_else(
            || {
                bad(format!(
                    "{}: expected a string, got {}",
                    self.path,
                    kind(self.v)
                ))
            },
            Ok,
        )
    }
    fn list(self) -> R<&'a [Value]> {
        match self.v {
            Value::Array(a) => Ok(a),
            _ => bad(format!(
                "{}: expected a list, got {}",
                self.path,
                kind(self.v)
            )),
        }
    }
    fn obj(self) -> R<Obj<'a>> {
        match self.v {
            Value::Object(m) => Ok(Obj {
                map: m,
                path: self.path.to_string(),
                seen: Vec::new(),
            }),
            _ => bad(format!(
                "{}: expected an object, got {}",
                self.path,
                kind(self.v)
            )),
        }
    }
    fn fixed<const N: usize>(self) -> R<[f64; N]> {
        let a = self.list()?;
        if a.len() != N {
            return bad(format!(
                "{}: expected a list of {N} numbers, got {} entries",
                self.path,
                a.len()
            ));
        }
        let mut out = [0.0; N];
        for (i, v) in a.iter().enumerate() {
            out[i] = Node {
                v,
                path: &format!("{}[{i}]", self.path),
            }
            .num()?;
        }
        Ok(out)
    }
    fn vec3(self) -> R<Vec3> {
        self.fixed::<3>().map(Vec3::from_array)
    }
}

impl Obj<'_> {
    fn key(&self, k: &str) -> String {
        if self.path.is_empty() {
            k.to_string()
        } else {
            format!("{}.{k}", self.path)
        }
    }
    /// The value at `k` (None when absent or null) and its path.
    fn opt(&mut self, k: &'static str) -> Option<(&Value, String)> {
        self.seen.push(k);
        match self.map.get(k) {
            None | Some(Value::Null) => None,
            Some(v) => Some((v, self.key(k))),
        }
    }
    fn req(&mut self, k: &'static str) -> R<(&Value, String)> {
        let path = self.key(k);
        self.opt(k)
            .map_or_else(|| bad(format!("{path} is missing (required)")), Ok)
    }
    fn num(&mut self, k: &'static str) -> R<f64> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.num()
    }
    fn num_or(&mut self, k: &'static str, default: f64) -> R<f64> {
        match self.opt(k) {
            Some((v, p)) => Node { v, path: &p }.num(),
            None => Ok(default),
        }
    }
    fn opt_num(&mut self, k: &'static str) -> R<Option<f64>> {
        match self.opt(k) {
            Some((v, p)) => Node { v, path: &p }.num().map(Some),
            None => Ok(None),
        }
    }
    fn uint(&mut self, k: &'static str) -> R<u64> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.uint()
    }
    fn uint_or(&mut self, k: &'static str, default: u64) -> R<u64> {
        match self.opt(k) {
            Some((v, p)) => Node { v, path: &p }.uint(),
            None => Ok(default),
        }
    }
    fn index(&mut self, k: &'static str, len: usize, what: &str) -> R<u32> {
        let (v, p) = self.req(k)?;
        let i = Node { v, path: &p }.uint()?;
        if i as usize >= len {
            return bad(format!(
                "{p} = {i} is out of range: {len} {what} defined (indices 0..{len})"
            ));
        }
        Ok(i as u32)
    }
    fn string(&mut self, k: &'static str) -> R<String> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.string().map(str::to_string)
    }
    fn vec3(&mut self, k: &'static str) -> R<Vec3> {
        let (v, p) = self.req(k)?;
        Node { v, path: &p }.vec3()
    }
    fn positive(&mut self, k: &'static str, unit: &str) -> R<f64> {
        let p = self.key(k);
        let x = self.num(k)?;
        dentalux_core::error::check_range(&p, x, 0.0, true, f64::INFINITY, true, unit)?;
        Ok(x)
    }
    fn nonneg(&mut self, k: &'static str) -> R<f64> {
        let p = self.key(k);
        let x = self.num(k)?;
        dentalux_core::error::check_range(&p, x, 0.0, false, f64::INFINITY, true, "")?;
        Ok(x)
    }
    /// Refuse keys not read.
    fn done(self) -> R<()> {
        for k in self.map.keys() {
            if !self.seen.contains(&k.as_str()) {
                let mut allowed = self.seen.clone();
                allowed.sort_unstable();
                allowed.dedup();
                return bad(format!(
                    "{}: unknown key; allowed: {}",
                    self.key(k),
                    allowed.join(", ")
                ));
            }
        }
        Ok(())
    }
}

fn list_of<'a>(o: &mut Obj<'a>, k: &'static str) -> R<Vec<(&'a Value, String)>> {
    let map: &'a Map<String, Value> = o.map;
    let path = o.key(k);
    o.seen.push(k);
    match map.get(k) {
        None | Some(Value::Null) => Ok(Vec::new()),
        Some(Value::Array(a)) => Ok(a
            .iter()
            .enumerate()
            .map(|(i, v)| (v, format!("{path}[{i}]")))
            .collect()),
        Some(v) => bad(format!("{path}: expected a list, got {}", kind(v))),
    }
}

fn camera(mut o: Obj) -> R<Camera> {
    let c = Camera::new(
        o.vec3("position")?,
        o.vec3("look_at")?,
        o.vec3("up")?,
        o.num("fov_deg")?,
        o.uint("width")? as usize,
        o.uint("height")? as usize,
    )?;
    o.done()?;
    Ok(c)
}

fn medium(mut o: Obj) -> R<Medium> {
    let _ = o.opt("name");
    let prefix = format!("{}.", o.path);
    let phase = match o.opt("phase") {
        None => PhaseFunction::Isotropic,
        Some((v, p)) => {
            let mut ph = Node { v, path: &p }.obj()?;
            let g = ph.num_or("g", 0.0)?;
            let fd = ph.num_or("fd", 0.0)?;
            let lobes = list_of(&mut ph, "lobes")?
                .into_iter()
                .map(|(v, p)| Node { v, path: &p }.fixed::<2>().map(|[w, g]| (w, g)))
                .collect::<R<Vec<_>>>()?;
            ph.done()?;
            let f = if lobes.is_empty() {
                PhaseFunction::hg_with_isotropic(g, fd)
            } else {
                PhaseFunction::multi_lobe(&lobes)
            };
            f.map_err(|e| Error::InvalidInput(format!("{p}.{e}")))?
        }
    };
    let m = Medium::new(&prefix, o.num("mua")?, o.num("mus")?, o.num("n")?, phase)?;
    o.done()?;
    Ok(m)
}

fn mapping(o: &mut Obj) -> R<Mapping> {
    let p = o.key("mapping");
    match o.opt("mapping") {
        None => Ok(Mapping::Uv),
        Some((v, _)) => match (Node { v, path: &p }).string()? {
            "uv" => Ok(Mapping::Uv),
            "xy" => Ok(Mapping::Xy),
            other => bad(format!("{p} = {other:?}: allowed \"uv\" or \"xy\"")),
        },
    }
}

fn surface(mut o: Obj) -> R<Surface> {
    let t = o.string("type")?;
    let s = match t.as_str() {
        "lambertian" => Surface::Lambertian {
            reflectance: o.num("reflectance")?,
        },
        "checker" => Surface::Checker {
            a: o.num("a")?,
            b: o.num("b")?,
            size: o.num("size")?,
            mapping: mapping(&mut o)?,
        },
        "image" => {
            let data = list_of(&mut o, "data")?
                .into_iter()
                .map(|(v, p)| Node { v, path: &p }.num())
                .collect::<R<Vec<_>>>()?;
            Surface::Image {
                width: o.uint("width")? as usize,
                height: o.uint("height")? as usize,
                data,
                mapping: mapping(&mut o)?,
                size: o.num_or("size", 1.0)?,
            }
        }
        "black" => Surface::Black,
        other => {
            return bad(format!(
                "{}: {other:?}: allowed \"lambertian\", \"checker\", \"image\", \"black\"",
                o.key("type")
            ))
        }
    };
    s.validate(&o.path)?;
    o.done()?;
    Ok(s)
}

fn boundary(o: &mut Obj, n_surfaces: usize, n_media: usize) -> R<Boundary> {
    let (v, p) = o.req("boundary")?;
    let mut b = Node { v, path: &p }.obj()?;
    let kind = b.string("kind")?;
    let out = match kind.as_str() {
        "opaque" => Boundary::Opaque {
            surface: b.index("surface", n_surfaces, "surfaces")?,
        },
        "dielectric" => Boundary::Dielectric {
            inside: b.index("inside", n_media, "media")?,
            outside: b.index("outside", n_media, "media")?,
        },
        other => {
            return bad(format!(
                "{p}.kind = {other:?}: allowed \"opaque\" or \"dielectric\""
            ))
        }
    };
    b.done()?;
    Ok(out)
}

fn transform(o: &mut Obj) -> R<Option<Transform>> {
    let Some((v, p)) = o.opt("transform") else {
        return Ok(None);
    };
    let rows = Node { v, path: &p }.list()?;
    if rows.len() != 4 {
        return bad(format!(
            "{p}: expected 4 rows of 4 numbers, got {} rows",
            rows.len()
        ));
    }
    let mut m = [[0.0; 4]; 4];
    for (i, r) in rows.iter().enumerate() {
        m[i] = Node {
            v: r,
            path: &format!("{p}[{i}]"),
        }
        .fixed::<4>()?;
    }
    Transform::from_rows(&p, m).map(Some)
}

fn shape(mut o: Obj, n_surfaces: usize, n_media: usize) -> R<ShapeInstance> {
    let t = o.string("type")?;
    let b = boundary(&mut o, n_surfaces, n_media)?;
    let tr = transform(&mut o)?;
    let g = match t.as_str() {
        "sphere" => Geometry::Sphere(Sphere {
            center: o.vec3("center")?,
            radius: o.positive("radius", "mm")?,
        }),
        "quad" => Geometry::Quad(Quad {
            corner: o.vec3("corner")?,
            u: o.vec3("u")?,
            v: o.vec3("v")?,
        }),
        "box" => Geometry::Box(BoxShape {
            min: o.vec3("min")?,
            max: o.vec3("max")?,
        }),
        "cylinder" => Geometry::Cylinder(Cylinder {
            center: o.vec3("center")?,
            axis: o.vec3("axis")?,
            radius: o.positive("radius", "mm")?,
            height: o.positive("height", "mm")?,
        }),
        "mesh" => {
            let positions = list_of(&mut o, "positions")?
                .into_iter()
                .map(|(v, p)| Node { v, path: &p }.vec3())
                .collect::<R<Vec<_>>>()?;
            let triangles = list_of(&mut o, "triangles")?
                .into_iter()
                .map(|(v, p)| {
                    let idx = Node { v, path: &p }.fixed::<3>()?;
                    let mut t = [0u32; 3];
                    for (k, x) in idx.iter().enumerate() {
                        if x.fract() != 0.0 || *x < 0.0 || *x > u32::MAX as f64 {
                            return bad(format!("{p}[{k}] = {x}: expected a vertex index"));
                        }
                        t[k] = *x as u32;
                    }
                    Ok(t)
                })
                .collect::<R<Vec<_>>>()?;
            let uvs = match o.opt("uvs") {
                None => None,
                Some(_) => Some(
                    list_of(&mut o, "uvs")?
                        .into_iter()
                        .map(|(v, p)| Node { v, path: &p }.fixed::<2>())
                        .collect::<R<Vec<_>>>()?,
                ),
            };
            Geometry::Mesh(TriangleMesh {
                positions,
                triangles,
                uvs,
            })
        }
        other => {
            return bad(format!(
                "{}: {other:?}: allowed \"sphere\", \"quad\", \"box\", \"cylinder\", \"mesh\"",
                o.key("type")
            ))
        }
    };
    let path = o.path.clone();
    o.done()?;
    ShapeInstance::new(&path, g, tr, b)
}

fn light(mut o: Obj) -> R<Light> {
    let t = o.string("type")?;
    let l = match t.as_str() {
        "quad" => Light::Quad {
            corner: o.vec3("corner")?,
            u: o.vec3("u")?,
            v: o.vec3("v")?,
            radiance: o.nonneg("radiance")?,
        },
        "disc" => Light::Disc {
            center: o.vec3("center")?,
            normal: dentalux_core::lights::unit(&o.key("normal"), o.vec3("normal")?)?,
            radius: o.positive("radius", "mm")?,
            radiance: o.nonneg("radiance")?,
        },
        "point" => Light::Point {
            position: o.vec3("position")?,
            intensity: o.nonneg("intensity")?,
        },
        "spot" => {
            let path = o.path.clone();
            Light::spot(
                &path,
                o.vec3("position")?,
                o.vec3("direction")?,
                o.nonneg("intensity")?,
                o.num("cone_deg")?,
                o.num_or("falloff_deg", 0.0)?,
            )?
        }
        other => {
            return bad(format!(
                "{}: {other:?}: allowed \"quad\", \"disc\", \"point\", \"spot\"",
                o.key("type")
            ))
        }
    };
    l.validate(&o.path)?;
    o.done()?;
    Ok(l)
}

/// Read the resolved scene JSON of the render contract.
fn scene_from_json(text: &str) -> R<Scene> {
    let root: Value = serde_json::from_str(text)
        .map_err(|e| Error::InvalidInput(format!("scene JSON is malformed: {e}")))?;
    let mut o = Node { v: &root, path: "" }.obj()?;
    let cam = {
        let (v, p) = o.req("camera")?;
        camera(Node { v, path: &p }.obj()?)?
    };
    let media = list_of(&mut o, "media")?
        .into_iter()
        .map(|(v, p)| medium(Node { v, path: &p }.obj()?))
        .collect::<R<Vec<_>>>()?;
    let media = if media.is_empty() {
        vec![Medium::new("", 0.0, 0.0, 1.0, PhaseFunction::Isotropic)?]
    } else {
        media
    };
    let ambient = o.uint_or("ambient_medium", 0)?;
    if ambient as usize >= media.len() {
        return bad(format!(
            "ambient_medium = {ambient} is out of range: {} media defined",
            media.len()
        ));
    }
    let surfaces = list_of(&mut o, "surfaces")?
        .into_iter()
        .map(|(v, p)| surface(Node { v, path: &p }.obj()?))
        .collect::<R<Vec<_>>>()?;
    let shapes = list_of(&mut o, "shapes")?
        .into_iter()
        .map(|(v, p)| shape(Node { v, path: &p }.obj()?, surfaces.len(), media.len()))
        .collect::<R<Vec<_>>>()?;
    let lights = list_of(&mut o, "lights")?
        .into_iter()
        .map(|(v, p)| light(Node { v, path: &p }.obj()?))
        .collect::<R<Vec<_>>>()?;
    o.done()?;
    Scene::new(cam, media, surfaces, shapes, lights, ambient as u32)
}

/// Read the settings JSON; returns the settings and the thread count (None: all cores).
fn settings_from_json(text: &str) -> R<(Settings, Option<usize>)> {
    let root: Value = serde_json::from_str(text)
        .map_err(|e| Error::InvalidInput(format!("settings JSON is malformed: {e}")))?;
    let mut o = Node {
        v: &root,
        path: "settings",
    }
    .obj()?;
    let d = Settings::default();
    let integrator = match o.opt("integrator") {
        Some((v, p)) => Integrator::parse(Node { v, path: &p }.string()?)?,
        None => d.integrator,
    };
    let to_u32 = |k: &str, x: u64| {
        u32::try_from(x)
            .map_err(|_| Error::InvalidInput(format!("settings.{k} = {x} is too large")))
    };
    let s = Settings {
        integrator,
        spp: to_u32("spp", o.uint_or("spp", d.spp as u64)?)?,
        photons: o.uint_or("photons", d.photons)?,
        volume_photons: o.uint_or("volume_photons", d.volume_photons)?,
        volume_stored: o.uint_or("volume_stored", d.volume_stored)?,
        aim: o.num_or("aim", d.aim)?,
        k: o.uint_or("k", d.k as u64)? as usize,
        radius: o.opt_num("radius")?,
        step: o.opt_num("step")?,
        seed: o.uint_or("seed", d.seed)?,
        band: o.uint_or("band", d.band)?,
        max_depth: to_u32("max_depth", o.uint_or("max_depth", d.max_depth as u64)?)?,
        passes: to_u32("passes", o.uint_or("passes", d.passes as u64)?)?,
        alpha: o.num_or("alpha", d.alpha)?,
        pass_index: to_u32("pass_index", o.uint_or("pass_index", d.pass_index as u64)?)?,
        final_gather: match o.opt("final_gather") {
            Some((v, p)) => Node { v, path: &p }.boolean()?,
            None => d.final_gather,
        },
        kernel_layer: o.num_or("kernel_layer", d.kernel_layer)?,
        kernel_clip: match o.opt("kernel_clip") {
            Some((v, p)) => Node { v, path: &p }.boolean()?,
            None => d.kernel_clip,
        },
    };
    let threads = match o.opt("threads") {
        Some((v, p)) => Some(Node { v, path: &p }.uint()? as usize),
        None => None,
    };
    o.done()?;
    s.validate()?;
    Ok((s, threads))
}

fn stats_dict<'py>(py: Python<'py>, s: &Stats) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("integrator", &s.integrator)?;
    d.set_item("seconds_total", s.seconds_total)?;
    d.set_item("seconds_photons", s.seconds_photons)?;
    d.set_item("seconds_build", s.seconds_build)?;
    d.set_item("seconds_camera", s.seconds_camera)?;
    d.set_item("photons_emitted", s.photons_emitted)?;
    d.set_item("photons_stored", s.photons_stored)?;
    d.set_item("bytes_per_photon", s.bytes_per_photon)?;
    d.set_item("photon_map_bytes", s.photon_map_bytes)?;
    d.set_item("radius", s.radius)?;
    d.set_item("rays", s.rays)?;
    d.set_item("spp", s.spp)?;
    for (k, v) in &s.extra {
        d.set_item(k, v)?;
    }
    Ok(d)
}

/// Pixel positions (x, y) of world points [mm] on the film of the camera in `camera_json`
/// (the render contract's `camera` object): the inverse of the core's camera rays, so image
/// regions follow the render's own handedness. `None` for a point behind the camera.
#[pyfunction]
pub fn camera_project(
    camera_json: &str,
    points: Vec<[f64; 3]>,
) -> PyResult<Vec<Option<(f64, f64)>>> {
    let value: Value = serde_json::from_str(camera_json)
        .map_err(|e| PyValueError::new_err(format!("camera JSON is malformed: {e}")))?;
    let cam = Node {
        v: &value,
        path: "camera",
    }
    .obj()
    .and_then(camera)
    .map_err(runner::to_py_err)?;
    Ok(points
        .into_iter()
        .map(|p| cam.project(Vec3::new(p[0], p[1], p[2])))
        .collect())
}

/// Render one band of a resolved scene (docs/render-contract.md): returns the radiance image
/// (numpy float32, height × width) and a dict of statistics.
#[pyfunction]
#[pyo3(signature = (scene_json, settings_json, progress=None))]
pub fn render_band<'py>(
    py: Python<'py>,
    scene_json: &str,
    settings_json: &str,
    progress: Option<PyObject>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let (settings, threads) = settings_from_json(settings_json).map_err(runner::to_py_err)?;
    let scene = scene_from_json(scene_json).map_err(runner::to_py_err)?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (image, stats) = runner::run(py, threads, progress, |c| core_render(&scene, &settings, c))?;
    let arr = PyArray1::from_vec(py, image)
        .reshape([h, w])
        .map_err(|e| PyValueError::new_err(format!("image shape: {e}")))?;
    Ok((arr.into_any(), stats_dict(py, &stats)?))
}
