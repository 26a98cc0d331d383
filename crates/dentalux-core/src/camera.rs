//! A perspective pinhole camera: position, look-at point, up vector, vertical field of view
//! and resolution. Pixel (0, 0) is the top-left of the image; rows run downwards.

use crate::error::{check_range, Error, Result};
use crate::geometry::{Ray, Vec3};

/// A pinhole camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Pinhole position [mm].
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit image-right direction.
    pub right: Vec3,
    /// Unit image-up direction.
    pub up: Vec3,
    /// tan(vertical fov / 2).
    pub tan_half_fov: f64,
    /// Image width [pixels].
    pub width: usize,
    /// Image height [pixels].
    pub height: usize,
}

impl Camera {
    /// A camera at `position` looking at `look_at`, `up` roughly up, vertical field of view
    /// `fov_deg` [degrees] in (0, 180), `width` × `height` pixels.
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_deg: f64,
        width: usize,
        height: usize,
    ) -> Result<Self> {
        check_range("camera.fov_deg", fov_deg, 0.0, true, 180.0, true, "degrees")?;
        for (k, v) in [("camera.width", width), ("camera.height", height)] {
            if v == 0 || v > 1 << 16 {
                return Err(Error::InvalidInput(format!(
                    "{k} = {v} is out of range: allowed [1, 65536] pixels"
                )));
            }
        }
        if width * height > 1 << 28 {
            return Err(Error::InvalidInput(format!(
                "camera.width × camera.height = {} pixels is too many: allowed ≤ 2^28 per band",
                width * height
            )));
        }
        let f = look_at - position;
        if !f.is_finite() || f.length() == 0.0 {
            return Err(Error::InvalidInput(
                "camera.look_at must differ from camera.position".into(),
            ));
        }
        let forward = f.normalize();
        let right = forward.cross(up);
        if !right.is_finite() || right.length() < 1e-9 * up.length().max(1e-300) {
            return Err(Error::InvalidInput(
                "camera.up must not be parallel to the viewing direction (look_at − position)"
                    .into(),
            ));
        }
        let right = right.normalize();
        Ok(Self {
            position,
            forward,
            right,
            up: right.cross(forward),
            tan_half_fov: (0.5 * fov_deg.to_radians()).tan(),
            width,
            height,
        })
    }

    /// The ray through film position (x, y) in pixels, x in [0, width), y in [0, height)
    /// from the top-left corner.
    #[inline]
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let aspect = self.width as f64 / self.height as f64;
        let sx = (2.0 * x / self.width as f64 - 1.0) * aspect * self.tan_half_fov;
        let sy = (1.0 - 2.0 * y / self.height as f64) * self.tan_half_fov;
        Ray::new(self.position, self.forward + self.right * sx + self.up * sy)
    }

    /// The film position (x, y) in pixels of world point `p` [mm]: the inverse of
    /// [`Self::ray`], so that `ray(x, y)` passes through `p`. `None` for points at or behind
    /// the pinhole's plane. Image regions are placed with this (Python's
    /// `dentalux.scene.project`), so they follow the same handedness as the render: with
    /// `right = forward × up`, a camera looking along +z with +y up sees +x on the left.
    pub fn project(&self, p: Vec3) -> Option<(f64, f64)> {
        let d = p - self.position;
        let depth = d.dot(self.forward);
        if depth.is_nan() || depth <= 0.0 || !d.is_finite() {
            return None;
        }
        let aspect = self.width as f64 / self.height as f64;
        let sx = d.dot(self.right) / depth;
        let sy = d.dot(self.up) / depth;
        let x = (sx / (aspect * self.tan_half_fov) + 1.0) * 0.5 * self.width as f64;
        let y = (1.0 - sy / self.tan_half_fov) * 0.5 * self.height as f64;
        Some((x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_ray() {
        let c = Camera::new(
            Vec3::new(1.0, 2.0, -30.0),
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.1, 1.0, 0.0),
            33.0,
            160,
            90,
        )
        .unwrap();
        for &(x, y) in &[(0.0, 0.0), (80.0, 45.0), (159.5, 3.25), (12.0, 88.0)] {
            let r = c.ray(x, y);
            let (px, py) = c.project(r.o + r.d * 7.3).unwrap();
            assert!(
                (px - x).abs() < 1e-9 && (py - y).abs() < 1e-9,
                "{x},{y} -> {px},{py}"
            );
        }
    }

    #[test]
    fn centre_and_corner_rays() {
        let c = Camera::new(Vec3::ZERO, -Vec3::Z, Vec3::Y, 90.0, 200, 100).unwrap();
        let r = c.ray(100.0, 50.0);
        assert!((r.d + Vec3::Z).length() < 1e-12);
        // top edge centre: 45° up
        let r = c.ray(100.0, 0.0);
        assert!((r.d - Vec3::new(0.0, 1.0, -1.0).normalize()).length() < 1e-12);
        // right edge: tan = aspect · tan(45°) = 2
        let r = c.ray(200.0, 50.0);
        assert!((r.d - Vec3::new(2.0, 0.0, -1.0).normalize()).length() < 1e-12);
        assert!(Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0, 4, 4).is_err());
        // looking along +z with +y up, +x is on the image's left (right = forward × up)
        let c = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 64, 48).unwrap();
        assert!(c.project(Vec3::new(1.0, 0.0, 10.0)).unwrap().0 < 32.0);
        assert!(c.project(Vec3::new(0.0, 0.0, -1.0)).is_none());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 0.0, 4, 4).is_err());
        assert!(Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 65536, 65536).is_err());
    }
}
