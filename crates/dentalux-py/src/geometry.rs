//! Bindings of the core's geometry checks. `shape_contains`: one shape of the render
//! contract (its JSON) goes to the core's decoder and inside test
//! ([`dentalux_core::contract::shape_contains`]), so the scene checks in Python ask the core
//! which points lie inside a shape. `mesh_topology`: whether a
//! mesh file closes a solid, by the rule the scene decoder applies to dielectric meshes.

use crate::runner;
use dentalux_core::contract::shape_contains as core_shape_contains;
use dentalux_core::geometry::mesh::{Topology, TriangleMesh};
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

/// How the core judges a triangle mesh (positions [mm], vertex-index triples) as the boundary
/// of a solid, on positions merged as for a render: ("closed", 0), ("open", the number of
/// edges not shared by exactly two triangles) or ("inconsistent", the number of edges
/// traversed twice in one direction), and whether its signed volume is negative (its normals
/// point in: the decoder turns such a dielectric mesh outward). The rule a dielectric mesh
/// must pass.
#[pyfunction]
pub fn mesh_topology(
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
) -> PyResult<(&'static str, usize, bool)> {
    let mesh = TriangleMesh {
        positions: positions.into_iter().map(Vec3::from_array).collect(),
        triangles,
        uvs: None,
    };
    mesh.check_indices("").map_err(runner::to_py_err)?;
    let inward = mesh.signed_volume() < 0.0;
    Ok(match mesh.topology() {
        Topology::Closed => ("closed", 0, inward),
        Topology::Open { bad_edges } => ("open", bad_edges, inward),
        Topology::Inconsistent { bad_edges } => ("inconsistent", bad_edges, inward),
    })
}
