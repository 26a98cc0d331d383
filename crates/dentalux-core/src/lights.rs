//! Light sources at one band: one-sided rectangular (quad) and disc area lights, a point
//! light and a spot light. Each can be sampled from a shading point (next-event
//! estimation), can emit photons, and knows its total power Φ.
//!
//! Units: `radiance` L in W/(mm²·sr·nm) up to one global scale, `intensity` I in
//! W/(sr·nm); power Φ = π·L·A for a one-sided Lambertian emitter of area A, 4π·I for a
//! point light, 2π·I·∫ falloff(μ) dμ for a spot light.
//!
//! Area lights are emitters only: they are not in the BVH and cast no shadow; a camera ray
//! (or a ray after a specular bounce) sees them through [`Light::le`] from their front side.

use crate::error::{check_positive, check_range, Error, Result};
use crate::geometry::{Ray, Vec3};
use crate::math::Frame;
use crate::sampling::{cosine_hemisphere, uniform_disc, uniform_sphere};
use std::f64::consts::PI;

/// A point on an area light: where, its radiance, its unit emitting normal, the light's area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaPoint {
    /// Position [mm].
    pub point: Vec3,
    /// Emitted radiance (towards `normal` only).
    pub radiance: f64,
    /// Unit normal of the emitting side.
    pub normal: Vec3,
    /// Area of the whole light [mm²] (1 / the sampling pdf).
    pub area: f64,
}

/// A light source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// Parallelogram corner + s·u + t·v emitting radiance L towards u × v only.
    Quad {
        /// Corner [mm].
        corner: Vec3,
        /// First edge [mm].
        u: Vec3,
        /// Second edge [mm].
        v: Vec3,
        /// Emitted radiance L.
        radiance: f64,
    },
    /// Disc emitting radiance L along `normal` only.
    Disc {
        /// Centre [mm].
        center: Vec3,
        /// Unit emitting normal.
        normal: Vec3,
        /// Radius [mm].
        radius: f64,
        /// Emitted radiance L.
        radiance: f64,
    },
    /// Isotropic point light of intensity I.
    Point {
        /// Position [mm].
        position: Vec3,
        /// Intensity I.
        intensity: f64,
    },
    /// Spot light: I inside `cos_start`, smoothstep to 0 at `cos_total`.
    Spot {
        /// Position [mm].
        position: Vec3,
        /// Unit axis.
        direction: Vec3,
        /// Intensity I on the axis.
        intensity: f64,
        /// cos(cone angle): no light beyond it.
        cos_total: f64,
        /// cos(cone − falloff): full intensity inside it.
        cos_start: f64,
    },
}

/// A sample of light arriving at a shading point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Distance to the sampled light point [mm].
    pub dist: f64,
    /// Incident radiance divided by the solid-angle pdf: the reflected radiance is
    /// f · value · |cos θ| at the receiver (for a point light, value = I/r²).
    pub value: f64,
}

impl Light {
    /// A spot light from angles in degrees: `cone_deg` in (0, 180], `falloff_deg` in
    /// [0, cone_deg].
    pub fn spot(
        field: &str,
        position: Vec3,
        direction: Vec3,
        intensity: f64,
        cone_deg: f64,
        falloff_deg: f64,
    ) -> Result<Self> {
        check_range(
            &format!("{field}.cone_deg"),
            cone_deg,
            0.0,
            true,
            180.0,
            false,
            "degrees",
        )?;
        check_range(
            &format!("{field}.falloff_deg"),
            falloff_deg,
            0.0,
            false,
            cone_deg,
            false,
            "degrees",
        )?;
        Ok(Light::Spot {
            position,
            direction: unit(&format!("{field}.direction"), direction)?,
            intensity,
            cos_total: cone_deg.to_radians().cos(),
            cos_start: (cone_deg - falloff_deg).to_radians().cos(),
        })
    }

    /// Whether `other` is the same light in the same place, whatever it emits (the bands of
    /// one scene differ only in their lights' radiance or intensity).
    pub fn same_place(&self, other: &Light) -> bool {
        let mut a = *self;
        let mut b = *other;
        for l in [&mut a, &mut b] {
            match l {
                Light::Quad { radiance, .. } | Light::Disc { radiance, .. } => *radiance = 0.0,
                Light::Point { intensity, .. } | Light::Spot { intensity, .. } => *intensity = 0.0,
            }
        }
        a == b
    }

    /// Check sizes and emission; `field` prefixes errors (e.g. `lights[0]`).
    pub fn validate(&self, field: &str) -> Result<()> {
        let nonneg = |k: &str, v: f64, unit: &str| {
            check_range(
                &format!("{field}.{k}"),
                v,
                0.0,
                false,
                f64::INFINITY,
                true,
                unit,
            )
        };
        match *self {
            Light::Quad { u, v, radiance, .. } => {
                nonneg("radiance", radiance, "")?;
                if u.cross(v).length() <= 0.0 || !u.is_finite() || !v.is_finite() {
                    return Err(Error::InvalidInput(format!(
                        "{field}: u and v must be finite, non-zero and not parallel"
                    )));
                }
                Ok(())
            }
            Light::Disc {
                radius,
                radiance,
                normal,
                ..
            } => {
                nonneg("radiance", radiance, "")?;
                check_positive(&format!("{field}.radius"), radius, "mm")?;
                unit(&format!("{field}.normal"), normal).map(|_| ())
            }
            Light::Point { intensity, .. } => nonneg("intensity", intensity, ""),
            Light::Spot { intensity, .. } => nonneg("intensity", intensity, ""),
        }
    }

    /// Total emitted power Φ.
    pub fn power(&self) -> f64 {
        match *self {
            Light::Quad { u, v, radiance, .. } => PI * radiance * u.cross(v).length(),
            Light::Disc {
                radius, radiance, ..
            } => PI * radiance * PI * radius * radius,
            Light::Point { intensity, .. } => 4.0 * PI * intensity,
            Light::Spot {
                intensity,
                cos_total,
                cos_start,
                ..
            } => {
                // ∫ falloff dμ: 1 over [cos_start, 1], the smoothstep averages ½ over the rest
                2.0 * PI * intensity * ((1.0 - cos_start) + 0.5 * (cos_start - cos_total))
            }
        }
    }

    /// A point of an area light, uniform in its area, from uniforms `u` (`None` for point
    /// and spot lights).
    pub fn area_point(&self, u: [f64; 2]) -> Option<AreaPoint> {
        match *self {
            Light::Quad {
                corner,
                u: eu,
                v: ev,
                radiance,
            } => {
                let nn = eu.cross(ev);
                Some(AreaPoint {
                    point: corner + eu * u[0] + ev * u[1],
                    radiance,
                    normal: nn.normalize(),
                    area: nn.length(),
                })
            }
            Light::Disc {
                center,
                normal,
                radius,
                radiance,
            } => {
                let (x, y) = uniform_disc(u);
                let f = Frame::from_axis(normal);
                Some(AreaPoint {
                    point: center + f.to_world(Vec3::new(x, y, 0.0)) * radius,
                    radiance,
                    normal,
                    area: PI * radius * radius,
                })
            }
            Light::Point { .. } | Light::Spot { .. } => None,
        }
    }

    /// Sample light arriving at `p` from uniforms `u`; `None` when no light can arrive
    /// (behind a one-sided emitter, outside a spot's cone, or zero emission).
    #[inline]
    pub fn sample_li(&self, p: Vec3, u: [f64; 2]) -> Option<LightSample> {
        match *self {
            Light::Point {
                position,
                intensity,
            } => return delta_sample(p, position, intensity),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_total,
                cos_start,
            } => {
                let s = delta_sample(p, position, intensity)?;
                let f = falloff(-s.wi.dot(direction), cos_total, cos_start);
                return (f > 0.0).then_some(LightSample {
                    value: s.value * f,
                    ..s
                });
            }
            _ => {}
        }
        let AreaPoint {
            point: q,
            radiance,
            normal: n,
            area,
        } = self.area_point(u)?;
        let w = q - p;
        let dist2 = w.length_squared();
        let dist = dist2.sqrt();
        let wi = w / dist;
        let cos_l = -wi.dot(n);
        if cos_l <= 0.0 || radiance <= 0.0 || dist == 0.0 {
            return None;
        }
        // area sampling: pdf_ω = dist² / (A cos θ_l)
        Some(LightSample {
            wi,
            dist,
            value: radiance * cos_l * area / dist2,
        })
    }

    /// Emit a photon: a ray from the light and its weight, whose mean over the uniforms is
    /// the power Φ (a photon of N carries weight/N).
    pub fn sample_emission(&self, u1: [f64; 2], u2: [f64; 2]) -> (Ray, f64) {
        // area lights: a uniform point, a cosine-distributed direction about the normal
        if let Some(a) = self.area_point(u1) {
            let d = Frame::from_axis(a.normal).to_world(cosine_hemisphere(u2));
            return (Ray::new(a.point, d), self.power());
        }
        match *self {
            // handled above (`area_point` is `Some` for them)
            Light::Quad { .. } | Light::Disc { .. } => (Ray::new(Vec3::ZERO, Vec3::Z), 0.0),
            Light::Point { position, .. } => (Ray::new(position, uniform_sphere(u1)), self.power()),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_total,
                cos_start,
            } => {
                // uniform in the cone's solid angle, weighted by the falloff
                let mu = 1.0 - u1[0] * (1.0 - cos_total);
                let d = crate::math::direction_about(direction, mu, 2.0 * PI * u1[1]);
                let w =
                    intensity * falloff(mu, cos_total, cos_start) * 2.0 * PI * (1.0 - cos_total);
                (Ray::new(position, d), w)
            }
        }
    }

    /// Radiance a ray sees on the emitter's front side, with its distance, if it meets the
    /// emitter before `t_max` (area lights only; point and spot lights are never seen).
    #[inline]
    pub fn le(&self, ray: &Ray, t_max: f64) -> Option<(f64, f64)> {
        match *self {
            Light::Quad {
                corner,
                u,
                v,
                radiance,
            } => {
                let q = crate::geometry::shapes::Quad { corner, u, v };
                let h = q.intersect(ray.o, ray.d, t_max)?;
                (ray.d.dot(h.n) < 0.0).then_some((radiance, h.t))
            }
            Light::Disc {
                center,
                normal,
                radius,
                radiance,
            } => {
                let denom = ray.d.dot(normal);
                if denom >= 0.0 {
                    return None;
                }
                let t = (center - ray.o).dot(normal) / denom;
                if !(t > 0.0 && t < t_max)
                    || (ray.at(t) - center).length_squared() > radius * radius
                {
                    return None;
                }
                Some((radiance, t))
            }
            Light::Point { .. } | Light::Spot { .. } => None,
        }
    }
}

/// Sample of a point-like source of intensity I at `q` seen from `p`.
#[inline]
fn delta_sample(p: Vec3, q: Vec3, intensity: f64) -> Option<LightSample> {
    let w = q - p;
    let dist2 = w.length_squared();
    if dist2 == 0.0 || intensity <= 0.0 {
        return None;
    }
    let dist = dist2.sqrt();
    Some(LightSample {
        wi: w / dist,
        dist,
        value: intensity / dist2,
    })
}

/// Spot falloff at cos θ from the axis: 1 inside `cos_start`, 0 beyond `cos_total`,
/// smoothstep between.
#[inline]
fn falloff(cos: f64, cos_total: f64, cos_start: f64) -> f64 {
    if cos >= cos_start {
        1.0
    } else if cos <= cos_total {
        0.0
    } else {
        let x = (cos - cos_total) / (cos_start - cos_total);
        x * x * (3.0 - 2.0 * x)
    }
}

/// `v` normalised, or an error naming `field` when it is zero or not finite.
pub fn unit(field: &str, v: Vec3) -> Result<Vec3> {
    let l = v.length();
    if !(l.is_finite() && l > 0.0) {
        return Err(Error::InvalidInput(format!(
            "{field} must be a finite non-zero vector, got {v}"
        )));
    }
    Ok(v / l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Stream;

    /// E at a point under the light by light sampling equals the closed form.
    #[test]
    fn disc_irradiance_on_axis_matches_closed_form() {
        let l = Light::Disc {
            center: Vec3::new(0.0, 0.0, 2.0),
            normal: -Vec3::Z,
            radius: 1.5,
            radiance: 3.0,
        };
        let mut rng = Stream::new(5, 0, 0);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = l
                .sample_li(Vec3::ZERO, rng.uniform2())
                .map_or(0.0, |ls| ls.value * ls.wi.z);
            s += x;
            s2 += x * x;
        }
        let mean = s / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
        // E = π L r² / (r² + h²) on the axis of a Lambertian disc
        let exact = PI * 3.0 * 1.5f64.powi(2) / (1.5f64.powi(2) + 4.0);
        assert!((mean - exact).abs() < 4.0 * se, "{mean} vs {exact} ± {se}");
        // behind the disc nothing arrives
        assert!(l.sample_li(Vec3::new(0.0, 0.0, 3.0), [0.3, 0.3]).is_none());
    }

    #[test]
    fn emission_weights_average_to_power() {
        let spot = Light::spot("l", Vec3::ZERO, Vec3::Z, 2.0, 40.0, 15.0).unwrap();
        let mut rng = Stream::new(6, 0, 0);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let (ray, w) = spot.sample_emission(rng.uniform2(), rng.uniform2());
            assert!(ray.d.z >= 40f64.to_radians().cos() - 1e-12);
            s += w;
            s2 += w * w;
        }
        let mean = s / n as f64;
        let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
        assert!((mean - spot.power()).abs() < 4.0 * se + 1e-12);
        let q = Light::Quad {
            corner: Vec3::ZERO,
            u: Vec3::X * 2.0,
            v: Vec3::Y * 3.0,
            radiance: 1.0,
        };
        assert!((q.power() - 6.0 * PI).abs() < 1e-12);
        let (r, _) = q.sample_emission([0.5, 0.5], [0.2, 0.7]);
        assert!(r.d.z > 0.0);
        // seen from the front only
        let front = Ray::new(Vec3::new(1.0, 1.0, 5.0), -Vec3::Z);
        assert_eq!(q.le(&front, 10.0), Some((1.0, 5.0)));
        let back = Ray::new(Vec3::new(1.0, 1.0, -5.0), Vec3::Z);
        assert!(q.le(&back, 10.0).is_none());
    }
}
