//! Smooth dielectric interfaces: unpolarised Fresnel reflectance, Snell refraction and total
//! internal reflection. `eta_i` is the index on the side the light comes from.

use crate::math::Vec3;

/// Unpolarised Fresnel reflectance for light arriving from index `eta_i` into `eta_t`
/// with |cos θ_i| = `cos_i`. Returns 1 under total internal reflection.
#[inline]
pub fn reflectance(cos_i: f64, eta_i: f64, eta_t: f64) -> f64 {
    reflectance_and_cos_t(cos_i, eta_i, eta_t).0
}

/// Fresnel reflectance and the transmitted |cos θ_t| in one go (cos_t = 0 under TIR).
#[inline]
pub fn reflectance_and_cos_t(cos_i: f64, eta_i: f64, eta_t: f64) -> (f64, f64) {
    let cos_i = cos_i.abs().min(1.0);
    if eta_i == eta_t {
        return (0.0, cos_i);
    }
    let sin_t = eta_i / eta_t * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

/// Refract travel direction `d` through a surface with unit normal `n` (either side),
/// from index `eta_i` into `eta_t`. `None` under total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta_i: f64, eta_t: f64) -> Option<Vec3> {
    // orient the normal against the travel direction
    let n = if d.dot(n) > 0.0 { -n } else { n };
    let cos_i = -d.dot(n);
    let eta = eta_i / eta_t;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((d * eta + n * (eta * cos_i - cos_t)).normalize())
}

/// Mirror travel direction `d` about the surface with normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_closed_form() {
        for (n1, n2) in [(1.0, 1.5), (1.5, 1.0), (1.0, 1.63), (1.54, 1.63)] {
            let r = reflectance(1.0, n1, n2);
            let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
            assert!((r - r0).abs() < 1e-14);
        }
        // docs/explanation/tooth-optics.md 2.5: R0 = 0.0574 for n = 1.63
        assert!((reflectance(1.0, 1.0, 1.63) - 0.0574).abs() < 5e-5);
    }

    #[test]
    fn grazing_tir_and_matched_limits() {
        assert!((reflectance(0.0, 1.0, 1.5) - 1.0).abs() < 1e-12);
        assert_eq!(reflectance(0.3, 1.5, 1.0), 1.0); // sin_t = 1.43 > 1
        assert_eq!(reflectance(0.3, 1.33, 1.33), 0.0);
        let d = Vec3::new(0.95, 0.0, -0.3122).normalize();
        assert!(refract(d, Vec3::Z, 1.5, 1.0).is_none());
    }

    #[test]
    fn refraction_obeys_snell_and_reciprocity() {
        let d = Vec3::new(0.6, 0.0, -0.8);
        let t = refract(d, Vec3::Z, 1.0, 1.5).unwrap();
        assert!((0.6 - 1.5 * t.x).abs() < 1e-12); // n1 sinθ1 = n2 sinθ2
        assert!(t.z < 0.0);
        let back = refract(-t, Vec3::Z, 1.5, 1.0).unwrap();
        assert!((back + d).length() < 1e-12);
        // reflectance is the same from both sides at reciprocal angles
        assert!((reflectance(0.8, 1.0, 1.5) - reflectance(-t.z, 1.5, 1.0)).abs() < 1e-12);
        assert!((reflect(d, Vec3::Z) - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-15);
    }
}
