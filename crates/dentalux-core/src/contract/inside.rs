//! Which points lie strictly inside one shape of the render contract: the test behind the
//! scene checks (a camera inside a shape, dielectric shapes that cross, a light inside a
//! medium), so Python asks the core instead of keeping its own copy of the geometry.

use super::json::{Node, R};
use super::shape_parts;
use crate::error::Error;
use crate::geometry::Vec3;
use crate::scene::{Boundary, Geometry, ShapeInstance};
use serde_json::Value;

/// For each of `points` [mm, world], whether it lies strictly inside the shape in
/// `shape_json` (one entry of the contract scene's `shapes`, decoded as the scene decoder
/// does; errors under `shape.`). Quads and meshes that are not watertight have no inside.
pub fn shape_contains(shape_json: &str, points: &[Vec3]) -> R<Vec<bool>> {
    let value: Value = serde_json::from_str(shape_json)
        .map_err(|e| Error::InvalidInput(format!("shape JSON is malformed: {e}")))?;
    let mut o = Node {
        v: &value,
        path: "shape",
    }
    .obj()?;
    // A lone shape has no lists for its boundary to index into, and what it separates does
    // not change the solid it bounds: the boundary is read (unknown keys are still refused)
    // and set aside, so a dielectric mesh's closedness stays the scene decoder's refusal.
    let (geometry, transform, _) = shape_parts(&mut o, usize::MAX, usize::MAX)?;
    let path = o.path.clone();
    o.done()?;
    let s = ShapeInstance::new(&path, geometry, transform, Boundary::Opaque { surface: 0 })?;
    Ok(match &s.geometry {
        // closedness once, and only when a point passes the cheaper parity test
        Geometry::Mesh(m) => {
            let mut closed = None;
            (points.iter())
                .map(|&p| m.encloses(p) && *closed.get_or_insert_with(|| m.is_watertight()))
                .collect()
        }
        _ => points.iter().map(|&p| s.contains(p)).collect(),
    })
}
