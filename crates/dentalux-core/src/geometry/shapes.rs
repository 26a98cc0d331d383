//! Analytic shapes in their own (object) space: sphere, quad (parallelogram), axis-aligned
//! box and capped cylinder (the disc specimens of the paper). Each gives the nearest
//! intersection of a ray o + t·d with t in (0, t_max) — d need not be unit, so a ray
//! mapped into object space by an affine transform keeps its world `t` — the outward
//! geometric normal, a uv parameterisation in [0, 1]², bounds, and (closed shapes) an
//! inside test. All lengths in mm.

use super::{Aabb, Vec3};
use crate::math::Frame;
use std::f64::consts::PI;

/// The result of intersecting one shape, in the shape's own space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalHit {
    /// Ray parameter (distance [mm] when d is unit).
    pub t: f64,
    /// Outward normal (not necessarily unit).
    pub n: Vec3,
    /// uv in [0, 1]².
    pub uv: [f64; 2],
}

/// A sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Centre [mm].
    pub center: Vec3,
    /// Radius [mm] (> 0).
    pub radius: f64,
}

impl Sphere {
    /// Nearest intersection with t in (0, t_max). uv = (azimuth/2π, polar/π) about +z.
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f64) -> Option<LocalHit> {
        let oc = o - self.center;
        let a = d.length_squared();
        let h = oc.dot(d);
        let c = oc.length_squared() - self.radius * self.radius;
        // discriminant from the closest-approach point: far better conditioned than h² − ac
        // when the sphere is small compared with its distance
        let l = oc - d * (h / a);
        let disc = a * (self.radius * self.radius - l.length_squared());
        if disc < 0.0 {
            return None;
        }
        let q = -(h + disc.sqrt().copysign(h));
        let (mut t0, mut t1) = (q / a, if q != 0.0 { c / q } else { q / a });
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let t = if t0 > 0.0 {
            t0
        } else if t1 > 0.0 {
            t1
        } else {
            return None;
        };
        if t >= t_max {
            return None;
        }
        let n = (oc + d * t) / self.radius;
        let phi = n.y.atan2(n.x).rem_euclid(2.0 * PI);
        let theta = n.z.clamp(-1.0, 1.0).acos();
        Some(LocalHit {
            t,
            n,
            uv: [phi / (2.0 * PI), theta / PI],
        })
    }
    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.center - Vec3::splat(self.radius),
            max: self.center + Vec3::splat(self.radius),
        }
    }
    /// Whether `p` lies strictly inside.
    pub fn contains(&self, p: Vec3) -> bool {
        (p - self.center).length_squared() < self.radius * self.radius
    }
    /// Distance from `p` to the surface.
    pub fn clearance(&self, p: Vec3) -> f64 {
        ((p - self.center).length() - self.radius).abs()
    }
    /// uv extents [mm per unit uv]: (equator length, meridian length).
    pub fn uv_scale(&self) -> [f64; 2] {
        [2.0 * PI * self.radius, PI * self.radius]
    }
}

/// A parallelogram corner + s·u + t·v, s, t ∈ [0, 1]; open (opaque boundaries only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quad {
    /// Corner [mm].
    pub corner: Vec3,
    /// First edge [mm].
    pub u: Vec3,
    /// Second edge [mm]; the normal is u × v normalised.
    pub v: Vec3,
}

impl Quad {
    /// Nearest intersection; uv = (s, t).
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f64) -> Option<LocalHit> {
        let nn = self.u.cross(self.v);
        let denom = d.dot(nn);
        if denom == 0.0 {
            return None;
        }
        let t = (self.corner - o).dot(nn) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let w = o + d * t - self.corner;
        let inv = 1.0 / nn.length_squared();
        let s = w.cross(self.v).dot(nn) * inv;
        let r = self.u.cross(w).dot(nn) * inv;
        if !(0.0..=1.0).contains(&s) || !(0.0..=1.0).contains(&r) {
            return None;
        }
        Some(LocalHit {
            t,
            n: nn,
            uv: [s, r],
        })
    }
    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        let c = self.corner;
        Aabb::EMPTY
            .grow(c)
            .grow(c + self.u)
            .grow(c + self.v)
            .grow(c + self.u + self.v)
    }
    /// Area [mm²].
    pub fn area(&self) -> f64 {
        self.u.cross(self.v).length()
    }
    /// A lower bound on the distance from `p` to the quad: its distance to the quad's plane.
    pub fn clearance(&self, p: Vec3) -> f64 {
        let nn = self.u.cross(self.v);
        ((p - self.corner).dot(nn) / nn.length()).abs()
    }
    /// uv extents [mm per unit uv].
    pub fn uv_scale(&self) -> [f64; 2] {
        [self.u.length(), self.v.length()]
    }
}

/// An axis-aligned box (in object space).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxShape {
    /// Lower corner [mm].
    pub min: Vec3,
    /// Upper corner [mm].
    pub max: Vec3,
}

impl BoxShape {
    /// Nearest intersection; uv = the two in-face coordinates of the face hit, normalised.
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f64) -> Option<LocalHit> {
        let inv = d.recip();
        let t0 = (self.min - o) * inv;
        let t1 = (self.max - o) * inv;
        let lo = t0.min(t1);
        let hi = t0.max(t1);
        let t_near = lo.x.max(lo.y).max(lo.z);
        let t_far = hi.x.min(hi.y).min(hi.z);
        if t_near > t_far {
            return None;
        }
        let t = if t_near > 0.0 { t_near } else { t_far };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        // the face hit: the axis along which p is farthest out relative to the half-extent
        let c = (self.min + self.max) * 0.5;
        let half = (self.max - self.min) * 0.5;
        let q = (o + d * t - c) / half;
        let a = q.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut n = Vec3::ZERO;
        n[axis] = q[axis].signum();
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let uv = [
            (0.5 * (q[i] + 1.0)).clamp(0.0, 1.0),
            (0.5 * (q[j] + 1.0)).clamp(0.0, 1.0),
        ];
        Some(LocalHit { t, n, uv })
    }
    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.min,
            max: self.max,
        }
    }
    /// Whether `p` lies strictly inside.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpgt(self.min).all() && p.cmplt(self.max).all()
    }
    /// Distance from `p` to the surface: to the nearest face inside, to the solid outside.
    pub fn clearance(&self, p: Vec3) -> f64 {
        let below = self.min - p;
        let above = p - self.max;
        let out = below.max(above);
        if out.max_element() < 0.0 {
            -out.max_element()
        } else {
            out.max(Vec3::ZERO).length()
        }
    }
    /// uv extents [mm per unit uv] (the largest edge: faces differ).
    pub fn uv_scale(&self) -> [f64; 2] {
        let e = (self.max - self.min).max_element();
        [e, e]
    }
}

/// A cylinder (disc) with flat caps: base centre, unit axis, radius and height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Centre of the base cap [mm].
    pub center: Vec3,
    /// Unit axis from the base cap to the top cap.
    pub axis: Vec3,
    /// Radius [mm] (> 0).
    pub radius: f64,
    /// Height (thickness of a disc) [mm] (> 0).
    pub height: f64,
}

impl Cylinder {
    /// Nearest intersection. uv: on the side (azimuth/2π, height fraction); on a cap the
    /// cap's planar coordinates mapped to [0, 1]².
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f64) -> Option<LocalHit> {
        let f = Frame::from_axis(self.axis);
        let q = f.to_local(o - self.center);
        let dl = f.to_local(d);
        let (r, h) = (self.radius, self.height);
        // the nearest hit: (t, local normal); its uv is computed once, at the end (an atan2
        // per side hit was 3 % of a Fig. 3 render)
        let mut best: Option<(f64, Vec3)> = None;
        let mut consider = |t: f64, n: Vec3| {
            if t > 0.0 && t < t_max && best.is_none_or(|b| t < b.0) {
                best = Some((t, n));
            }
        };
        // side: (qx + t dx)² + (qy + t dy)² = r², 0 ≤ z ≤ h
        let a = dl.x * dl.x + dl.y * dl.y;
        if a > 0.0 {
            let b = q.x * dl.x + q.y * dl.y;
            // closest approach in the xy plane, for a well-conditioned discriminant
            let (lx, ly) = (q.x - dl.x * b / a, q.y - dl.y * b / a);
            let disc = a * (r * r - lx * lx - ly * ly);
            if disc >= 0.0 {
                let s = disc.sqrt();
                for t in [(-b - s) / a, (-b + s) / a] {
                    let z = q.z + t * dl.z;
                    if (0.0..=h).contains(&z) {
                        consider(t, Vec3::new(q.x + t * dl.x, q.y + t * dl.y, 0.0));
                    }
                }
            }
        }
        // caps at z = 0 (normal −axis) and z = h (normal +axis)
        if dl.z != 0.0 {
            for (z, nz) in [(0.0, -1.0), (h, 1.0)] {
                let t = (z - q.z) / dl.z;
                let (x, y) = (q.x + t * dl.x, q.y + t * dl.y);
                if x * x + y * y <= r * r {
                    consider(t, Vec3::new(0.0, 0.0, nz));
                }
            }
        }
        best.map(|(t, n)| {
            let p = q + dl * t;
            let uv = if n.z == 0.0 {
                let phi = p.y.atan2(p.x).rem_euclid(2.0 * PI);
                [phi / (2.0 * PI), p.z / h]
            } else {
                [0.5 + 0.5 * p.x / r, 0.5 + 0.5 * p.y / r]
            };
            LocalHit {
                t,
                n: f.to_world(n),
                uv,
            }
        })
    }
    /// Bounds (of the two cap discs).
    pub fn bounds(&self) -> Aabb {
        let a = self.axis;
        // extent of a disc of radius r with normal a along each world axis: r·sqrt(1 − a_i²)
        let e = Vec3::new(
            (1.0 - a.x * a.x).max(0.0).sqrt(),
            (1.0 - a.y * a.y).max(0.0).sqrt(),
            (1.0 - a.z * a.z).max(0.0).sqrt(),
        ) * self.radius;
        let top = self.center + a * self.height;
        Aabb {
            min: self.center.min(top) - e,
            max: self.center.max(top) + e,
        }
    }
    /// Whether `p` lies strictly inside.
    pub fn contains(&self, p: Vec3) -> bool {
        let w = p - self.center;
        let z = w.dot(self.axis);
        z > 0.0 && z < self.height && (w - self.axis * z).length_squared() < self.radius.powi(2)
    }
    /// Distance from `p` to the surface: to the nearest of side and caps inside, to the solid
    /// outside.
    pub fn clearance(&self, p: Vec3) -> f64 {
        let w = p - self.center;
        let z = w.dot(self.axis);
        let rho = (w - self.axis * z).length();
        // signed distances past the side and past the nearer cap (negative inside)
        let side = rho - self.radius;
        let cap = (-z).max(z - self.height);
        if side < 0.0 && cap < 0.0 {
            -side.max(cap)
        } else {
            // not f64::hypot: libm's is several times slower, and these are mm, far from
            // overflow
            (side.max(0.0).powi(2) + cap.max(0.0).powi(2)).sqrt()
        }
    }
    /// uv extents [mm per unit uv] on the side: (circumference, height).
    pub fn uv_scale(&self) -> [f64; 2] {
        [2.0 * PI * self.radius, self.height]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(v: Vec3) -> Vec3 {
        v.normalize()
    }

    #[test]
    fn sphere_from_outside_and_inside() {
        let s = Sphere {
            center: Vec3::new(0.0, 0.0, -5.0),
            radius: 1.0,
        };
        let h = s.intersect(Vec3::ZERO, -Vec3::Z, 100.0).unwrap();
        assert!((h.t - 4.0).abs() < 1e-12);
        assert!((h.n - Vec3::Z).length() < 1e-12);
        let h = s
            .intersect(Vec3::new(0.0, 0.0, -5.0), Vec3::X, 100.0)
            .unwrap();
        assert!((h.t - 1.0).abs() < 1e-12 && (h.n - Vec3::X).length() < 1e-12);
        assert!(s.intersect(Vec3::ZERO, Vec3::Z, 100.0).is_none());
        assert!(s.intersect(Vec3::ZERO, -Vec3::Z, 3.9).is_none());
        // a non-unit direction keeps t as a ray parameter
        let h = s.intersect(Vec3::ZERO, -Vec3::Z * 2.0, 100.0).unwrap();
        assert!((h.t - 2.0).abs() < 1e-12);
        // far away, tiny: the well-conditioned discriminant still finds it
        let far = Sphere {
            center: Vec3::new(0.0, 0.0, -1e6),
            radius: 1e-3,
        };
        let h = far.intersect(Vec3::ZERO, -Vec3::Z, 1e7).unwrap();
        assert!((h.t - (1e6 - 1e-3)).abs() < 1e-6);
    }

    #[test]
    fn quad_bounds_and_normal() {
        let q = Quad {
            corner: Vec3::new(-1.0, -1.0, 0.0),
            u: Vec3::new(2.0, 0.0, 0.0),
            v: Vec3::new(0.0, 2.0, 0.0),
        };
        let h = q
            .intersect(Vec3::new(0.5, 0.0, 3.0), -Vec3::Z, 10.0)
            .unwrap();
        assert!((h.t - 3.0).abs() < 1e-12);
        assert!((unit(h.n) - Vec3::Z).length() < 1e-12);
        assert!((h.uv[0] - 0.75).abs() < 1e-12 && (h.uv[1] - 0.5).abs() < 1e-12);
        assert!(q
            .intersect(Vec3::new(1.5, 0.0, 3.0), -Vec3::Z, 10.0)
            .is_none());
        assert!(q
            .intersect(Vec3::new(0.0, 0.0, 3.0), Vec3::X, 10.0)
            .is_none());
        assert!((q.area() - 4.0).abs() < 1e-12);
    }

    #[test]
    fn box_faces() {
        let b = BoxShape {
            min: Vec3::new(0.0, 0.0, 0.0),
            max: Vec3::new(1.0, 2.0, 3.0),
        };
        let h = b
            .intersect(Vec3::new(0.5, 1.0, 10.0), -Vec3::Z, 100.0)
            .unwrap();
        assert!((h.t - 7.0).abs() < 1e-12 && h.n == Vec3::Z);
        let h = b
            .intersect(Vec3::new(0.5, 1.0, 1.0), Vec3::Y, 100.0)
            .unwrap();
        assert!((h.t - 1.0).abs() < 1e-12 && h.n == Vec3::Y);
        assert!(b.contains(Vec3::new(0.5, 1.0, 1.0)));
        assert!(!b.contains(Vec3::new(1.5, 1.0, 1.0)));
    }

    #[test]
    fn cylinder_side_and_caps() {
        let c = Cylinder {
            center: Vec3::ZERO,
            axis: Vec3::Z,
            radius: 5.0,
            height: 2.0,
        };
        let h = c
            .intersect(Vec3::new(1.0, 0.0, 10.0), -Vec3::Z, 100.0)
            .unwrap();
        assert!((h.t - 8.0).abs() < 1e-12 && (unit(h.n) - Vec3::Z).length() < 1e-12);
        let h = c
            .intersect(Vec3::new(-10.0, 0.0, 1.0), Vec3::X, 100.0)
            .unwrap();
        assert!((h.t - 5.0).abs() < 1e-12 && (unit(h.n) + Vec3::X).length() < 1e-12);
        // from inside through the bottom cap
        let h = c
            .intersect(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, 100.0)
            .unwrap();
        assert!((h.t - 1.0).abs() < 1e-12 && (unit(h.n) + Vec3::Z).length() < 1e-12);
        // a tilted axis: bounds hold the caps
        let t = Cylinder {
            axis: unit(Vec3::new(1.0, 1.0, 0.0)),
            ..c
        };
        let b = t.bounds();
        for s in 0..32 {
            let phi = s as f64 / 32.0 * 2.0 * PI;
            let f = Frame::from_axis(t.axis);
            let rim = f.to_world(Vec3::new(phi.cos(), phi.sin(), 0.0)) * 5.0;
            for p in [rim, rim + t.axis * 2.0] {
                assert!(p.cmpge(b.min - 1e-9).all() && p.cmple(b.max + 1e-9).all());
            }
        }
        assert!(c.contains(Vec3::new(0.0, 4.9, 1.0)) && !c.contains(Vec3::new(0.0, 0.0, 2.1)));
    }

    /// The nearest surface point over many directions from `p`, by ray casting.
    fn cast_distance(intersect: impl Fn(Vec3, Vec3) -> Option<f64>, p: Vec3) -> f64 {
        let mut rng = crate::rng::Stream::new(3, 0, 0);
        (0..20_000)
            .filter_map(|_| intersect(p, crate::sampling::uniform_sphere(rng.uniform2())))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn clearance_bounds_every_ray_and_is_tight_for_closed_shapes() {
        let cyl = Cylinder {
            center: Vec3::new(1.0, -2.0, 0.5),
            axis: unit(Vec3::new(0.3, 0.2, 1.0)),
            radius: 2.0,
            height: 1.5,
        };
        let sph = Sphere {
            center: Vec3::new(0.5, 0.0, 1.0),
            radius: 1.5,
        };
        let bx = BoxShape {
            min: Vec3::new(-1.0, -2.0, 0.0),
            max: Vec3::new(2.0, 1.0, 0.7),
        };
        let quad = Quad {
            corner: Vec3::new(-3.0, -3.0, 0.2),
            u: Vec3::new(6.0, 0.0, 0.5),
            v: Vec3::new(0.0, 6.0, 0.0),
        };
        let mut rng = crate::rng::Stream::new(4, 0, 0);
        for _ in 0..40 {
            let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 6.0 - 3.0;
            // (the bound, the nearest hit over many rays, whether the bound is the distance)
            macro_rules! case {
                ($shape:expr, $tight:expr) => {
                    (
                        $shape.clearance(p),
                        cast_distance(|o, d| $shape.intersect(o, d, 1e9).map(|h| h.t), p),
                        $tight,
                    )
                };
            }
            let cases = [
                case!(cyl, true),
                case!(sph, true),
                case!(bx, true),
                case!(quad, false),
            ];
            for (i, (bound, cast, tight)) in cases.into_iter().enumerate() {
                // a lower bound on every ray's hit ...
                assert!(bound <= cast + 1e-12, "shape {i} at {p}: {bound} > {cast}");
                // ... and, for the closed shapes, the distance itself (20 000 directions find
                // the nearest point to within a few per cent of the distance)
                if tight {
                    assert!(
                        cast <= bound * 1.05 + 1e-3,
                        "shape {i} at {p}: {bound} vs {cast}"
                    );
                }
            }
        }
    }
}
