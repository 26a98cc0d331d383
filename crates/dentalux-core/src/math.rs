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
    let (sp, cp) = phi.sin_cos();
    direction_about_cs(axis, cos_theta, (cp, sp))
}

/// [`direction_about`] with the azimuth given as (cos φ, sin φ).
#[inline]
pub fn direction_about_cs(axis: Vec3, cos_theta: f64, (cp, sp): (f64, f64)) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Frame::from_axis(axis)
        .to_world(Vec3::new(sin_theta * cp, sin_theta * sp, cos_theta))
        .normalize()
}

/// Rotate the unit travel direction `d` by polar angle θ and azimuth φ (given as cosines and
/// sine): the spin of a photon at a scattering event. Uses the rotation-about-`d` formula that
/// avoids building a frame; falls back to the z axis when `d` is within 1e-10 rad of it,
/// where the general formula would divide by nearly zero. sin of the polar angle of `d` is
/// taken as √(dx² + dy²), not √(1 − dz²), which loses digits near the poles.
#[inline]
pub fn rotate_direction(d: Vec3, cos_theta: f64, cos_phi: f64, sin_phi: f64) -> Vec3 {
    rotate_direction_scaled(d, cos_theta, cos_phi, sin_phi, 1.0)
}

/// [`rotate_direction`] with the azimuth given as (ρ cos φ, ρ sin φ, ρ) for any ρ > 0, as
/// [`crate::sampling::sample_azimuth_scaled`] returns it: the normalisation by ρ is folded
/// into the one division the rotation needs anyway.
#[inline]
pub fn rotate_direction_scaled(d: Vec3, cos_theta: f64, c: f64, s: f64, rho: f64) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (ux, uy, uz) = (d.x, d.y, d.z);
    let tmp2 = ux * ux + uy * uy;
    if tmp2 < 1e-20 {
        let k = sin_theta / rho;
        return Vec3::new(k * c, k * s, cos_theta * uz.signum());
    }
    let tmp = tmp2.sqrt();
    // sinθ / (ρ sinΘ_d): one division for the azimuth and the frame
    let st_t = sin_theta / (tmp * rho);
    Vec3::new(
        st_t * (ux * uz * c - uy * s) + ux * cos_theta,
        st_t * (uy * uz * c + ux * s) + uy * cos_theta,
        -st_t * c * tmp2 + uz * cos_theta,
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
            // just outside the fallback cone: the general formula must stay accurate
            Vec3::new(2e-5, 0.0, 1.0).normalize(),
            Vec3::new(0.0, -3e-5, -1.0).normalize(),
        ] {
            let (s, c) = 0.7f64.sin_cos();
            let w = rotate_direction(d, -0.25, c, s);
            assert!((w.length() - 1.0).abs() < 1e-9, "{d:?}");
            assert!((w.dot(d) + 0.25).abs() < 1e-9, "{d:?}");
            let v = rotate_direction_scaled(d, -0.25, 3.0 * c, 3.0 * s, 3.0);
            assert!((v - w).length() < 1e-14, "{d:?}");
        }
    }

    /// A photon spins up to millions of times without renormalising: the length must not
    /// drift, including through the near-polar directions that forward scattering visits.
    #[test]
    fn repeated_rotations_do_not_drift() {
        let mut rng = crate::rng::Stream::new(1, 0, 0);
        let mut d = Vec3::Z;
        for i in 0..1_000_000 {
            // strongly forward cosines (as g = 0.96 gives) and some back-scatter
            let cos_theta = if i % 7 == 0 {
                2.0 * rng.uniform() - 1.0
            } else {
                1.0 - 1e-9 * rng.uniform()
            };
            let (s, c) = (2.0 * std::f64::consts::PI * rng.uniform()).sin_cos();
            d = rotate_direction(d, cos_theta, c, s);
        }
        assert!((d.length() - 1.0).abs() < 1e-9, "{}", d.length());
    }

    #[test]
    fn direction_about_has_requested_cosine() {
        let axis = Vec3::new(0.2, -0.5, 0.8).normalize();
        let d = direction_about(axis, 0.3, 1.234);
        assert!((d.dot(axis) - 0.3).abs() < 1e-12);
    }
}
