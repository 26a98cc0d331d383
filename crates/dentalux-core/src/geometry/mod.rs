//! Geometry: rays, hits, analytic shapes, triangle meshes, transforms and the BVH that
//! finds the first surface a ray meets.
//!
//! Conventions, stated once:
//! - Lengths in mm. A [`Ray`] has a unit direction, so the hit distance `t` is in mm.
//! - [`Hit::n`] is the unit *geometric* normal pointing outward of a closed shape (towards
//!   the boundary's `outside` medium); for a quad it is u × v normalised.
//! - Rays leaving a surface are offset by [`offset_origin`] along the normal by a distance
//!   `eps` scaled to the scene size ([`crate::scene::Scene::eps`]), so they never re-hit
//!   the surface they start on (no self-intersection acne).

pub mod bvh;
pub mod clearance_grid;
pub mod mesh;
pub mod shapes;
pub mod transform;

pub use crate::math::Vec3;

/// A ray o + t·d with unit direction d; `t` in mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin [mm].
    pub o: Vec3,
    /// Unit travel direction.
    pub d: Vec3,
}

impl Ray {
    /// A ray from `o` along `d` (normalised here).
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Self {
            o,
            d: d.normalize(),
        }
    }
    /// The point at distance `t` [mm].
    #[inline]
    pub fn at(&self, t: f64) -> Vec3 {
        self.o + self.d * t
    }
}

/// Where a ray met a surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the ray [mm].
    pub t: f64,
    /// Hit point [mm].
    pub p: Vec3,
    /// Unit geometric normal, outward of the closed shape (quads: u × v normalised).
    pub n: Vec3,
    /// Surface parameterisation in [0, 1]² (for textures).
    pub uv: [f64; 2],
    /// Index into `scene.shapes`.
    pub shape: u32,
}

/// An axis-aligned bounding box [mm].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (union identity).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f64::INFINITY),
        max: Vec3::splat(f64::NEG_INFINITY),
    };
    /// Smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    /// Smallest box holding this one and point `p`.
    #[inline]
    pub fn grow(&self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    /// Centre point.
    #[inline]
    pub fn centroid(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    /// Surface area [mm²] (0 for an empty box).
    #[inline]
    pub fn area(&self) -> f64 {
        let e = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    /// The 8 corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }
    /// Squared distance from `p` to the box (0 inside it).
    #[inline]
    pub fn distance2(&self, p: Vec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.dot(d)
    }
    /// Slab test: the entry distance if the ray (with precomputed `inv_d` = 1/d) meets the
    /// box within (0, t_max), else +∞.
    #[inline]
    pub fn hit_distance(&self, o: Vec3, inv_d: Vec3, t_max: f64) -> f64 {
        let t0 = (self.min - o) * inv_d;
        let t1 = (self.max - o) * inv_d;
        // f64::min/max drop a NaN operand (0·∞ when the origin lies on a slab plane)
        let tmin =
            t0.x.min(t1.x)
                .max(t0.y.min(t1.y))
                .max(t0.z.min(t1.z))
                .max(0.0);
        let tmax =
            t0.x.max(t1.x)
                .min(t0.y.max(t1.y))
                .min(t0.z.max(t1.z))
                .min(t_max);
        if tmin <= tmax {
            tmin
        } else {
            f64::INFINITY
        }
    }
}

/// Offset a point `p` on a surface with unit normal `n` to the side that direction `d`
/// leaves towards, by `eps` [mm]: the origin of a spawned ray that cannot re-hit the
/// surface it starts on.
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, d: Vec3, eps: f64) -> Vec3 {
    if d.dot(n) >= 0.0 {
        p + n * eps
    } else {
        p - n * eps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_test_hits_and_misses() {
        let b = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let d = Vec3::new(1.0, 0.0, 0.0);
        let inv = d.recip();
        assert!((b.hit_distance(Vec3::new(-3.0, 0.0, 0.0), inv, 10.0) - 2.0).abs() < 1e-12);
        assert!(b
            .hit_distance(Vec3::new(-3.0, 2.0, 0.0), inv, 10.0)
            .is_infinite());
        assert!(b
            .hit_distance(Vec3::new(-3.0, 0.0, 0.0), inv, 1.0)
            .is_infinite());
        // origin inside: entry distance clamps to 0
        assert_eq!(b.hit_distance(Vec3::ZERO, inv, 10.0), 0.0);
        // a flat box (a quad's bounds) is still hit by a ray crossing its plane
        let flat = Aabb {
            min: Vec3::new(-1.0, -1.0, 0.0),
            max: Vec3::new(1.0, 1.0, 0.0),
        };
        let d = Vec3::new(0.1, 0.0, -1.0).normalize();
        let t = flat.hit_distance(Vec3::new(0.0, 0.0, 2.0), d.recip(), 10.0);
        assert!((t - 2.0 / -d.z).abs() < 1e-12);
        assert!((b.area() - 24.0).abs() < 1e-12);
    }
}
