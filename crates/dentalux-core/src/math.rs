//! Vectors, orthonormal frames and rays (f64, via glam).
//!
//! Direction convention, stated once: `wo` points *away* from the scattering point towards
//! where the light goes (the viewer, or the next vertex of a photon path); `wi` points away
//! from the point towards where the light comes from. A photon travelling along `d`
//! therefore arrives with `wi = -d`. The phase functions here depend only on the
//! scattering angle θ between the old and new *travel* directions, cos θ = d_old · d_new.

pub use glam::DVec3 as Vec3;

/// An orthonormal basis (s, t, n) with n the given axis.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Axis.
    pub n: Vec3,
}

impl Frame {
    /// Frame around a unit vector `n` (branchless construction of Duff et al. 2017).
    pub fn from_axis(n: Vec3) -> Self {
        let sign = 1.0f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }
    /// Local coordinates (x along s, y along t, z along n) to world.
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
    /// World to local coordinates.
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// Direction with polar cosine `cos_theta` and azimuth `phi` about the unit axis `axis`.
pub fn direction_about(axis: Vec3, cos_theta: f64, phi: f64) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (sp, cp) = phi.sin_cos();
    Frame::from_axis(axis)
        .to_world(Vec3::new(sin_theta * cp, sin_theta * sp, cos_theta))
        .normalize()
}

/// Rotate the unit travel direction `d` by polar angle θ and azimuth φ (given as cosines and
/// sine): the spin of a photon at a scattering event. Uses the rotation-about-`d` formula that
/// avoids building a frame; falls back to the z axis when `d` is (anti)parallel to it.
#[inline]
pub fn rotate_direction(d: Vec3, cos_theta: f64, cos_phi: f64, sin_phi: f64) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (ux, uy, uz) = (d.x, d.y, d.z);
    if uz.abs() > 0.999_999 {
        return Vec3::new(
            sin_theta * cos_phi,
            sin_theta * sin_phi,
            cos_theta * uz.signum(),
        );
    }
    let tmp = (1.0 - uz * uz).sqrt();
    let st_t = sin_theta / tmp;
    Vec3::new(
        st_t * (ux * uz * cos_phi - uy * sin_phi) + ux * cos_theta,
        st_t * (uy * uz * cos_phi + ux * sin_phi) + uy * cos_theta,
        -sin_theta * cos_phi * tmp + uz * cos_theta,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_awkward_axes() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.0, -1e-12, -1.0).normalize(),
            Vec3::new(1.0, 2.0, -3.0).normalize(),
        ] {
            let f = Frame::from_axis(n);
            assert!((f.s.length() - 1.0).abs() < 1e-12);
            assert!((f.t.length() - 1.0).abs() < 1e-12);
            assert!(f.s.dot(f.t).abs() < 1e-12 && f.s.dot(n).abs() < 1e-12);
            let v = Vec3::new(0.3, -0.4, 0.5);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-12);
        }
    }

    #[test]
    fn rotation_keeps_unit_length_and_cosine() {
        for d in [
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
        ] {
            let (s, c) = 0.7f64.sin_cos();
            let w = rotate_direction(d, -0.25, c, s);
            assert!((w.length() - 1.0).abs() < 1e-12);
            assert!((w.dot(d) + 0.25).abs() < 1e-5);
        }
    }

    #[test]
    fn direction_about_has_requested_cosine() {
        let axis = Vec3::new(0.2, -0.5, 0.8).normalize();
        let d = direction_about(axis, 0.3, 1.234);
        assert!((d.dot(axis) - 0.3).abs() < 1e-12);
    }
}
