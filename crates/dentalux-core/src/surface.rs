//! Opaque surface materials: Lambertian reflectance, constant or from a texture (checker on
//! the shape's uv or on world xy, an image), or black. Reflectance ρ is at one band; the
//! BRDF is ρ/π on both sides of the surface.

use crate::error::{check_positive, check_range, Error, Result};
use crate::geometry::{Hit, Vec3};

/// Where a texture looks up its coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mapping {
    /// The shape's uv, scaled to mm by the shape's uv extent (see `ShapeInstance::uv_scale`).
    Uv,
    /// World x and y [mm] (a checker lying on a horizontal ribbon).
    Xy,
}

/// A Lambertian surface material.
#[derive(Debug, Clone, PartialEq)]
pub enum Surface {
    /// Constant reflectance ρ in [0, 1].
    Lambertian {
        /// Reflectance ρ.
        reflectance: f64,
    },
    /// Checks of side `size` [mm] alternating between reflectances `a` and `b`.
    Checker {
        /// Reflectance of the check holding the origin.
        a: f64,
        /// Reflectance of the other checks.
        b: f64,
        /// Side of one check [mm].
        size: f64,
        /// Coordinates used.
        mapping: Mapping,
    },
    /// A reflectance image, row 0 at the top (v = 1), nearest-pixel lookup, repeated.
    Image {
        /// Pixels across.
        width: usize,
        /// Pixels down.
        height: usize,
        /// Row-major reflectances in [0, 1].
        data: Vec<f64>,
        /// Coordinates used; with `Xy` one image covers `size` mm.
        mapping: Mapping,
        /// Side [mm] that one repeat of the image covers with `Xy` mapping.
        size: f64,
    },
    /// Reflects nothing.
    Black,
}

impl Surface {
    /// Check ranges; `field` prefixes error messages (e.g. `surfaces[1]`).
    pub fn validate(&self, field: &str) -> Result<()> {
        let unit =
            |k: &str, v: f64| check_range(&format!("{field}.{k}"), v, 0.0, false, 1.0, false, "");
        match self {
            Surface::Lambertian { reflectance } => unit("reflectance", *reflectance),
            Surface::Checker { a, b, size, .. } => {
                unit("a", *a)?;
                unit("b", *b)?;
                check_positive(&format!("{field}.size"), *size, "mm")
            }
            Surface::Image {
                width,
                height,
                data,
                size,
                ..
            } => {
                if *width == 0 || *height == 0 || data.len() != width * height {
                    return Err(Error::InvalidInput(format!(
                        "{field}.data has {} values; width × height = {} × {} (both ≥ 1) needed",
                        data.len(),
                        width,
                        height
                    )));
                }
                for (i, v) in data.iter().enumerate() {
                    check_range(
                        &format!("{field}.data[{i}]"),
                        *v,
                        0.0,
                        false,
                        1.0,
                        false,
                        "",
                    )?;
                }
                check_positive(&format!("{field}.size"), *size, "mm")
            }
            Surface::Black => Ok(()),
        }
    }

    /// Reflectance ρ at a hit; `uv_scale` [mm per unit uv] of the shape hit.
    #[inline]
    pub fn reflectance(&self, hit: &Hit, uv_scale: [f64; 2]) -> f64 {
        match self {
            Surface::Lambertian { reflectance } => *reflectance,
            Surface::Black => 0.0,
            Surface::Checker {
                a,
                b,
                size,
                mapping,
            } => {
                let (x, y) = coords(hit, *mapping, uv_scale);
                let i = (x / size).floor() as i64 + (y / size).floor() as i64;
                if i.rem_euclid(2) == 0 {
                    *a
                } else {
                    *b
                }
            }
            Surface::Image {
                width,
                height,
                data,
                mapping,
                size,
            } => {
                let (s, t) = match mapping {
                    Mapping::Uv => (hit.uv[0], hit.uv[1]),
                    Mapping::Xy => (hit.p.x / size, hit.p.y / size),
                };
                let (s, t) = (s.rem_euclid(1.0), t.rem_euclid(1.0));
                let col = ((s * *width as f64) as usize).min(width - 1);
                let row = (((1.0 - t) * *height as f64) as usize).min(height - 1);
                data[row * width + col]
            }
        }
    }
}

/// Texture coordinates [mm] for a mapping.
fn coords(hit: &Hit, mapping: Mapping, uv_scale: [f64; 2]) -> (f64, f64) {
    match mapping {
        Mapping::Uv => (hit.uv[0] * uv_scale[0], hit.uv[1] * uv_scale[1]),
        Mapping::Xy => (hit.p.x, hit.p.y),
    }
}

/// A hit at point `p` with uv (for tests).
#[doc(hidden)]
pub fn test_hit(p: Vec3, uv: [f64; 2]) -> Hit {
    Hit {
        t: 1.0,
        p,
        n: Vec3::Z,
        uv,
        shape: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checker_alternates_in_xy_and_uv() {
        let c = Surface::Checker {
            a: 0.9,
            b: 0.1,
            size: 2.0,
            mapping: Mapping::Xy,
        };
        assert_eq!(
            c.reflectance(&test_hit(Vec3::new(0.5, 0.5, 0.0), [0.0; 2]), [1.0; 2]),
            0.9
        );
        assert_eq!(
            c.reflectance(&test_hit(Vec3::new(2.5, 0.5, 0.0), [0.0; 2]), [1.0; 2]),
            0.1
        );
        assert_eq!(
            c.reflectance(&test_hit(Vec3::new(-0.5, 0.5, 0.0), [0.0; 2]), [1.0; 2]),
            0.1
        );
        let u = Surface::Checker {
            a: 0.9,
            b: 0.1,
            size: 2.0,
            mapping: Mapping::Uv,
        };
        // a 10 mm wide quad: uv 0.25 is 2.5 mm along, in the second check
        assert_eq!(
            u.reflectance(&test_hit(Vec3::ZERO, [0.25, 0.0]), [10.0, 10.0]),
            0.1
        );
        assert!(u.validate("surfaces[0]").is_ok());
        let bad = Surface::Checker {
            a: 1.5,
            b: 0.1,
            size: 2.0,
            mapping: Mapping::Uv,
        };
        assert!(bad
            .validate("surfaces[3]")
            .unwrap_err()
            .to_string()
            .contains("surfaces[3].a"));
    }

    #[test]
    fn image_rows_start_at_the_top() {
        let im = Surface::Image {
            width: 2,
            height: 2,
            data: vec![0.1, 0.2, 0.3, 0.4],
            mapping: Mapping::Uv,
            size: 1.0,
        };
        assert_eq!(
            im.reflectance(&test_hit(Vec3::ZERO, [0.25, 0.75]), [1.0; 2]),
            0.1
        );
        assert_eq!(
            im.reflectance(&test_hit(Vec3::ZERO, [0.75, 0.25]), [1.0; 2]),
            0.4
        );
        let bad = Surface::Image {
            width: 2,
            height: 2,
            data: vec![0.1],
            mapping: Mapping::Uv,
            size: 1.0,
        };
        assert!(bad.validate("surfaces[0]").is_err());
    }
}
