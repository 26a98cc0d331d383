//! Binding of `shape_contains`: one shape of the render contract (its JSON) goes to the
//! core's decoder and inside test ([`dentalux_core::contract::shape_contains`]), so the scene
//! checks in Python ask the core which points lie inside a shape.

use crate::runner;
use dentalux_core::contract::shape_contains as core_shape_contains;
use dentalux_core::geometry::Vec3;
use pyo3::prelude::*;

/// For each world point [mm], whether it lies strictly inside the shape in `shape_json` (one
/// entry of the render contract's `shapes`). Quads and meshes that are not watertight have
/// no inside.
#[pyfunction]
pub fn shape_contains(shape_json: &str, points: Vec<[f64; 3]>) -> PyResult<Vec<bool>> {
    let points: Vec<Vec3> = points.into_iter().map(Vec3::from_array).collect();
    core_shape_contains(shape_json, &points).map_err(runner::to_py_err)
}
