//! Photon emission aimed at the scattering media (a projection map in the spirit of
//! Jensen's photon mapping book, as a one-sample mixture so it stays unbiased).
//!
//! In a room-sized scene most photons of the volume pass never reach the small teeth: they
//! bounce between the walls until the roulette ends them, and the volume maps stay sparse
//! (coloured grain). Here a fraction `w` of the photons is sent into the cone that subtends
//! the bounding sphere of a medium-filled shape, the rest as the light emits. A photon's
//! direction ω then has the mixture density
//!
//!   p(ω) = (1 − w) p_light(ω) + w / J Σ_j p_cone,j(ω),
//!
//! and its power is Φ p_light(ω) / p(ω), so every light path keeps its expected power
//! (photons that reach the media by way of the walls included) while the media receive many
//! more photons per emitted photon. Spot lights emit as usual (their cone is already narrow).

use crate::geometry::{Ray, Vec3};
use crate::lights::Light;
use crate::math::{direction_about, Frame};
use crate::sampling::{cosine_hemisphere, uniform_sphere};
use crate::scene::{Boundary, Scene};
use std::f64::consts::PI;

/// A bounding sphere of a scattering medium's shape.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Target {
    centre: Vec3,
    radius: f64,
}

/// Aimed emission for one scene: the targets and the aimed fraction `w`.
#[derive(Debug, Clone, PartialEq)]
pub struct Aim {
    targets: Vec<Target>,
    fraction: f64,
    /// Split heavy photons where they enter a medium ([`Aim::sample_emission`]).
    splitting: bool,
}

/// How a light emits, for the mixture: the origin and the density of its own directions.
#[derive(Debug, Clone, Copy)]
enum Emitter {
    /// One-sided area light: cosine about `normal`.
    Area { normal: Vec3 },
    /// Point light: uniform over the sphere.
    Point,
}

impl Emitter {
    fn pdf(&self, d: Vec3) -> f64 {
        match self {
            Emitter::Area { normal } => (d.dot(*normal)).max(0.0) / PI,
            Emitter::Point => 0.25 / PI,
        }
    }
    fn sample(&self, u: [f64; 2]) -> Vec3 {
        match self {
            Emitter::Area { normal } => Frame::from_axis(*normal).to_world(cosine_hemisphere(u)),
            Emitter::Point => uniform_sphere(u),
        }
    }
}

impl Aim {
    /// Aimed emission with fraction `fraction` in [0, 1) towards every closed shape with a
    /// dielectric boundary around a scattering medium (spheres inside another target's
    /// sphere are dropped). `None` when the fraction is 0 or the scene has no such shape.
    pub fn new(scene: &Scene, fraction: f64) -> Option<Aim> {
        if fraction <= 0.0 {
            return None;
        }
        let scattering = |m: u32| scene.media[m as usize].sigma_s > 0.0;
        let mut spheres: Vec<Target> = Vec::new();
        for s in scene.shapes() {
            let Boundary::Dielectric { inside, outside } = s.boundary else {
                continue;
            };
            if !s.is_closed() || !(scattering(inside) || scattering(outside)) {
                continue;
            }
            let b = s.bounds();
            let radius = 0.5 * (b.max - b.min).length();
            if radius.is_finite() && radius > 0.0 {
                spheres.push(Target {
                    centre: b.centroid(),
                    radius,
                });
            }
        }
        // an enamel shell's sphere holds its dentin core's: aim once
        let inside_other = |i: usize| {
            spheres.iter().enumerate().any(|(j, o)| {
                j != i
                    && (spheres[i].centre - o.centre).length() + spheres[i].radius
                        <= o.radius * (1.0 + 1e-9)
                    && (spheres[i] != *o || j < i)
            })
        };
        let targets: Vec<Target> = (0..spheres.len())
            .filter(|&i| !inside_other(i))
            .map(|i| spheres[i])
            .collect();
        (!targets.is_empty()).then(|| Aim {
            targets,
            fraction: fraction.min(0.999),
            splitting: true,
        })
    }

    /// The same aim without splitting (every photon one walk; for comparisons).
    pub fn without_splitting(self) -> Aim {
        Aim {
            splitting: false,
            ..self
        }
    }

    /// Number of target spheres.
    pub fn targets(&self) -> usize {
        self.targets.len()
    }

    /// Cone from `o` onto target `t`: axis and cos of its half-angle (`None` when `o` is
    /// inside the sphere: that strategy then emits as the light does).
    fn cone(o: Vec3, t: &Target) -> Option<(Vec3, f64)> {
        let to = t.centre - o;
        let d2 = to.length_squared();
        if d2 <= t.radius * t.radius {
            return None;
        }
        let d = d2.sqrt();
        let sin2 = t.radius * t.radius / d2;
        Some((to / d, (1.0 - sin2).max(0.0).sqrt()))
    }

    /// An emission ray from `light`, its power (Φ p_light / p_mixture) and its split count,
    /// like [`Light::sample_emission`]; `u1` picks the point, `u2` the direction, `u3` the
    /// strategy. The power is 0 for an aimed direction the light does not emit into.
    pub fn sample_emission(&self, light: &Light, u1: [f64; 2], u2: [f64; 2], u3: f64) -> Aimed {
        let (o, emitter) = if let Some(a) = light.area_point(u1) {
            (a.point, Emitter::Area { normal: a.normal })
        } else if let Light::Point { position, .. } = *light {
            (position, Emitter::Point)
        } else {
            let (ray, power) = light.sample_emission(u1, u2);
            return Aimed::whole(ray, power);
        };
        let w = self.fraction;
        let j_count = self.targets.len();
        // cones are recomputed below rather than collected: this runs once per photon and band
        let d = if u3 < w {
            let j = ((u3 / w * j_count as f64) as usize).min(j_count - 1);
            match Self::cone(o, &self.targets[j]) {
                Some((axis, cos_max)) => {
                    let mu = 1.0 - u2[0] * (1.0 - cos_max);
                    direction_about(axis, mu, 2.0 * PI * u2[1])
                }
                None => emitter.sample(u2),
            }
        } else {
            emitter.sample(u2)
        };
        let (base, pdf) = self.densities(&emitter, o, d);
        if base <= 0.0 {
            return Aimed::whole(Ray::new(o, d), 0.0);
        }
        Aimed {
            ray: Ray::new(o, d),
            power: light.power() * base / pdf,
            source: Some(Source {
                origin: o,
                emitter,
                factor: base / pdf,
            }),
        }
    }

    /// The light's own density p_light(d) and the mixture's p(d) of direction `d` from `o`
    /// (p_light is 0 where the light does not emit; p is then not computed).
    fn densities(&self, emitter: &Emitter, o: Vec3, d: Vec3) -> (f64, f64) {
        let base = emitter.pdf(d);
        if base <= 0.0 {
            return (0.0, 0.0);
        }
        let aimed: f64 = self
            .targets
            .iter()
            .map(|t| match Self::cone(o, t) {
                Some((axis, cos_max)) if d.dot(axis) >= cos_max => {
                    1.0 / (2.0 * PI * (1.0 - cos_max))
                }
                Some(_) => 0.0,
                None => base,
            })
            .sum::<f64>()
            / self.targets.len() as f64;
        (base, (1.0 - self.fraction) * base + self.fraction * aimed)
    }

    /// Into how many walks a photon from `source` is split where it enters a scattering
    /// medium from a clear one, at `x`: its power factor over the factor of a photon sent
    /// from the same point straight at `x` (what the aimed photons that reach `x` directly
    /// carry), rounded, in [1, [`MAX_SPLIT`]]; 1 where the light does not emit towards `x`.
    /// A photon outside every cone carries 1/(1 − w), an aimed one about p_light/(w p_cone),
    /// tens of times less for a small target: the few photons that reach a medium without
    /// being aimed (off a floor or a wall) would otherwise be that much heavier than their
    /// neighbours in the map, each a kernel-sized blotch in its band. Measured at the entry
    /// point, the reference is the entered target's own (and, where cones overlap, their
    /// sum's), whatever the other targets' sizes, and a walk that scatters out of a large
    /// target into a small one is split again there. Splitting keeps the expected power
    /// (each walk carries 1/m of it).
    pub fn split_at(&self, source: &Source, x: Vec3) -> u32 {
        if !self.splitting {
            return 1;
        }
        let to = x - source.origin;
        let len = to.length();
        if len <= 0.0 || !len.is_finite() {
            return 1;
        }
        match self.densities(&source.emitter, source.origin, to / len) {
            (base, pdf) if base > 0.0 && pdf > 0.0 => (source.factor * pdf / base)
                .round()
                .clamp(1.0, MAX_SPLIT as f64)
                as u32,
            _ => 1,
        }
    }
}

/// Most walks one photon is split into ([`Aim::sample_emission`]).
pub const MAX_SPLIT: u32 = 256;

/// An aimed emission: the ray, its power [W] and where it came from, which decides into how
/// many walks it is split where it enters a scattering medium ([`Aim::split_at`]).
#[derive(Debug, Clone, Copy)]
pub struct Aimed {
    /// The emission ray.
    pub ray: Ray,
    /// Φ p_light / p_mixture.
    pub power: f64,
    /// Where and how it was emitted (`None`: never split).
    pub source: Option<Source>,
}

/// The emission point of an aimed photon, its light's own density and its power factor
/// p_light / p_mixture.
#[derive(Debug, Clone, Copy)]
pub struct Source {
    origin: Vec3,
    emitter: Emitter,
    factor: f64,
}

impl Source {
    /// The same emission carrying 1/`m` of its power (one of `m` split walks).
    pub fn divided(self, m: u32) -> Self {
        Self {
            factor: self.factor / m as f64,
            ..self
        }
    }
}

impl Aimed {
    /// An emission that is not split.
    pub fn whole(ray: Ray, power: f64) -> Self {
        Self {
            ray,
            power,
            source: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E[f(ω) · power / Φ] over aimed samples equals E[f(ω)] over the light's own directions
    /// (the mixture weight keeps every direction's expected power).
    #[test]
    fn aimed_emission_keeps_the_expected_power_per_direction() {
        let light = Light::Quad {
            corner: Vec3::new(-1.0, 1.0, 10.0),
            u: Vec3::new(2.0, 0.0, 0.0),
            v: Vec3::new(0.0, -2.0, 0.0),
            radiance: 1.0,
        };
        let aim = Aim {
            targets: vec![Target {
                centre: Vec3::new(3.0, 0.0, 0.0),
                radius: 1.0,
            }],
            fraction: 0.6,
            splitting: true,
        };
        let phi = light.power();
        let mut rng = crate::rng::Stream::new(5, 0, 0);
        // test function: the sphere's cone region and the rest of the hemisphere separately
        let n = 400_000;
        let (mut in_a, mut sq_a, mut in_b, mut total) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let e = aim.sample_emission(&light, rng.uniform2(), rng.uniform2(), rng.uniform());
            let (ray, p) = (e.ray, e.power);
            let w = p / phi;
            let hit_target = {
                let t = aim.targets[0];
                let oc = t.centre - ray.o;
                let b = oc.dot(ray.d);
                b > 0.0 && oc.length_squared() - b * b <= t.radius * t.radius
            };
            if hit_target {
                in_a += w;
                sq_a += w * w;
            } else {
                in_b += w;
            }
            total += w;
        }
        // reference: the light's own cosine emission, counted the same way
        let mut rng = crate::rng::Stream::new(6, 0, 0);
        let mut ref_a = 0.0;
        for _ in 0..n {
            let (ray, _) = light.sample_emission(rng.uniform2(), rng.uniform2());
            let t = aim.targets[0];
            let oc = t.centre - ray.o;
            let b = oc.dot(ray.d);
            if b > 0.0 && oc.length_squared() - b * b <= t.radius * t.radius {
                ref_a += 1.0;
            }
        }
        let nf = n as f64;
        let (a, r) = (in_a / nf, ref_a / nf);
        let se = ((sq_a / nf - a * a) / nf).sqrt() + (r * (1.0 - r) / nf).sqrt();
        assert!((a - r).abs() < 4.0 * se, "aimed {a} vs cosine {r} ± {se}");
        assert!(
            (total / nf - 1.0).abs() < 0.01,
            "total weight {}",
            total / nf
        );
        assert!((in_b / nf - (1.0 - r)).abs() < 0.01);
    }
}
