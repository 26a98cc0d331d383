//! Binding of `render_band`, `render_bands`, `camera_project`, `settings_schema` and `photons_traced`: the JSON strings of the render contract
//! (docs/render-contract.md) go to the core's decoder ([`dentalux_core::contract`]), the band
//! is rendered off the GIL through [`runner::run`], and the image and statistics come back as
//! numpy and a dict.

use crate::runner;
use dentalux_core::contract::settings_schema as core_settings_schema;
use dentalux_core::contract::{
    band_scenes_from_json, camera_from_json, scene_from_json, settings_from_json,
};
use dentalux_core::geometry::Vec3;
use dentalux_core::integrators::render::{
    render_band as core_render, render_bands as core_render_bands,
};
use dentalux_core::integrators::settings::Stats;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::types::PyList;

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
    if !s.estimator.is_empty() {
        d.set_item("volume_estimator", &s.estimator)?;
    }
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
    let cam = camera_from_json(camera_json).map_err(runner::to_py_err)?;
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

/// Render every band of a multi-band scene (docs/render-contract.md: the shapes once, each
/// band's media, surfaces and lights in `bands`), band `b` with random-stream key
/// `band_keys[b]`: the shapes and their BVH are decoded and built once. Returns the radiance
/// (numpy float32, bands × height × width) and a list of per-band statistics dicts.
#[pyfunction]
#[pyo3(signature = (scene_json, settings_json, band_keys, progress=None))]
pub fn render_bands<'py>(
    py: Python<'py>,
    scene_json: &str,
    settings_json: &str,
    band_keys: Vec<u64>,
    progress: Option<PyObject>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyList>)> {
    let (settings, threads) = settings_from_json(settings_json).map_err(runner::to_py_err)?;
    let scenes = band_scenes_from_json(scene_json).map_err(runner::to_py_err)?;
    let (w, h) = (scenes[0].camera.width, scenes[0].camera.height);
    let bands = runner::run(py, threads, progress, |c| {
        core_render_bands(&scenes, &settings, &band_keys, c)
    })?;
    let n = bands.len();
    let mut pixels = Vec::with_capacity(n * w * h);
    let stats = PyList::empty(py);
    for (image, s) in &bands {
        pixels.extend_from_slice(image);
        stats.append(stats_dict(py, s)?)?;
    }
    let arr = PyArray1::from_vec(py, pixels)
        .reshape([n, h, w])
        .map_err(|e| PyValueError::new_err(format!("image shape: {e}")))?;
    Ok((arr.into_any(), stats))
}

/// The settings' schema as JSON (integrator names, keys with defaults and ranges, the pass
/// bound): what Python validates user input against.
#[pyfunction]
pub fn settings_schema() -> String {
    core_settings_schema()
}

/// Photons one pass of one band traces with the settings in `settings_json` (the progress
/// count's unit besides pixels).
#[pyfunction]
pub fn photons_traced(settings_json: &str) -> PyResult<u64> {
    let (settings, _) = settings_from_json(settings_json).map_err(runner::to_py_err)?;
    Ok(settings.photons_traced())
}
