//! The render contract (docs/render-contract.md): the resolved scene and the settings arrive
//! as JSON and are decoded into core types here, with serde_json reading the text and
//! [`json`]'s reader walking it, so every error names its key path (`shapes[2].radius`) and
//! unknown keys are refused. The binding passes the strings through; the core's own
//! constructors check the values' ranges.

mod inside;
mod json;

pub use inside::shape_contains;

use crate::camera::Camera;
use crate::error::Error;
use crate::geometry::mesh::TriangleMesh;
use crate::geometry::shapes::{BoxShape, Cylinder, Quad, Sphere};
use crate::geometry::transform::Transform;
use crate::integrators::settings::{
    Integrator, Range, Settings, VolumeEstimator, KEYS, MAX_PASSES,
};
use crate::lights::Light;
use crate::medium::Medium;
use crate::phase::PhaseFunction;
use crate::scene::{Boundary, Geometry, Scene, ShapeInstance};
use crate::surface::{Mapping, Surface};
use json::{bad, list_of, Node, Obj, R};
use serde_json::{json, Value};

/// The error for an unknown `type` of the object `o`, listing the allowed ones.
fn unknown_type<T>(o: &Obj, other: &str, allowed: &[&str]) -> R<T> {
    let allowed: Vec<String> = allowed.iter().map(|a| format!("{a:?}")).collect();
    bad(format!(
        "{}: {other:?}: allowed {}",
        o.key("type"),
        allowed.join(", ")
    ))
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
            PhaseFunction::from_params(g, fd, &lobes)
                .map_err(|e| Error::InvalidInput(format!("{p}.{e}")))?
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
        other => return unknown_type(&o, other, &["lambertian", "checker", "image", "black"]),
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
    let (g, tr, b) = shape_parts(&mut o, n_surfaces, n_media)?;
    let path = o.path.clone();
    o.done()?;
    ShapeInstance::new(&path, g, tr, b)
}

/// The geometry, transform and boundary of the shape object `o`, unvalidated (the caller
/// refuses unknown keys and builds the [`ShapeInstance`]).
fn shape_parts(
    o: &mut Obj,
    n_surfaces: usize,
    n_media: usize,
) -> R<(Geometry, Option<Transform>, Boundary)> {
    let t = o.string("type")?;
    let b = boundary(o, n_surfaces, n_media)?;
    let tr = transform(o)?;
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
            let positions = list_of(o, "positions")?
                .into_iter()
                .map(|(v, p)| Node { v, path: &p }.vec3())
                .collect::<R<Vec<_>>>()?;
            let triangles = list_of(o, "triangles")?
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
                    list_of(o, "uvs")?
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
            let allowed = ["sphere", "quad", "box", "cylinder", "mesh"];
            return unknown_type(o, other, &allowed);
        }
    };
    Ok((g, tr, b))
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
            normal: crate::lights::unit(&o.key("normal"), o.vec3("normal")?)?,
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
        other => return unknown_type(&o, other, &["quad", "disc", "point", "spot"]),
    };
    l.validate(&o.path)?;
    o.done()?;
    Ok(l)
}

/// The `media` list of `o` (air alone when absent or empty).
fn media_of(o: &mut Obj) -> R<Vec<Medium>> {
    let media = list_of(o, "media")?
        .into_iter()
        .map(|(v, p)| medium(Node { v, path: &p }.obj()?))
        .collect::<R<Vec<_>>>()?;
    if media.is_empty() {
        Ok(vec![Medium::new(
            "",
            0.0,
            0.0,
            1.0,
            PhaseFunction::Isotropic,
        )?])
    } else {
        Ok(media)
    }
}

/// The `surfaces` list of `o`.
fn surfaces_of(o: &mut Obj) -> R<Vec<Surface>> {
    list_of(o, "surfaces")?
        .into_iter()
        .map(|(v, p)| surface(Node { v, path: &p }.obj()?))
        .collect()
}

/// The `shapes` list of `o`, their boundaries checked against the counts of media and
/// surfaces.
fn shapes_of(o: &mut Obj, n_surfaces: usize, n_media: usize) -> R<Vec<ShapeInstance>> {
    list_of(o, "shapes")?
        .into_iter()
        .map(|(v, p)| shape(Node { v, path: &p }.obj()?, n_surfaces, n_media))
        .collect()
}

/// The `lights` list of `o`.
fn lights_of(o: &mut Obj) -> R<Vec<Light>> {
    list_of(o, "lights")?
        .into_iter()
        .map(|(v, p)| light(Node { v, path: &p }.obj()?))
        .collect()
}

/// `ambient_medium` of `o`, checked against the number of media.
fn ambient_of(o: &mut Obj, n_media: usize) -> R<u32> {
    let ambient = o.uint_or("ambient_medium", 0)?;
    if ambient as usize >= n_media {
        return bad(format!(
            "ambient_medium = {ambient} is out of range: {n_media} media defined"
        ));
    }
    Ok(ambient as u32)
}

fn parse_root<'a>(text: &str, root: &'a mut Value) -> R<Obj<'a>> {
    *root = serde_json::from_str(text)
        .map_err(|e| Error::InvalidInput(format!("scene JSON is malformed: {e}")))?;
    Node { v: root, path: "" }.obj()
}

fn camera_of(o: &mut Obj) -> R<Camera> {
    let (v, p) = o.req("camera")?;
    camera(Node { v, path: &p }.obj()?)
}

/// Read the resolved scene JSON of the render contract (one band).
pub fn scene_from_json(text: &str) -> R<Scene> {
    let mut root = Value::Null;
    let mut o = parse_root(text, &mut root)?;
    let cam = camera_of(&mut o)?;
    let media = media_of(&mut o)?;
    let ambient = ambient_of(&mut o, media.len())?;
    let surfaces = surfaces_of(&mut o)?;
    let shapes = shapes_of(&mut o, surfaces.len(), media.len())?;
    let lights = lights_of(&mut o)?;
    o.done()?;
    Scene::new(cam, media, surfaces, shapes, lights, ambient)
}

/// Read the multi-band scene JSON of the render contract: `camera`, `ambient_medium` and
/// `shapes` once, and `bands`, a list of objects with each band's `media`, `surfaces` and
/// `lights`. Returns a scene per band; they share one set of shapes and one BVH.
pub fn band_scenes_from_json(text: &str) -> R<Vec<Scene>> {
    let mut root = Value::Null;
    let mut o = parse_root(text, &mut root)?;
    let cam = camera_of(&mut o)?;
    let bands = list_of(&mut o, "bands")?;
    if bands.is_empty() {
        return bad(format!(
            "{}: empty; at least one band is needed",
            o.key("bands")
        ));
    }
    let mut parts: Vec<(Vec<Medium>, Vec<Surface>, Vec<Light>)> = Vec::with_capacity(bands.len());
    for (v, p) in &bands {
        let mut b = Node { v, path: p }.obj()?;
        let band = (media_of(&mut b)?, surfaces_of(&mut b)?, lights_of(&mut b)?);
        b.done()?;
        if let Some((m0, s0, l0)) = parts.first() {
            let counts = [
                ("media", band.0.len(), m0.len()),
                ("surfaces", band.1.len(), s0.len()),
                ("lights", band.2.len(), l0.len()),
            ];
            for (what, n, n0) in counts {
                if n != n0 {
                    return bad(format!(
                        "{p}.{what} has {n} entries and bands[0].{what} has {n0}: every band lists the same {what}"
                    ));
                }
            }
        }
        parts.push(band);
    }
    let mut parts = parts.into_iter();
    let (media, surfaces, lights) = parts.next().expect("at least one band");
    let ambient = ambient_of(&mut o, media.len())?;
    let shapes = shapes_of(&mut o, surfaces.len(), media.len())?;
    o.done()?;
    let in_band = |i: usize| {
        move |e: Error| match e {
            Error::InvalidInput(m) => Error::InvalidInput(format!("bands[{i}]: {m}")),
            other => other,
        }
    };
    let first = Scene::new(cam, media, surfaces, shapes, lights, ambient).map_err(in_band(0))?;
    let mut scenes = Vec::with_capacity(bands.len());
    for (i, (media, surfaces, lights)) in parts.enumerate() {
        let scene = first
            .with_band(media, surfaces, lights)
            .map_err(in_band(i + 1))?;
        scenes.push(scene);
    }
    scenes.insert(0, first);
    Ok(scenes)
}

/// Read the settings JSON; returns the settings and the thread count (None: all cores).
pub fn settings_from_json(text: &str) -> R<(Settings, Option<usize>)> {
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
        surface_k: o.opt_with("surface_k", |n| n.uint())?.map(|v| v as usize),
        radius: o.opt_num("radius")?,
        surface_radius: o.opt_num("surface_radius")?,
        step: o.opt_num("step")?,
        seed: o.uint_or("seed", d.seed)?,
        band: o.uint_or("band", d.band)?,
        max_depth: to_u32("max_depth", o.uint_or("max_depth", d.max_depth as u64)?)?,
        passes: to_u32("passes", o.uint_or("passes", d.passes as u64)?)?,
        alpha: o.num_or("alpha", d.alpha)?,
        pass_index: to_u32("pass_index", o.uint_or("pass_index", d.pass_index as u64)?)?,
        final_gather: (o.opt_with("final_gather", |n| n.boolean())?).unwrap_or(d.final_gather),
        kernel_layer: o.num_or("kernel_layer", d.kernel_layer)?,
        kernel_clip: (o.opt_with("kernel_clip", |n| n.boolean())?).unwrap_or(d.kernel_clip),
        spectral_photons: (o.opt_with("spectral_photons", |n| n.boolean())?)
            .unwrap_or(d.spectral_photons),
        hero_camera: (o.opt_with("hero_camera", |n| n.boolean())?).unwrap_or(d.hero_camera),
        volume_estimator: match o.opt("volume_estimator") {
            Some((v, p)) => VolumeEstimator::parse(Node { v, path: &p }.string()?)?,
            None => d.volume_estimator,
        },
    };
    let threads = o.opt_with("threads", |n| n.uint())?.map(|t| t as usize);
    o.done()?;
    s.validate()?;
    Ok((s, threads))
}

/// Read the render contract's `camera` object (`camera_json`), errors under `camera.`.
pub fn camera_from_json(camera_json: &str) -> R<Camera> {
    let value: Value = serde_json::from_str(camera_json)
        .map_err(|e| Error::InvalidInput(format!("camera JSON is malformed: {e}")))?;
    Node {
        v: &value,
        path: "camera",
    }
    .obj()
    .and_then(camera)
}

/// The settings' schema, as JSON, for the layer where user input comes in (Python's
/// scene/schema.py validates against it): the integrators (and which photons they trace),
/// every key of [`KEYS`] in order with its default ([`Settings::default`]) and range, and
/// the pass bound [`MAX_PASSES`].
pub fn settings_schema() -> String {
    let d = Settings::default();
    let default = |name: &str| -> Value {
        match name {
            "integrator" => json!(d.integrator.name()),
            "spp" => json!(d.spp),
            "photons" => json!(d.photons),
            "volume_photons" => json!(d.volume_photons),
            "volume_stored" => json!(d.volume_stored),
            "aim" => json!(d.aim),
            "k" => json!(d.k),
            "surface_k" => json!(d.surface_k),
            "radius" => json!(d.radius),
            "surface_radius" => json!(d.surface_radius),
            "step" => json!(d.step),
            "seed" => json!(d.seed),
            "band" => json!(d.band),
            "max_depth" => json!(d.max_depth),
            "passes" => json!(d.passes),
            "alpha" => json!(d.alpha),
            "pass_index" => json!(d.pass_index),
            "final_gather" => json!(d.final_gather),
            "kernel_layer" => json!(d.kernel_layer),
            "kernel_clip" => json!(d.kernel_clip),
            "volume_estimator" => json!(d.volume_estimator.name()),
            "spectral_photons" => json!(d.spectral_photons),
            "hero_camera" => json!(d.hero_camera),
            _ => Value::Null,
        }
    };
    let keys: Vec<Value> = KEYS
        .iter()
        .map(|k| {
            let mut v = match k.range {
                Range::Integer { lo } => json!({"kind": "integer", "lo": lo}),
                Range::Real {
                    lo,
                    lo_open,
                    hi,
                    hi_open,
                } => json!({"kind": "real", "lo": lo, "lo_open": lo_open, "hi": hi,
                            "hi_open": hi_open}),
                Range::Positive => json!({"kind": "positive", "unit": "mm"}),
                Range::Boolean => json!({"kind": "boolean"}),
                Range::Integrator => json!({"kind": "integrator"}),
                Range::Choice(values) => json!({"kind": "choice", "values": values}),
            };
            v["name"] = json!(k.name);
            v["default"] = default(k.name);
            v["scene"] = json!(k.scene);
            v
        })
        .collect();
    let integrators: Vec<Value> = Integrator::ALL
        .iter()
        .map(|(i, name)| {
            json!({"name": name, "traces_photons": i.traces_photons(),
                   "traces_volume_photons": i.traces_volume_photons(),
                   "shares_bands": i.shares_bands()})
        })
        .collect();
    json!({"integrators": integrators, "keys": keys, "max_passes": MAX_PASSES}).to_string()
}

#[cfg(test)]
mod tests;
