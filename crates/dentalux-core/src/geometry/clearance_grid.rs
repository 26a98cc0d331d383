//! A voxel grid of lower bounds on the distance to the nearest surface, for scenes where a
//! scan of the shapes would cost more than it saves (triangle meshes): a random walk inside
//! a tooth looks its clearance up in O(1) and skips the BVH for every flight shorter than it.
//!
//! Each voxel holds a lower bound D on the distance from its centre c to every surface; at a
//! point p of the voxel the bound is D − |p − c| (a distance changes no faster than the
//! point moves). D comes from two sources:
//! - every voxel that a primitive's bounding box overlaps is marked, and a breadth-first
//!   search over the 26 neighbours gives each voxel its Chebyshev index distance k to the
//!   nearest marked one: its centre is at least (k − ½) voxel sides from every marked voxel
//!   along some axis, hence that far from every surface;
//! - near the surfaces (k ≤ [`EXACT_STEPS`]), where boxes standing off slanted triangles
//!   would leave little, the exact distance to the nearest primitive is asked for instead.

use super::{Aabb, Vec3};
use rayon::prelude::*;
use std::collections::VecDeque;

/// Most voxels a grid holds (one byte each).
pub const MAX_VOXELS: usize = 1 << 21;
/// Voxels at most this many steps from a marked one get their centre's exact distance.
pub const EXACT_STEPS: u8 = 6;
/// Bounds are stored rounded down to multiples of a voxel side over this.
const LEVELS_PER_SIDE: f64 = 8.0;

/// Distance lower bounds on a voxel grid over a region of the scene.
#[derive(Debug, Clone)]
pub struct ClearanceGrid {
    lo: Vec3,
    side: f64,
    dims: [usize; 3],
    /// Each voxel's lower bound at its centre (x fastest), in units of `side /
    /// LEVELS_PER_SIDE`, saturated at 255.
    centre: Vec<u8>,
}

impl ClearanceGrid {
    /// A grid over `region` of at most [`MAX_VOXELS`] cubic voxels. `surfaces` are the
    /// bounding boxes of all of the scene's primitives (a box reaching outside the region
    /// marks the voxels nearest it inside); `exact(p, reach)` is a lower bound on the
    /// distance from `p` to every primitive, at most `reach` (it need search no further).
    /// `None` for an empty or flat region.
    pub fn build(
        region: Aabb,
        surfaces: impl Iterator<Item = Aabb>,
        exact: impl Fn(Vec3, f64) -> f64 + Sync,
    ) -> Option<Self> {
        let extent = region.max - region.min;
        let volume = extent.x * extent.y * extent.z;
        if region.is_empty() || !(volume > 0.0 && volume.is_finite()) {
            return None;
        }
        let mut side = (volume / MAX_VOXELS as f64).cbrt();
        let dims = loop {
            let d = [0, 1, 2].map(|i| ((extent[i] / side).ceil() as usize).max(1));
            if d[0] * d[1] * d[2] <= MAX_VOXELS {
                break d;
            }
            side *= 1.01;
        };
        let mut grid = Self {
            lo: region.min,
            side,
            dims,
            centre: Vec::new(),
        };
        let steps = grid.steps(surfaces);
        let unit = side / LEVELS_PER_SIDE;
        let reach = (f64::from(EXACT_STEPS) + 1.0) * side;
        grid.centre = steps
            .par_iter()
            .enumerate()
            .map(|(i, &k)| {
                let boxes = (f64::from(k) - 0.5).max(0.0) * side;
                let d = if k <= EXACT_STEPS {
                    boxes.max(exact(grid.centre_of(i), reach))
                } else {
                    boxes
                };
                (d / unit).floor().min(255.0) as u8
            })
            .collect();
        Some(grid)
    }

    /// Chebyshev index distance of each voxel to the nearest marked one, saturated at 255.
    fn steps(&self, surfaces: impl Iterator<Item = Aabb>) -> Vec<u8> {
        let [nx, ny, nz] = self.dims;
        let mut steps = vec![u8::MAX; nx * ny * nz];
        let mut queue = VecDeque::new();
        for b in surfaces {
            let (Some(lo), Some(hi)) = (self.voxel_clamped(b.min), self.voxel_clamped(b.max))
            else {
                continue;
            };
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let i = self.index([x, y, z]);
                        if steps[i] != 0 {
                            steps[i] = 0;
                            queue.push_back(i);
                        }
                    }
                }
            }
        }
        while let Some(i) = queue.pop_front() {
            let next = steps[i].saturating_add(1);
            let [x, y, z] = self.coords(i);
            for zz in z.saturating_sub(1)..=(z + 1).min(nz - 1) {
                for yy in y.saturating_sub(1)..=(y + 1).min(ny - 1) {
                    for xx in x.saturating_sub(1)..=(x + 1).min(nx - 1) {
                        let j = self.index([xx, yy, zz]);
                        if steps[j] > next {
                            steps[j] = next;
                            queue.push_back(j);
                        }
                    }
                }
            }
        }
        steps
    }

    /// The voxel of `p` clamped into the grid; `None` for a NaN coordinate.
    fn voxel_clamped(&self, p: Vec3) -> Option<[usize; 3]> {
        let mut v = [0; 3];
        for i in 0..3 {
            let f = ((p[i] - self.lo[i]) / self.side).floor();
            if f.is_nan() {
                return None;
            }
            v[i] = f.clamp(0.0, (self.dims[i] - 1) as f64) as usize;
        }
        Some(v)
    }

    #[inline]
    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// The inverse of [`Self::index`].
    #[inline]
    fn coords(&self, i: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }

    #[inline]
    fn centre_of(&self, i: usize) -> Vec3 {
        let [x, y, z] = self.coords(i);
        self.lo + Vec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * self.side
    }

    /// Lower every voxel's bound to what `bound` (a lower bound on the distance to one more
    /// surface, such as a large analytic shape whose box would mark the whole grid) gives
    /// at its centre.
    pub fn limit(&mut self, bound: impl Fn(Vec3) -> f64 + Sync) {
        let unit = self.side / LEVELS_PER_SIDE;
        let mut centre = std::mem::take(&mut self.centre);
        centre.par_iter_mut().enumerate().for_each(|(i, level)| {
            let d = bound(self.centre_of(i)).max(0.0);
            *level = (*level).min((d / unit).floor().min(255.0) as u8);
        });
        self.centre = centre;
    }

    /// A lower bound on the distance from `p` to every surface [mm] (0 outside the grid).
    /// Not yet shrunk for rounding.
    #[inline]
    pub fn clearance(&self, p: Vec3) -> f64 {
        let mut index = 0;
        let mut stride = 1;
        let mut offset = Vec3::ZERO;
        for i in 0..3 {
            let f = (p[i] - self.lo[i]) / self.side;
            // also false for NaN
            if !(f >= 0.0 && f < self.dims[i] as f64) {
                return 0.0;
            }
            let cell = f as usize;
            offset[i] = f - cell as f64 - 0.5;
            index += cell * stride;
            stride *= self.dims[i];
        }
        let d = f64::from(self.centre[index]) / LEVELS_PER_SIDE - offset.length();
        d.max(0.0) * self.side
    }

    /// Side of a voxel [mm].
    pub fn side(&self) -> f64 {
        self.side
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Stream;

    fn box_distance(b: &Aabb, p: Vec3) -> f64 {
        b.distance2(p).sqrt()
    }

    #[test]
    fn bounds_the_distance_to_every_box_and_is_tight_near_them() {
        let mut rng = Stream::new(9, 0, 0);
        let mut point = |scale: f64| {
            Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * scale - scale / 2.0
        };
        // small boxes (the "surfaces") inside a 10 mm region, one far outside it
        let mut boxes: Vec<Aabb> = (0..40)
            .map(|_| {
                let c = point(10.0);
                Aabb::EMPTY.grow(c).grow(c + Vec3::splat(0.2))
            })
            .collect();
        boxes.push(
            Aabb::EMPTY
                .grow(Vec3::new(30.0, 0.0, 0.0))
                .grow(Vec3::new(31.0, 1.0, 1.0)),
        );
        let exact = |p: Vec3| {
            boxes
                .iter()
                .map(|b| box_distance(b, p))
                .fold(f64::INFINITY, f64::min)
        };
        let region = Aabb::EMPTY.grow(Vec3::splat(-5.0)).grow(Vec3::splat(5.0));
        for near in [true, false] {
            // with and without the exact distances near the boxes
            let ask = |p: Vec3, reach: f64| if near { exact(p).min(reach) } else { 0.0 };
            let grid = ClearanceGrid::build(region, boxes.iter().copied(), ask).unwrap();
            let mut rng = Stream::new(10, 0, 0);
            for _ in 0..20_000 {
                let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 12.0 - 6.0;
                let (c, d) = (grid.clearance(p), exact(p));
                assert!(c <= d, "{c} above the distance {d} at {p}");
                let inside = (0..3).all(|i| p[i].abs() < 5.0);
                if inside && near && d < 6.0 * grid.side() {
                    // the centre's exact distance, less at most half a diagonal twice and a level
                    let slack = (3f64.sqrt() + 1.0 / LEVELS_PER_SIDE) * grid.side();
                    assert!(c >= d - slack, "{c} against {d} at {p}");
                } else if inside {
                    // the Chebyshev bound: within a few voxels of the maximum-norm distance,
                    // the far box counting as the region's face it is clamped onto, and the
                    // stored bounds saturating at 255 levels
                    let d = d.min(5.0 - p.x).min(255.0 / LEVELS_PER_SIDE * grid.side());
                    assert!(c >= d / 3f64.sqrt() - 4.0 * grid.side(), "{c} against {d}");
                } else {
                    assert_eq!(c, 0.0);
                }
            }
        }
        // an analytic bound lowers the grid where it is smaller
        let mut grid = ClearanceGrid::build(region, boxes.iter().copied(), |_, _| 0.0).unwrap();
        let wall = |p: Vec3| (p.x + 5.5).abs();
        grid.limit(wall);
        let p = Vec3::new(-4.9, 0.3, 0.2);
        assert!(grid.clearance(p) <= wall(p));
        assert!(ClearanceGrid::build(Aabb::EMPTY, boxes.into_iter(), |_, _| 0.0).is_none());
    }
}
