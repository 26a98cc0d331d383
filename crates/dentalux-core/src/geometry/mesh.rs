//! Triangle meshes (already in world space: the scene bakes a mesh's transform into its
//! positions), Möller–Trumbore intersection, and the topology checks a dielectric boundary
//! needs: closed (every edge shared by exactly two triangles) and consistently oriented
//! (each shared edge traversed once in each direction), outward normals by positive volume;
//! and the inside test of a watertight mesh (ray-crossing parity).

use super::shapes::LocalHit;
use super::{Aabb, Vec3};
use crate::error::{Error, Result};
use std::collections::HashMap;

/// An indexed triangle mesh [mm]. A triangle (a, b, c) has normal (b − a) × (c − a),
/// outward when the triangles wind counter-clockwise seen from outside.
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions [mm].
    pub positions: Vec<Vec3>,
    /// Vertex indices per triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Optional per-vertex uv (texture coordinates).
    pub uvs: Option<Vec<[f64; 2]>>,
}

/// What [`TriangleMesh::topology`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Topology {
    /// Closed and consistently oriented.
    Closed,
    /// Some edge belongs to a number of triangles other than two.
    Open {
        /// Number of edges not shared by exactly two triangles.
        bad_edges: usize,
    },
    /// Closed, but two neighbouring triangles disagree on which side is out.
    Inconsistent {
        /// Number of edges traversed twice in the same direction.
        bad_edges: usize,
    },
}

impl TriangleMesh {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }
    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
    /// The three corners of triangle `i`.
    #[inline]
    pub fn corners(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
    /// Bounds of triangle `i`.
    pub fn triangle_bounds(&self, i: usize) -> Aabb {
        let [a, b, c] = self.corners(i);
        Aabb::EMPTY.grow(a).grow(b).grow(c)
    }
    /// Möller–Trumbore: nearest intersection with triangle `i`, t in (0, t_max). The
    /// normal is the (non-unit) geometric normal; uv interpolates the vertex uvs, or is the
    /// barycentric (b1, b2) when the mesh has none.
    #[inline]
    pub fn intersect_triangle(&self, i: usize, o: Vec3, d: Vec3, t_max: f64) -> Option<LocalHit> {
        let [a, b, c] = self.corners(i);
        let (t, b1, b2) = intersect_corners(a, b, c, o, d, t_max)?;
        Some(LocalHit {
            t,
            n: (b - a).cross(c - a),
            uv: self.uv_at(i, b1, b2),
        })
    }
    /// uv of triangle `i` at barycentric (b1, b2): the interpolated vertex uvs, or (b1, b2).
    #[inline]
    pub fn uv_at(&self, i: usize, b1: f64, b2: f64) -> [f64; 2] {
        match &self.uvs {
            Some(uvs) => {
                let [ia, ib, ic] = self.triangles[i];
                let (ua, ub, uc) = (uvs[ia as usize], uvs[ib as usize], uvs[ic as usize]);
                let b0 = 1.0 - b1 - b2;
                [
                    b0 * ua[0] + b1 * ub[0] + b2 * uc[0],
                    b0 * ua[1] + b1 * ub[1] + b2 * uc[1],
                ]
            }
            None => [b1, b2],
        }
    }
    /// Refuse a triangle that refers to a vertex past the positions (`field`: the mesh's
    /// key path, for the message); [`topology`](Self::topology) and the geometry assume none.
    pub fn check_indices(&self, field: &str) -> Result<()> {
        let nv = self.positions.len();
        match (self.triangles.iter()).position(|t| t.iter().any(|&k| k as usize >= nv)) {
            Some(i) => Err(Error::InvalidInput(format!(
                "{field}triangles[{i}] = {:?} refers to a vertex ≥ {nv} (the number of positions)",
                self.triangles[i]
            ))),
            None => Ok(()),
        }
    }
    /// Closedness and orientation consistency, from directed-edge counts over positions
    /// merged as in [`merged_ids`](Self::merged_ids): a file that duplicates vertices along
    /// uv seams is closed when the solid is.
    pub fn topology(&self) -> Topology {
        let id = self.merged_ids();
        let mut directed: HashMap<(u32, u32), u32> = HashMap::with_capacity(self.len() * 3);
        for t in &self.triangles {
            for k in 0..3 {
                let edge = (id[t[k] as usize], id[t[(k + 1) % 3] as usize]);
                *directed.entry(edge).or_insert(0) += 1;
            }
        }
        let mut open = 0;
        let mut inconsistent = 0;
        for (&(a, b), &count) in &directed {
            let back = directed.get(&(b, a)).copied().unwrap_or(0);
            if count + back != 2 {
                open += 1;
            } else if count != 1 {
                // (b, a) is absent then: each such edge is met once
                inconsistent += 1;
            }
        }
        if open > 0 {
            Topology::Open { bad_edges: open }
        } else if inconsistent > 0 {
            Topology::Inconsistent {
                bad_edges: inconsistent,
            }
        } else {
            Topology::Closed
        }
    }
    /// One id per vertex, equal for positions equal on a 10⁻⁸ mm grid. The grid is trimesh's
    /// (`tol.merge`, ties to even), with which mesh files are loaded and merged in Python.
    fn merged_ids(&self) -> Vec<u32> {
        let key = |x: f64| (x * 1e8).round_ties_even() as i64;
        let mut ids: HashMap<[i64; 3], u32> = HashMap::with_capacity(self.positions.len());
        (self.positions.iter())
            .map(|p| {
                let next = ids.len() as u32;
                *ids.entry([key(p.x), key(p.y), key(p.z)]).or_insert(next)
            })
            .collect()
    }
    /// Signed enclosed volume [mm³] (divergence theorem); positive when normals point out.
    pub fn signed_volume(&self) -> f64 {
        (0..self.len())
            .map(|i| {
                let [a, b, c] = self.corners(i);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }
    /// Whether every edge is shared by exactly two triangles (positions merged as in
    /// [`topology`](Self::topology)), orientation aside: closed as a solid.
    pub fn is_watertight(&self) -> bool {
        !matches!(self.topology(), Topology::Open { .. })
    }
    /// Whether `p` lies strictly inside the bounds of the positions and an odd number of
    /// triangles lie on a ray from it: inside, for a watertight mesh. The ray is skewed off
    /// the axes and diagonals so that it almost surely misses edges and vertices.
    pub fn encloses(&self, p: Vec3) -> bool {
        let b = (self.positions.iter()).fold(Aabb::EMPTY, |b, &q| b.grow(q));
        if !(p.cmpgt(b.min).all() && p.cmplt(b.max).all()) {
            return false;
        }
        let d = Vec3::new(0.5377, 0.6151, 0.5767).normalize();
        let crossings = (0..self.len())
            .filter(|&i| {
                let [a, b, c] = self.corners(i);
                intersect_corners(a, b, c, p, d, f64::INFINITY).is_some()
            })
            .count();
        crossings % 2 == 1
    }
    /// Reverse every triangle's winding (turn inward normals outward).
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }
    /// A UV sphere of `n_theta` × `n_phi` quads split into triangles, outward-wound
    /// (for tests and benchmarks).
    pub fn uv_sphere(center: Vec3, radius: f64, n_theta: usize, n_phi: usize) -> Self {
        use std::f64::consts::PI;
        let mut positions = vec![center + Vec3::Z * radius];
        for i in 1..n_theta {
            let th = PI * i as f64 / n_theta as f64;
            for j in 0..n_phi {
                let ph = 2.0 * PI * j as f64 / n_phi as f64;
                positions.push(
                    center + Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * radius,
                );
            }
        }
        positions.push(center - Vec3::Z * radius);
        let south = (positions.len() - 1) as u32;
        let ring = |i: usize, j: usize| (1 + (i - 1) * n_phi + j % n_phi) as u32;
        let mut triangles = Vec::new();
        for j in 0..n_phi {
            triangles.push([0, ring(1, j), ring(1, j + 1)]);
            triangles.push([south, ring(n_theta - 1, j + 1), ring(n_theta - 1, j)]);
        }
        for i in 1..n_theta - 1 {
            for j in 0..n_phi {
                let (a, b) = (ring(i, j), ring(i, j + 1));
                let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
                triangles.push([a, c, d]);
                triangles.push([a, d, b]);
            }
        }
        Self {
            positions,
            triangles,
            uvs: None,
        }
    }
}

/// Distance from `p` to the triangle (a, b, c) [mm]: to its plane where `p`'s projection
/// falls inside the triangle, else to the nearest edge.
pub fn distance_to_corners(a: Vec3, b: Vec3, c: Vec3, p: Vec3) -> f64 {
    let (e1, e2, w) = (b - a, c - a, p - a);
    let n = e1.cross(e2);
    let nn = n.dot(n);
    if nn > 0.0 {
        // barycentric weights of b and c at the projection of p
        let s = w.cross(e2).dot(n) / nn;
        let t = e1.cross(w).dot(n) / nn;
        if s >= 0.0 && t >= 0.0 && s + t <= 1.0 {
            return w.dot(n).abs() / nn.sqrt();
        }
    }
    segment_distance(a, b, p)
        .min(segment_distance(b, c, p))
        .min(segment_distance(c, a, p))
}

/// Distance from `p` to the segment from `a` to `b`.
fn segment_distance(a: Vec3, b: Vec3, p: Vec3) -> f64 {
    let ab = b - a;
    let len2 = ab.dot(ab);
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

/// Möller–Trumbore on corners (a, b, c): (t, b1, b2) of the hit with t in (0, t_max), b1 and
/// b2 the barycentric weights of b and c.
#[inline]
pub fn intersect_corners(
    a: Vec3,
    b: Vec3,
    c: Vec3,
    o: Vec3,
    d: Vec3,
    t_max: f64,
) -> Option<(f64, f64, f64)> {
    let e1 = b - a;
    let e2 = c - a;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - a;
    let b1 = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qv = tv.cross(e1);
    let b2 = d.dot(qv) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (t > 0.0 && t < t_max).then_some((t, b1, b2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_distance_is_the_least_over_the_triangle() {
        use crate::rng::Stream;
        let mut rng = Stream::new(3, 0, 0);
        let mut point = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0;
        for _ in 0..300 {
            let (a, b, c, p) = (point(), point(), point(), point());
            let d = distance_to_corners(a, b, c, p);
            // brute force over a grid of barycentric points, spacing h along each edge
            let n = 200;
            let mut least = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    least = least.min((a + (b - a) * u + (c - a) * v - p).length());
                }
            }
            let h = ((b - a).length() + (c - a).length()) / n as f64;
            assert!(d <= least + 1e-12 && d >= least - h, "{d} against {least}");
        }
        // on the triangle: 0; in its plane beyond an edge: the edge's distance; above it
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(
            distance_to_corners(a, b, c, Vec3::new(0.25, 0.25, 0.0)),
            0.0
        );
        assert_eq!(distance_to_corners(a, b, c, Vec3::new(0.5, -2.0, 0.0)), 2.0);
        assert_eq!(distance_to_corners(a, b, c, Vec3::new(0.2, 0.3, -0.7)), 0.7);
    }

    fn tetra() -> TriangleMesh {
        TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            uvs: None,
        }
    }

    #[test]
    fn tetrahedron_topology_and_volume() {
        let m = tetra();
        assert_eq!(m.topology(), Topology::Closed);
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-12);
        let mut open = m.clone();
        open.triangles.pop();
        assert!(matches!(open.topology(), Topology::Open { bad_edges: 3 }));
        let mut bad = m.clone();
        bad.triangles[3].swap(1, 2);
        // the turned triangle's three edges each run the way a neighbour's does
        assert_eq!(bad.topology(), Topology::Inconsistent { bad_edges: 3 });
        let mut f = m.clone();
        f.flip();
        assert_eq!(f.topology(), Topology::Closed);
        assert!(f.signed_volume() < 0.0);
    }

    #[test]
    fn triangle_hit_and_outward_normal() {
        let m = tetra();
        // from below through the z = 0 face: normal points to −z
        let h = m
            .intersect_triangle(0, Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 10.0)
            .unwrap();
        assert!((h.t - 1.0).abs() < 1e-12);
        assert!(h.n.normalize().dot(-Vec3::Z) > 0.999_999);
        assert!(m
            .intersect_triangle(0, Vec3::new(0.8, 0.8, -1.0), Vec3::Z, 10.0)
            .is_none());
    }

    #[test]
    fn watertight_merges_duplicated_positions() {
        let m = tetra();
        assert!(m.is_watertight());
        // corner 0 duplicated (as a uv seam does): open by index, closed as a solid
        let mut seam = m.clone();
        seam.positions.push(Vec3::new(0.0, 0.0, 1e-9));
        seam.triangles[0] = [4, 2, 1];
        seam.triangles[2] = [4, 3, 2];
        assert_eq!(seam.topology(), Topology::Closed);
        assert!(seam.is_watertight());
        // a duplicate 1e-7 mm away is another vertex: the seam stays open
        let mut apart = seam.clone();
        apart.positions[4] = Vec3::new(0.0, 0.0, 1e-7);
        assert!(matches!(apart.topology(), Topology::Open { .. }));
        // winding does not matter, a missing triangle does
        let mut bad = m.clone();
        bad.triangles[3].swap(1, 2);
        assert!(bad.is_watertight());
        let mut open = m.clone();
        open.triangles.pop();
        assert!(!open.is_watertight());
    }

    #[test]
    fn encloses_by_parity() {
        let m = TriangleMesh::uv_sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 32, 64);
        assert!(m.encloses(Vec3::new(1.0, 2.0, 3.0)));
        assert!(m.encloses(Vec3::new(2.5, 2.0, 3.0)));
        assert!(!m.encloses(Vec3::new(3.5, 2.0, 3.0)));
        // outside the bounds, and on them
        assert!(!m.encloses(Vec3::new(1.0, 2.0, 10.0)));
        assert!(!m.encloses(Vec3::new(1.0, 2.0, 5.0)));
    }

    #[test]
    fn uv_sphere_is_closed_with_right_volume() {
        let m = TriangleMesh::uv_sphere(Vec3::new(1.0, 2.0, 3.0), 2.0, 64, 128);
        assert_eq!(m.topology(), Topology::Closed);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 8.0;
        let v = m.signed_volume();
        assert!(
            v > 0.0 && (v - exact).abs() / exact < 2e-3,
            "{v} vs {exact}"
        );
    }
}
