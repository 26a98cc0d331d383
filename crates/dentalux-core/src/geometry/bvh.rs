//! A bounding volume hierarchy over all primitives of a scene (analytic shapes and single
//! triangles alike), built with the binned surface-area heuristic and flattened depth-first
//! (the left child of node i is node i + 1), in f64 like the rest of the renderer.
//!
//! Why our own instead of a crate: the maintained `bvh` crate works in f32 through nalgebra
//! and owns the primitive trait; the scene here needs f64 (mm-scale specimens inside 500 mm
//! boxes), a closed enum of primitives matched without dynamic dispatch, and both a nearest
//! and an any-hit query. A binned SAH build is ~150 lines; `benchmarks/render_cornell.py`
//! prints its build and traversal speed on a 1 M-triangle mesh.

use super::{Aabb, Ray, Vec3};

/// Most primitives a leaf holds when splitting still pays off.
const MAX_LEAF: usize = 4;
/// Number of SAH bins per axis.
const BINS: usize = 12;
/// Deepest tree allowed (the traversal stack holds this many entries).
const MAX_DEPTH: usize = 96;
/// At most this many primitives are searched by testing each one's box in slot order
/// instead of a traversal (the Fig. 3 scene's four shapes: the tree's inner boxes and its
/// stack cost more than they save there).
const SCAN: usize = 8;

/// One flattened node, 32 bytes: bounds stored as f32 rounded outwards (so the box still
/// holds its f64 contents; intersections themselves stay f64), which halves the memory a
/// traversal pulls through the cache on large meshes.
#[derive(Debug, Clone, Copy)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    /// Leaf: index of the first primitive in `order`; interior: index of the right child.
    offset: u32,
    /// Number of primitives (0 for an interior node) in the low 30 bits; split axis of an
    /// interior node (traversal visits the near child first) in the top 2.
    count_axis: u32,
}

/// f32 not above `x`.
#[inline]
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        f.next_down()
    } else {
        f
    }
}

/// f32 not below `x`.
#[inline]
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

impl Node {
    fn new(b: &Aabb, offset: usize, count: usize) -> Self {
        Self {
            lo: [f32_down(b.min.x), f32_down(b.min.y), f32_down(b.min.z)],
            hi: [f32_up(b.max.x), f32_up(b.max.y), f32_up(b.max.z)],
            offset: offset as u32,
            count_axis: count as u32,
        }
    }
    #[inline]
    fn count(&self) -> u32 {
        self.count_axis & 0x3FFF_FFFF
    }
    #[inline]
    fn axis(&self) -> usize {
        (self.count_axis >> 30) as usize
    }
    #[inline]
    fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::new(self.lo[0] as f64, self.lo[1] as f64, self.lo[2] as f64),
            max: Vec3::new(self.hi[0] as f64, self.hi[1] as f64, self.hi[2] as f64),
        }
    }
}

/// A BVH over primitives identified by their index in the slice given to [`Bvh::build`].
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// Each slot's box (rounded outwards as the nodes' are) when there are at most
    /// [`SCAN`] primitives; empty otherwise.
    scan: Vec<Node>,
}

struct Item {
    bounds: Aabb,
    centroid: Vec3,
}

impl Bvh {
    /// Build over primitive bounds (index i is primitive i).
    pub fn build(bounds: &[Aabb]) -> Self {
        let mut items: Vec<Item> = bounds
            .iter()
            .map(|b| Item {
                bounds: *b,
                centroid: b.centroid(),
            })
            .collect();
        let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * bounds.len() / MAX_LEAF + 1);
        if !bounds.is_empty() {
            build_node(&mut nodes, &mut items, &mut order, 0, bounds.len(), 0);
        }
        let scan = if bounds.len() <= SCAN {
            order
                .iter()
                .map(|&p| Node::new(&bounds[p as usize], 0, 1))
                .collect()
        } else {
            Vec::new()
        };
        Self { nodes, order, scan }
    }

    /// The primitive in each slot: leaves hold consecutive slots.
    pub fn order(&self) -> &[u32] {
        &self.order
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bounds of everything (empty box when there are no primitives).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds())
    }

    /// Visit primitives whose boxes the ray meets before `t_max`, near first. `test(slot,
    /// t_max)` — `slot` indexes [`Bvh::order`], whose entry is the primitive — returns the
    /// distance of a hit closer than `t_max` (then the search shrinks to it), or `None`.
    /// Returns the nearest distance found. Callers that store their primitives in slot order
    /// read a leaf's primitives from contiguous memory.
    #[inline]
    pub fn nearest<F: FnMut(u32, f64) -> Option<f64>>(
        &self,
        ray: &Ray,
        t_max: f64,
        mut test: F,
    ) -> Option<f64> {
        let mut best = t_max;
        let mut found = false;
        self.walk(ray, &mut best, |prim, tm| match test(prim, tm) {
            Some(t) if t < tm => {
                found = true;
                (Some(t), false)
            }
            _ => (None, false),
        });
        found.then_some(best)
    }

    /// Whether `test(slot, t_max)` is true for any primitive whose box the ray meets (`slot`
    /// as in [`Bvh::nearest`]).
    #[inline]
    pub fn any<F: FnMut(u32, f64) -> bool>(&self, ray: &Ray, t_max: f64, mut test: F) -> bool {
        let mut best = t_max;
        let mut hit = false;
        self.walk(ray, &mut best, |prim, tm| {
            if test(prim, tm) {
                hit = true;
                (None, true)
            } else {
                (None, false)
            }
        });
        hit
    }

    /// A lower bound on the distance from `p` to every primitive, at most `reach`:
    /// `dist(slot)` is a lower bound on the distance to the primitive in `slot` (as in
    /// [`Bvh::nearest`]). Subtrees whose box lies at least the bound found so far from `p`
    /// are skipped: everything in them is at least that far.
    pub fn distance_bound<F: FnMut(u32) -> f64>(&self, p: Vec3, reach: f64, mut dist: F) -> f64 {
        let mut best = reach;
        for (slot, node) in self.scan.iter().enumerate() {
            if node.bounds().distance2(p) < best * best {
                best = best.min(dist(slot as u32));
            }
        }
        if self.nodes.is_empty() || !self.scan.is_empty() {
            return best;
        }
        let mut stack = [(0u32, 0.0f64); MAX_DEPTH + 2];
        let mut top = 1;
        stack[0] = (0, self.nodes[0].bounds().distance2(p));
        while top > 0 {
            top -= 1;
            let (n, d2) = stack[top];
            if d2 >= best * best {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count() > 0 {
                let first = node.offset as usize;
                for slot in first..first + node.count() as usize {
                    best = best.min(dist(slot as u32));
                }
                continue;
            }
            let (a, b) = (n + 1, node.offset);
            let da = self.nodes[a as usize].bounds().distance2(p);
            let db = self.nodes[b as usize].bounds().distance2(p);
            // the nearer child on top of the stack: it is searched first
            let (near, far) = if da <= db {
                ((a, da), (b, db))
            } else {
                ((b, db), (a, da))
            };
            stack[top] = far;
            stack[top + 1] = near;
            top += 2;
        }
        best
    }

    /// Core traversal: `visit` returns (a new closer t_max, stop now).
    #[inline]
    fn walk<F: FnMut(u32, f64) -> (Option<f64>, bool)>(
        &self,
        ray: &Ray,
        t_max: &mut f64,
        mut visit: F,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv_d = ray.d.recip();
        if !self.scan.is_empty() {
            for (slot, node) in self.scan.iter().enumerate() {
                if node.bounds().hit_distance(ray.o, inv_d, *t_max).is_finite() {
                    let (closer, stop) = visit(slot as u32, *t_max);
                    if let Some(t) = closer {
                        *t_max = t;
                    }
                    if stop {
                        return;
                    }
                }
            }
            return;
        }
        let neg = [ray.d.x < 0.0, ray.d.y < 0.0, ray.d.z < 0.0];
        let mut stack = [0u32; MAX_DEPTH + 2];
        let mut top = 0;
        let mut current = 0usize;
        if self.nodes[0]
            .bounds()
            .hit_distance(ray.o, inv_d, *t_max)
            .is_infinite()
        {
            return;
        }
        loop {
            let node = &self.nodes[current];
            if node.count() > 0 {
                let first = node.offset as usize;
                for slot in first..first + node.count() as usize {
                    let (closer, stop) = visit(slot as u32, *t_max);
                    if let Some(t) = closer {
                        *t_max = t;
                    }
                    if stop {
                        return;
                    }
                }
            } else {
                let (mut near, mut far) = (current + 1, node.offset as usize);
                if neg[node.axis()] {
                    std::mem::swap(&mut near, &mut far);
                }
                let tn = self.nodes[near].bounds().hit_distance(ray.o, inv_d, *t_max);
                let tf = self.nodes[far].bounds().hit_distance(ray.o, inv_d, *t_max);
                match (tn.is_finite(), tf.is_finite()) {
                    (true, true) => {
                        // visit the closer box first, keep the other for later
                        let (a, b) = if tf < tn { (far, near) } else { (near, far) };
                        stack[top] = b as u32;
                        top += 1;
                        current = a;
                        continue;
                    }
                    (true, false) => {
                        current = near;
                        continue;
                    }
                    (false, true) => {
                        current = far;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            // pop the next subtree that may still hold something closer
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let n = stack[top] as usize;
                if self.nodes[n]
                    .bounds()
                    .hit_distance(ray.o, inv_d, *t_max)
                    .is_finite()
                {
                    current = n;
                    break;
                }
            }
        }
    }
}

/// Build the subtree over items[start..end]; returns its node index.
fn build_node(
    nodes: &mut Vec<Node>,
    items: &mut [Item],
    order: &mut [u32],
    start: usize,
    end: usize,
    depth: usize,
) -> usize {
    let index = nodes.len();
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for it in &items[start..end] {
        bounds = bounds.union(&it.bounds);
        cbounds = cbounds.grow(it.centroid);
    }
    nodes.push(Node::new(&bounds, start, end - start));
    let n = end - start;
    if n <= 1 || depth >= MAX_DEPTH {
        return index;
    }
    // binned SAH over the three axes
    let extent = cbounds.max - cbounds.min;
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, split bin)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f64 / extent[axis];
        let bin_of = |c: Vec3| (((c[axis] - cbounds.min[axis]) * scale) as usize).min(BINS - 1);
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for it in &items[start..end] {
            let b = bin_of(it.centroid);
            bin_bounds[b] = bin_bounds[b].union(&it.bounds);
            bin_count[b] += 1;
        }
        // sweep: areas and counts left of each split plane, then right
        let mut left_area = [0.0; BINS];
        let mut left_count = [0usize; BINS];
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
            acc = acc.union(&bin_bounds[i]);
            cnt += bin_count[i];
            left_area[i] = acc.area();
            left_count[i] = cnt;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            acc = acc.union(&bin_bounds[i]);
            cnt += bin_count[i];
            let lc = left_count[i - 1];
            if lc == 0 || cnt == 0 {
                continue;
            }
            let cost = left_area[i - 1] * lc as f64 + acc.area() * cnt as f64;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let Some((cost, axis, split)) = best else {
        // all centroids coincide: no split separates them
        return index;
    };
    // a leaf is cheaper than traversal + two children when the SAH says so
    let leaf_cost = n as f64 * bounds.area();
    if n <= MAX_LEAF && cost >= leaf_cost - 1.0 * bounds.area() {
        return index;
    }
    let scale = BINS as f64 / extent[axis];
    let lo = cbounds.min[axis];
    // partition items (and the order alongside) by bin
    let (mut i, mut j) = (start, end);
    while i < j {
        let b = (((items[i].centroid[axis] - lo) * scale) as usize).min(BINS - 1);
        if b < split {
            i += 1;
        } else {
            j -= 1;
            items.swap(i, j);
            order.swap(i, j);
        }
    }
    let mid = i;
    if mid == start || mid == end {
        return index;
    }
    nodes[index].count_axis = (axis as u32) << 30;
    build_node(nodes, items, order, start, mid, depth + 1);
    let right = build_node(nodes, items, order, mid, end, depth + 1);
    nodes[index].offset = right as u32;
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes::Sphere;
    use crate::rng::Stream;
    use crate::sampling::uniform_sphere;

    #[test]
    fn nearest_and_any_match_brute_force_on_random_spheres() {
        // 500 spheres (a traversal) and 6 large ones (the scan of SCAN or fewer)
        for (count, size) in [(500, 0.8), (6, 6.0)] {
            brute_force_check(count, size);
        }
    }

    fn brute_force_check(count: usize, size: f64) {
        let mut rng = Stream::new(11, 0, 0);
        let spheres: Vec<Sphere> = (0..count)
            .map(|_| Sphere {
                center: Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 20.0 - 10.0,
                radius: 0.05 + rng.uniform() * size,
            })
            .collect();
        let bvh = Bvh::build(&spheres.iter().map(|s| s.bounds()).collect::<Vec<_>>());
        assert!(count <= SCAN || bvh.node_count() > 100);
        assert_eq!(bvh.scan.len(), if count <= SCAN { count } else { 0 });
        for _ in 0..5000 {
            let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 30.0 - 15.0;
            let ray = Ray::new(o, uniform_sphere(rng.uniform2()));
            let t_max = if rng.uniform() < 0.5 {
                f64::INFINITY
            } else {
                8.0
            };
            let brute = spheres
                .iter()
                .filter_map(|s| s.intersect(ray.o, ray.d, t_max).map(|h| h.t))
                .fold(f64::INFINITY, f64::min);
            let got = bvh.nearest(&ray, t_max, |i, tm| {
                spheres[bvh.order()[i as usize] as usize]
                    .intersect(ray.o, ray.d, tm)
                    .map(|h| h.t)
            });
            match got {
                Some(t) => assert_eq!(t, brute),
                None => assert!(brute.is_infinite()),
            }
            let any = bvh.any(&ray, t_max, |i, tm| {
                spheres[bvh.order()[i as usize] as usize]
                    .intersect(ray.o, ray.d, tm)
                    .is_some()
            });
            assert_eq!(any, brute.is_finite());
            // the distance to the nearest sphere's surface, skipping far subtrees, is exact
            let gap = |i: u32| {
                let s = &spheres[bvh.order()[i as usize] as usize];
                ((o - s.center).length() - s.radius).abs()
            };
            let least = (0..count as u32).map(gap).fold(f64::INFINITY, f64::min);
            let mut asked = 0;
            let got = bvh.distance_bound(o, f64::INFINITY, |i| {
                asked += 1;
                gap(i)
            });
            assert_eq!(got, least);
            assert!(
                count <= SCAN || asked < count / 4,
                "{asked} of {count} asked"
            );
            assert_eq!(bvh.distance_bound(o, 0.5 * least, gap), 0.5 * least);
        }
    }

    #[test]
    fn empty_and_coincident() {
        let b = Bvh::build(&[]);
        assert!(b
            .nearest(&Ray::new(Vec3::ZERO, Vec3::X), 1.0, |_, _| Some(0.5))
            .is_none());
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        // 100 identical primitives: one leaf, no endless recursion
        let b = Bvh::build(&vec![s.bounds(); 100]);
        let mut visits = 0;
        b.nearest(
            &Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X),
            100.0,
            |_, _| {
                visits += 1;
                None
            },
        );
        assert_eq!(visits, 100);
    }
}
