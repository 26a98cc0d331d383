//! Affine object-to-world transforms (4×4, row-major as given by the scene JSON), with the
//! inverse and the inverse transpose precomputed for rays and normals.

use super::{Aabb, Vec3};
use crate::error::{Error, Result};
use glam::{DMat3, DMat4};

/// An affine object-to-world transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    m: DMat4,
    inv: DMat4,
    /// Inverse transpose of the linear part (maps object normals to world normals).
    normal: DMat3,
    /// Cube root of |det| of the linear part: the mean length scale factor.
    scale: f64,
    /// A lower bound on how much the linear part shortens a vector (its smallest singular
    /// value): world distances are at least this times object distances.
    min_stretch: f64,
}

/// 1 / sqrt(‖A‖₁ ‖A‖∞) for A the inverse of a linear part: since the spectral norm is at most
/// sqrt(‖A‖₁ ‖A‖∞), this is at most the linear part's smallest singular value (exact for
/// diagonal matrices).
fn min_stretch(inv_lin: DMat3) -> f64 {
    let a = inv_lin.to_cols_array_2d(); // a[col][row]
    let col = (0..3).map(|c| (0..3).map(|r| a[c][r].abs()).sum::<f64>());
    let row = (0..3).map(|r| (0..3).map(|c| a[c][r].abs()).sum::<f64>());
    1.0 / (col.fold(0.0, f64::max) * row.fold(0.0, f64::max)).sqrt()
}

impl Transform {
    /// From a row-major 4×4 matrix; `field` names it in error messages. The last row must
    /// be (0, 0, 0, 1) and the linear part invertible.
    pub fn from_rows(field: &str, rows: [[f64; 4]; 4]) -> Result<Self> {
        if rows.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::InvalidInput(format!(
                "{field} has a non-finite entry"
            )));
        }
        let last = rows[3];
        if last[0].abs() > 1e-12
            || last[1].abs() > 1e-12
            || last[2].abs() > 1e-12
            || (last[3] - 1.0).abs() > 1e-12
        {
            return Err(Error::InvalidInput(format!(
                "{field}: the last row must be [0, 0, 0, 1] (an affine transform), got {last:?}"
            )));
        }
        // glam is column-major: build from the transpose
        let m = DMat4::from_cols_array_2d(&rows).transpose();
        let lin = DMat3::from_mat4(m);
        let det = lin.determinant();
        if det.abs() < 1e-12 {
            return Err(Error::InvalidInput(format!(
                "{field} is singular (determinant {det:e}); scale factors must be non-zero"
            )));
        }
        Ok(Self {
            m,
            inv: m.inverse(),
            normal: lin.inverse().transpose(),
            scale: det.abs().cbrt(),
            min_stretch: min_stretch(lin.inverse()),
        })
    }
    /// The identity.
    pub fn identity() -> Self {
        Self {
            m: DMat4::IDENTITY,
            inv: DMat4::IDENTITY,
            normal: DMat3::IDENTITY,
            scale: 1.0,
            min_stretch: 1.0,
        }
    }
    /// A translation by `t` [mm] (for tests and built-in geometry).
    pub fn translate(t: Vec3) -> Self {
        let m = DMat4::from_translation(t);
        Self {
            m,
            inv: m.inverse(),
            normal: DMat3::IDENTITY,
            scale: 1.0,
            min_stretch: 1.0,
        }
    }
    /// Object point to world.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.m.transform_point3(p)
    }
    /// Object direction to world (not normalised).
    #[inline]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.m.transform_vector3(v)
    }
    /// World point to object.
    #[inline]
    pub fn inv_point(&self, p: Vec3) -> Vec3 {
        self.inv.transform_point3(p)
    }
    /// World direction to object (not normalised, so ray parameters t are preserved).
    #[inline]
    pub fn inv_vector(&self, v: Vec3) -> Vec3 {
        self.inv.transform_vector3(v)
    }
    /// Object normal to a unit world normal (inverse transpose keeps the outward side).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal * n).normalize()
    }
    /// Whether this is exactly the identity (then points, vectors and normals map to
    /// themselves bit for bit, up to the sign of zero).
    pub fn is_identity(&self) -> bool {
        self.m == DMat4::IDENTITY
    }
    /// Mean length scale factor |det|^(1/3) (for uv scales in mm).
    pub fn scale(&self) -> f64 {
        self.scale
    }
    /// A lower bound on the factor by which the transform shortens any vector: a world
    /// distance is at least this times the object-space distance it maps from.
    pub fn min_stretch(&self) -> f64 {
        self.min_stretch
    }
    /// World bounds of an object-space box.
    pub fn bounds(&self, b: &Aabb) -> Aabb {
        b.corners()
            .iter()
            .fold(Aabb::EMPTY, |acc, c| acc.grow(self.point(*c)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_major_translation_and_normals() {
        let t = Transform::from_rows(
            "t",
            [
                [2.0, 0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0, 2.0],
                [0.0, 0.0, 1.0, 3.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
        )
        .unwrap();
        assert!((t.point(Vec3::new(1.0, 1.0, 1.0)) - Vec3::new(3.0, 3.0, 4.0)).length() < 1e-12);
        assert!((t.inv_point(Vec3::new(3.0, 3.0, 4.0)) - Vec3::ONE).length() < 1e-12);
        // a plane x + y = c stretched along x: its normal tilts towards y
        let n = t.normal(Vec3::new(1.0, 1.0, 0.0).normalize());
        assert!((n - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-12);
        assert!((t.scale() - 2f64.cbrt()).abs() < 1e-12);
    }

    #[test]
    fn min_stretch_bounds_every_direction() {
        let mut rng = crate::rng::Stream::new(9, 0, 0);
        let rows = [
            // a scale: the bound is its smallest factor
            [
                [2.0, 0.0, 0.0, 1.0],
                [0.0, 0.5, 0.0, 0.0],
                [0.0, 0.0, 3.0, 0.0],
            ],
            // a rotation about z by 30° with a shear
            [
                [0.866, -0.5, 0.2, 0.0],
                [0.5, 0.866, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
        ];
        for (i, r) in rows.iter().enumerate() {
            let t = Transform::from_rows("t", [r[0], r[1], r[2], [0.0, 0.0, 0.0, 1.0]]).unwrap();
            let shortest = (0..20_000)
                .map(|_| {
                    t.vector(crate::sampling::uniform_sphere(rng.uniform2()))
                        .length()
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                t.min_stretch() <= shortest + 1e-12,
                "{i}: {}",
                t.min_stretch()
            );
            assert!(t.min_stretch() > 0.5 * shortest, "{i}: {}", t.min_stretch());
        }
        let scale = Transform::from_rows(
            "t",
            [
                [2.0, 0.0, 0.0, 0.0],
                [0.0, 0.5, 0.0, 0.0],
                [0.0, 0.0, 3.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
        )
        .unwrap();
        assert!((scale.min_stretch() - 0.5).abs() < 1e-12);
        assert_eq!(Transform::identity().min_stretch(), 1.0);
    }

    #[test]
    fn rejects_singular_and_projective() {
        let mut r = [[0.0; 4]; 4];
        r[3][3] = 1.0;
        assert!(Transform::from_rows("shapes[0].transform", r)
            .unwrap_err()
            .to_string()
            .contains("shapes[0].transform is singular"));
        let mut p = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0; 4],
        ];
        p[3][2] = 1.0;
        assert!(Transform::from_rows("x", p).is_err());
    }
}
