//! Photon maps: compact photon records, a balanced kd-tree over them, k-nearest and
//! fixed-radius queries, and the radiance estimates of the paper (eq. 11's multiple-scattering
//! term for volumes, the classic Σ f ΔΦ / (π r²) for surfaces).
//!
//! **For the surface photon map (renderer-core, `integrators/pm.rs`):** this file serves both
//! maps. Collect `Photon::new(position [mm], travel_direction, power)` records (the travel
//! direction is the direction the photon was moving when it landed, i.e. `-wi`), build with
//! [`PhotonMap::build`], then per shading point call [`PhotonMap::surface_irradiance`] and
//! multiply by the BRDF (ρ/π for Lambertian). [`PhotonMap::knn`] / [`PhotonMap::for_each_within`]
//! give raw neighbour access. Photon power is the light's power Φ divided by the number of
//! photons emitted (not stored).
//!
//! Layout: a photon is 20 bytes ([`PHOTON_BYTES`]): position as 3 × f32, power as f32, and one
//! u32 holding the travel direction (octahedral map, 15 + 15 bits, error < 2e-4 rad) and the
//! kd-tree split axis (2 bits). The tree is implicit: the photons are permuted so that the
//! median of `[lo, hi)` sits at `(lo + hi) / 2` with the smaller half to its left, so the map
//! needs no memory beyond the photon array itself (100 M photons = 2.0 GB).
//!
//! Why not `kiddo`: its trees keep their own copy of the coordinates plus an item index per
//! point (≥ 16 bytes on top of the record), which breaks the memory target of 100 M photons in
//! < 3 GB; an implicit median tree is the classic photon-map structure (Jensen 2001) and is
//! short.

use crate::math::Frame;
use crate::math::Vec3;
use crate::phase::PhaseFunction;
use std::f64::consts::PI;

/// Size of one stored photon [bytes].
pub const PHOTON_BYTES: usize = std::mem::size_of::<Photon>();

/// Subtrees at most this long are scanned linearly instead of descended.
const LEAF: usize = 16;
/// Subtrees at least this long are built in parallel (rayon::join).
const PAR_BUILD: usize = 16_384;
/// Bits per octahedral coordinate.
const OCT_BITS: u32 = 15;
const OCT_MAX: f32 = ((1u32 << OCT_BITS) - 1) as f32;

/// One stored photon: where it is, which way it travelled, and how much power it carries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Photon {
    /// Position [mm] (f32: 1e-5 mm resolution at 100 mm from the origin).
    pub pos: [f32; 3],
    /// Power ΔΦ_p carried by the photon [W up to the scene's global scale].
    pub power: f32,
    /// Octahedral travel direction (bits 0–29) and kd-tree split axis (bits 30–31).
    packed: u32,
}

/// Octahedral encoding of a unit vector into 15 + 15 bits.
fn encode_dir(d: Vec3) -> u32 {
    let l1 = d.x.abs() + d.y.abs() + d.z.abs();
    let (mut x, mut y) = if l1 > 0.0 {
        (d.x / l1, d.y / l1)
    } else {
        (0.0, 0.0)
    };
    if d.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * if ox >= 0.0 { 1.0 } else { -1.0 };
        y = (1.0 - ox.abs()) * if oy >= 0.0 { 1.0 } else { -1.0 };
    }
    let q = |v: f64| (((v * 0.5 + 0.5) as f32 * OCT_MAX).round() as u32).min(OCT_MAX as u32);
    q(x) | (q(y) << OCT_BITS)
}

/// Inverse of [`encode_dir`] (unit vector).
fn decode_dir(bits: u32) -> Vec3 {
    let mask = (1u32 << OCT_BITS) - 1;
    let x = (bits & mask) as f64 / OCT_MAX as f64 * 2.0 - 1.0;
    let y = ((bits >> OCT_BITS) & mask) as f64 / OCT_MAX as f64 * 2.0 - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    Vec3::new(x, y, z).normalize()
}

impl Photon {
    /// A photon at `pos` [mm] that was travelling along the unit vector `dir`, carrying `power`.
    pub fn new(pos: Vec3, dir: Vec3, power: f64) -> Self {
        Self {
            pos: [pos.x as f32, pos.y as f32, pos.z as f32],
            power: power as f32,
            packed: encode_dir(dir),
        }
    }
    /// Position [mm].
    #[inline]
    pub fn position(&self) -> Vec3 {
        Vec3::new(self.pos[0] as f64, self.pos[1] as f64, self.pos[2] as f64)
    }
    /// Unit travel direction at the moment of storage (the incoming direction is its negative).
    #[inline]
    pub fn direction(&self) -> Vec3 {
        decode_dir(self.packed & 0x3FFF_FFFF)
    }
    #[inline]
    fn axis(&self) -> usize {
        (self.packed >> 30) as usize
    }
    #[inline]
    fn set_axis(&mut self, axis: usize) {
        self.packed = (self.packed & 0x3FFF_FFFF) | ((axis as u32) << 30);
    }
}

/// A reusable buffer for k-nearest queries: the photons found so far, unordered, and the
/// squared radius that still matters. Candidates are appended in O(1); when the buffer holds
/// 2k of them it is cut back to the k nearest by a linear-time selection, which tightens the
/// bound (amortised O(1) per candidate, against O(log k) sifts of a binary heap).
#[derive(Debug, Default, Clone)]
pub struct Neighbours {
    found: Vec<(f32, u32)>,
    k: usize,
    /// Squared search radius that still matters [mm²]: `r_max²` until k are found, then the
    /// k-th smallest distance² among those found at the last cut.
    bound: f32,
    /// Buffer length that triggers the next cut.
    cap: usize,
    max_d2: f32,
}

impl Neighbours {
    /// An empty buffer.
    pub fn new() -> Self {
        Self::default()
    }
    /// Number of photons found.
    pub fn len(&self) -> usize {
        self.found.len()
    }
    /// Whether no photon was found.
    pub fn is_empty(&self) -> bool {
        self.found.is_empty()
    }
    /// (distance² [mm²], index into [`PhotonMap::photons`]) of the photons found, unordered.
    pub fn items(&self) -> &[(f32, u32)] {
        &self.found
    }
    /// Largest squared distance among the photons found [mm²] (0 when none).
    pub fn max_dist2(&self) -> f32 {
        self.max_d2
    }
    fn start(&mut self, k: usize, r2_max: f32) {
        self.found.clear();
        self.k = k.max(1);
        self.bound = r2_max;
        self.cap = self.k;
        self.max_d2 = 0.0;
    }
    /// Keep the k nearest and tighten the bound to the k-th distance².
    fn cut(&mut self) {
        let k = self.k;
        if self.found.len() > k {
            self.found
                .select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            self.found.truncate(k);
            self.bound = self.found[k - 1].0;
        } else if self.found.len() == k {
            self.bound = self.found.iter().fold(0.0f32, |m, h| m.max(h.0));
        }
        self.cap = 2 * k.max(8);
    }
    #[inline]
    fn push(&mut self, d2: f32, i: u32) {
        self.found.push((d2, i));
        if self.found.len() >= self.cap {
            self.cut();
        }
    }
    fn finish(&mut self) {
        if self.found.len() > self.k {
            self.cut();
        }
        self.max_d2 = self.found.iter().fold(0.0f32, |m, h| m.max(h.0));
    }
}

/// A density estimate: its value, the radius it used [mm] and the number of photons in it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Estimate {
    /// The estimate (units depend on the estimator; see its doc).
    pub value: f64,
    /// Radius of the gathering sphere or disc [mm].
    pub radius: f64,
    /// Photons that contributed.
    pub count: usize,
}

/// Photons arranged as an implicit balanced kd-tree.
#[derive(Debug, Clone, Default)]
pub struct PhotonMap {
    photons: Vec<Photon>,
}

fn build_rec(p: &mut [Photon]) {
    let n = p.len();
    if n <= LEAF {
        return;
    }
    // split along the axis of largest extent, at the median
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for q in p.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(q.pos[a]);
            hi[a] = hi[a].max(q.pos[a]);
        }
    }
    let ext = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] {
        0
    } else if ext[1] >= ext[2] {
        1
    } else {
        2
    };
    let mid = n / 2;
    p.select_nth_unstable_by(mid, |a, b| a.pos[axis].total_cmp(&b.pos[axis]));
    p[mid].set_axis(axis);
    let (l, r) = p.split_at_mut(mid);
    let r = &mut r[1..];
    if n >= PAR_BUILD {
        rayon::join(|| build_rec(l), || build_rec(r));
    } else {
        build_rec(l);
        build_rec(r);
    }
}

#[inline]
fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

/// The boundary planes around a point in a medium, each (point, unit outward normal): the
/// nearer one orients the layer kernel; `far`, when anti-parallel to it, bounds a thin layer.
/// `clip`, when set, removes from the kernel what lies beyond any other face (a disc's rim,
/// a curved wall): see [`KernelClip`].
#[derive(Clone, Copy)]
pub struct Planes<'a> {
    /// The nearer boundary plane.
    pub near: (Vec3, Vec3),
    /// The opposite boundary plane, if any.
    pub far: Option<(Vec3, Vec3)>,
    /// Rays that find the other faces within the kernel, if enabled.
    pub clip: Option<KernelClip<'a>>,
}

/// Quadrature of a kernel cut by faces parallel to its axis: strata in radius² and angle of
/// its cross-section (the axial moments are exact).
const CLIP_GRID_2D: [usize; 2] = [16, 32];
/// Quadrature of a kernel cut by an oblique face: strata along the axis, radius², angle.
const CLIP_GRID_3D: [usize; 3] = [4, 8, 16];
/// Rays cast from the estimate's point to the kernel's outer edge to find other faces.
const CLIP_RAYS: usize = 8;

/// The part of a layer kernel that lies inside the medium. The two planes cut the kernel
/// exactly, but near a disc's rim or on a curved wall another face cuts it too, and a
/// kernel that counts photons over a volume partly outside the medium reads too dark
/// (issue 5's bias map: −5 … −9 % along the rims, to −20 % at the foot of a curved wall).
/// Eight rays from the estimate's point to the kernel's outer edge (alternately at its two
/// ends along the axis, rotated by a random angle `u` per estimate) find the faces within
/// it; each face met is replaced by its tangent plane there (the kernel is small beside a
/// face's curvature). Where a face is met, the inside part's axial moments ∫1, ∫z, ∫z² come
/// from a quadrature against those planes, rotated by `u` so that they are unbiased: over
/// the cross-section (512 points; the axial integrals exact) when every plane is parallel
/// to the kernel's axis (a disc's side wall seen from its top, or its top seen from the
/// side wall), over the volume (512 points) otherwise. The depth fit then uses them. (A fit
/// linear in all three directions, towards the wall as well, measured the same on Fig. 3:
/// docs/vpm-convergence.md.) Where no face is met, the kernel keeps its exact moments.
#[derive(Clone, Copy)]
pub struct KernelClip<'a> {
    /// The first surface on the segment from a point along a unit direction within a
    /// distance [mm]: (hit point, surface normal), any orientation.
    pub hit: &'a dyn Fn(Vec3, Vec3, f64) -> Option<(Vec3, Vec3)>,
    /// Random rotation of the rays and quadrature points about the kernel's axis, [0, 1).
    pub u: f64,
}

/// Whether offset `d` lies on the inner side of every plane (offset, outward unit normal).
fn inside_planes(planes: &[(Vec3, Vec3)], d: Vec3) -> bool {
    planes.iter().all(|(o, nrm)| (d - *o).dot(*nrm) < 0.0)
}

/// ∫1, ∫z, ∫z² over a prism of cross-section `area` and z ∈ [a, b].
fn prism_moments(area: f64, a: f64, b: f64) -> [f64; 3] {
    [
        area * (b - a),
        area * (b * b - a * a) / 2.0,
        area * (b * b * b - a * a * a) / 3.0,
    ]
}

/// The fraction of the disc of radius `r` about the origin of the (s, t) plane that lies
/// inside every plane (offset, outward normal; z ignored): a 512-point quadrature in
/// radius² and angle, rotated by `u` ∈ [0, 1).
fn disc_fraction_inside(planes: &[(Vec3, Vec3)], r: f64, u: f64) -> f64 {
    let [nr, na] = CLIP_GRID_2D;
    let dirs = rotated_circle::<{ CLIP_GRID_2D[1] }>(u);
    let mut hits = 0usize;
    for ir in 0..nr {
        let rho = r * ((ir as f64 + 0.5) / nr as f64).sqrt();
        for [c, s] in dirs {
            hits += inside_planes(planes, Vec3::new(rho * c, rho * s, 0.0)) as usize;
        }
    }
    hits as f64 / (nr * na) as f64
}

/// (cos φ_j, sin φ_j) for φ_j = 2π (j + u) / N, j < N: one sin_cos and a rotation per point
/// (the quadratures' 512 sin_cos calls were 5 % of a Fig. 3 render).
fn rotated_circle<const N: usize>(u: f64) -> [[f64; 2]; N] {
    let (s0, c0) = (2.0 * PI * u / N as f64).sin_cos();
    let (ds, dc) = (2.0 * PI / N as f64).sin_cos();
    let mut out = [[0.0; 2]; N];
    let (mut c, mut s) = (c0, s0);
    for o in out.iter_mut() {
        *o = [c, s];
        (c, s) = (c * dc - s * ds, s * dc + c * ds);
    }
    out
}

impl KernelClip<'_> {
    /// The faces met by rays from `x` to the points `target(j)` (j < CLIP_RAYS, in `frame`,
    /// offsets from x), as planes in `frame`: (offset from x, unit normal pointing away from
    /// x), duplicates (the same plane met twice, to `1e-3 · scale`) dropped.
    fn faces(
        &self,
        x: Vec3,
        frame: &Frame,
        scale: f64,
        target: impl Fn(usize) -> Vec3,
    ) -> ([(Vec3, Vec3); CLIP_RAYS], usize) {
        let mut planes = [(Vec3::ZERO, Vec3::ZERO); CLIP_RAYS];
        let mut count = 0;
        for j in 0..CLIP_RAYS {
            let d = frame.to_world(target(j));
            let len = d.length();
            let Some((p, nrm)) = (self.hit)(x, d / len, len * (1.0 - 1e-9)) else {
                continue;
            };
            let nrm = frame.to_local(if nrm.dot(d) < 0.0 { -nrm } else { nrm });
            let off = frame.to_local(p - x);
            let same = planes[..count]
                .iter()
                .any(|(o, m)| m.dot(nrm) > 0.999 && (off - *o).dot(nrm).abs() < 1e-3 * scale);
            if !same {
                planes[count] = (off, nrm);
                count += 1;
            }
        }
        (planes, count)
    }

    /// ∫1, ∫z, ∫z² over the inside part of the cylinder of radius `big_r` around `x`,
    /// axis `n`, z ∈ [a, b] measured along n from x; `None` when no other face lies in it.
    fn moments(&self, x: Vec3, n: Vec3, a: f64, b: f64, big_r: f64) -> Option<[f64; 3]> {
        let frame = Frame::from_axis(n);
        let rays = rotated_circle::<CLIP_RAYS>(self.u);
        let (planes, count) = self.faces(x, &frame, big_r, |j| {
            let [c, s] = rays[j];
            Vec3::new(big_r * c, big_r * s, if j % 2 == 0 { a } else { b })
        });
        if count == 0 {
            return None;
        }
        let planes = &planes[..count];
        let disc = PI * big_r * big_r;
        let m = if planes.iter().all(|(_, nrm)| nrm.z.abs() < 1e-6) {
            // cross-section A (its area by quadrature) times [a, b]
            prism_moments(disc * disc_fraction_inside(planes, big_r, self.u), a, b)
        } else {
            let [nz, nr, na] = CLIP_GRID_3D;
            let dirs = rotated_circle::<{ CLIP_GRID_3D[2] }>(self.u);
            let mut m = [0.0; 3];
            for iz in 0..nz {
                let z = a + (b - a) * (iz as f64 + 0.5) / nz as f64;
                for ir in 0..nr {
                    let rho = big_r * ((ir as f64 + 0.5) / nr as f64).sqrt();
                    for [c, s] in dirs {
                        if inside_planes(planes, Vec3::new(rho * c, rho * s, z)) {
                            m[0] += 1.0;
                            m[1] += z;
                            m[2] += z * z;
                        }
                    }
                }
            }
            m.map(|v| v * disc * (b - a) / (nz * nr * na) as f64)
        };
        (m[0] > 0.0).then_some(m)
    }
}

/// Gathering radius of a k-nearest query and the factor that makes its estimate unbiased
/// for a uniform density: when k photons were found the radius is the k-th distance and that
/// photon sits on the sphere, so Σ ΔΦ / V over k photons overestimates by k/(k − 1)
/// (E[(k − 1)/V_k] = density for a Poisson process); with fewer, the radius is `r_max`.
fn knn_radius(nb: &Neighbours, k: usize, r_max: f64) -> (f64, f64) {
    if nb.len() < k || k < 2 {
        (r_max, 1.0)
    } else {
        ((nb.max_dist2() as f64).sqrt(), (k - 1) as f64 / k as f64)
    }
}

impl PhotonMap {
    /// Build the tree from photons (parallel for large maps; O(n log n)).
    pub fn build(mut photons: Vec<Photon>) -> Self {
        // drop photons whose position is not finite: they would poison the ordering
        photons.retain(|p| p.pos.iter().all(|c| c.is_finite()) && p.power.is_finite());
        photons.shrink_to_fit();
        build_rec(&mut photons);
        Self { photons }
    }
    /// Number of stored photons.
    pub fn len(&self) -> usize {
        self.photons.len()
    }
    /// Whether the map holds no photon.
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }
    /// The photons, in tree order.
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }
    /// Memory held by the map [bytes].
    pub fn bytes(&self) -> usize {
        self.photons.capacity() * PHOTON_BYTES
    }
    /// Total stored power Σ ΔΦ_p.
    pub fn total_power(&self) -> f64 {
        self.photons.iter().map(|p| p.power as f64).sum()
    }

    /// Multiply every photon's power by `w` (the tree orders photons by position only, so it
    /// stays valid).
    pub fn scale_powers(&mut self, w: f64) {
        for p in &mut self.photons {
            p.power = (p.power as f64 * w) as f32;
        }
    }

    /// The (at most) `k` photons nearest to `x` within `r_max` [mm], into `out`.
    ///
    /// Iterative descent with an explicit stack: the near side first, the far side pushed with
    /// its squared distance to the splitting plane and skipped when popped if that exceeds the
    /// bound found meanwhile.
    pub fn knn(&self, x: Vec3, k: usize, r_max: f64, out: &mut Neighbours) {
        out.start(k, (r_max * r_max) as f32);
        let q = [x.x as f32, x.y as f32, x.z as f32];
        let ph = &self.photons[..];
        // the tree is balanced: depth ≤ log2(n) + 1 < 64
        let mut stack = [(0u32, 0u32, 0f32); 64];
        let mut sp = 0usize;
        let (mut lo, mut hi) = (0usize, ph.len());
        loop {
            while hi - lo > LEAF {
                let mid = (lo + hi) / 2;
                let p = &ph[mid];
                let d2 = dist2(&p.pos, &q);
                if d2 <= out.bound {
                    out.push(d2, mid as u32);
                }
                let axis = p.axis();
                let delta = q[axis] - p.pos[axis];
                let plane = delta * delta;
                let (near, far) = if delta < 0.0 {
                    ((lo, mid), (mid + 1, hi))
                } else {
                    ((mid + 1, hi), (lo, mid))
                };
                if far.0 < far.1 && plane <= out.bound {
                    stack[sp] = (far.0 as u32, far.1 as u32, plane);
                    sp += 1;
                }
                (lo, hi) = near;
            }
            for (j, p) in ph[lo..hi].iter().enumerate() {
                let d2 = dist2(&p.pos, &q);
                if d2 <= out.bound {
                    out.push(d2, (lo + j) as u32);
                }
            }
            loop {
                if sp == 0 {
                    out.finish();
                    return;
                }
                sp -= 1;
                let (l, h, plane) = stack[sp];
                if plane <= out.bound {
                    (lo, hi) = (l as usize, h as usize);
                    break;
                }
            }
        }
    }

    /// Call `f(photon, distance²)` for every photon within `r` [mm] of `x`.
    pub fn for_each_within<F: FnMut(&Photon, f32)>(&self, x: Vec3, r: f64, mut f: F) {
        let q = [x.x as f32, x.y as f32, x.z as f32];
        let r2 = (r * r) as f32;
        // explicit stack of [lo, hi) ranges; depth is log2(n) ≤ 64
        let mut stack: Vec<(usize, usize)> = Vec::with_capacity(64);
        if !self.photons.is_empty() {
            stack.push((0, self.photons.len()));
        }
        while let Some((lo, hi)) = stack.pop() {
            if hi - lo <= LEAF {
                for p in &self.photons[lo..hi] {
                    let d2 = dist2(&p.pos, &q);
                    if d2 <= r2 {
                        f(p, d2);
                    }
                }
                continue;
            }
            let mid = (lo + hi) / 2;
            let p = &self.photons[mid];
            let d2 = dist2(&p.pos, &q);
            if d2 <= r2 {
                f(p, d2);
            }
            let delta = q[p.axis()] - p.pos[p.axis()];
            if (delta <= 0.0 || delta * delta <= r2) && lo < mid {
                stack.push((lo, mid));
            }
            if (delta >= 0.0 || delta * delta <= r2) && mid + 1 < hi {
                stack.push((mid + 1, hi));
            }
        }
    }

    /// Eq. 11's multiple-scattering term at `x`: Σ p(d_p · wo) ΔΦ_p / (4/3 π r³) over the `k`
    /// nearest photons within `r_max` [mm], r being the distance of the farthest one found
    /// (or `r_max` when fewer than `k` lie within it), times (k − 1)/k when k were found (see
    /// `knn_radius`: the k-th photon lies on the sphere). `wo` is the unit direction the
    /// scattered light leaves in (towards the viewer: minus the camera ray's direction).
    /// The value is σs·L_i, in-scattered radiance per mm [W/(sr·mm³) · mm² = radiance/mm]:
    /// multiply by the march step Δx [mm] and the transmittance to the eye.
    pub fn volume_radiance(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let (r, unbias) = knn_radius(nb, k, r_max);
        let sum: f64 = nb
            .items()
            .iter()
            .map(|&(_, i)| {
                let p = &self.photons[i as usize];
                phase.eval(p.direction().dot(wo)) * p.power as f64
            })
            .sum();
        Estimate {
            value: unbias * sum / (4.0 / 3.0 * PI * r * r * r),
            radius: r,
            count: nb.len(),
        }
    }

    /// [`Self::volume_radiance`] with a kernel shaped for a boundary: the k-NN sphere's
    /// radius r sets the size of the layer kernel of [`Self::volume_radiance_layer_radius`].
    /// The k-th photon (on the sphere) is left out, which keeps the estimate unbiased for a
    /// uniform density (given r, the other k − 1 are uniform inside the sphere).
    #[allow(clippy::too_many_arguments)]
    pub fn volume_radiance_layer(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        k: usize,
        r_max: f64,
        layer: f64,
        planes: Planes,
        nb: &mut Neighbours,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let r = knn_radius(nb, k, r_max).0;
        let kth = if nb.len() >= k && k >= 2 {
            nb.items()
                .iter()
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .map(|&(_, i)| i as usize)
        } else {
            None
        };
        self.layer_estimate(x, wo, phase, r, layer, planes, kth)
    }

    /// Eq. 11's multiple-scattering term with a kernel shaped for a boundary, of the volume of
    /// the sphere of radius `r` [mm]: a flat cylinder whose axis is the normal n of the nearer
    /// boundary plane, half-height t = `layer` · r and radius R = r √(2/(3·layer)), cut by
    /// that plane (and by the opposite plane of a thin layer), z ∈ [a, b] with
    /// b = min(t, depth of `x`), z measured along n from `x`. Below a boundary the photon
    /// density changes with depth within a mean free path, along the boundary slowly; a sphere
    /// cut by the boundary misses photons (up to half) and sees the density's gradient. Here
    /// the density is fitted as ρ₀ + γ z from the moments Σ w, Σ w z of the phase-weighted
    /// photons against the cut cylinder's A (b − a), A (b² − a²)/2, A (b³ − a³)/3 and ρ₀
    /// reported: exact for a density linear in depth, and the plain mean where nothing cuts
    /// the kernel. Measured against the slab simulator and `volpath`: docs/vpm-convergence.md.
    #[allow(clippy::too_many_arguments)]
    pub fn volume_radiance_layer_radius(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        r: f64,
        layer: f64,
        planes: Planes,
    ) -> Estimate {
        self.layer_estimate(x, wo, phase, r, layer, planes, None)
    }

    #[allow(clippy::too_many_arguments)]
    fn layer_estimate(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        r: f64,
        layer: f64,
        planes: Planes,
        skip: Option<usize>,
    ) -> Estimate {
        let (p0, n) = planes.near;
        let t = layer * r;
        let big_r2 = r * r * 2.0 / (3.0 * layer);
        let b = t.min((p0 - x).dot(n).max(0.0));
        // the far plane of a thin layer (anti-parallel normal) bounds z from below
        let a = planes
            .far
            .filter(|(_, nf)| nf.dot(n) < -0.99)
            .map_or(-t, |(pf, nf)| (-t).max(-(pf - x).dot(nf).max(0.0)));
        let mut e = Estimate {
            radius: r,
            ..Estimate::default()
        };
        if b - a <= 1e-9 * r {
            return e;
        }
        let (mut s0, mut s1) = (0.0, 0.0);
        let skip = skip.map(|i| &self.photons[i] as *const Photon);
        self.for_each_within(x, (big_r2 + t * t).sqrt(), |p, _| {
            let d = p.position() - x;
            let z = d.dot(n);
            if z < a || z > b || d.dot(d) - z * z > big_r2 || skip == Some(p as *const Photon) {
                return;
            }
            let w = phase.eval(p.direction().dot(wo)) * p.power as f64;
            s0 += w;
            s1 += w * z;
            e.count += 1;
        });
        let [v, m1, m2] = planes
            .clip
            .and_then(|c| c.moments(x, n, a, b, big_r2.sqrt()))
            .unwrap_or_else(|| prism_moments(PI * big_r2, a, b));
        let det = v * m2 - m1 * m1;
        // radiance is not negative: a fit that extrapolates below 0 (few photons, steep
        // gradient) is clamped. That biases upwards only where it happens; with k ≥ 64 it is
        // rare (the slab test agrees with the slab simulator to 0.1 % either way).
        e.value = if det > 1e-12 * v * m2 {
            ((s0 * m2 - s1 * m1) / det).max(0.0)
        } else {
            s0 / v
        };
        e
    }

    /// Same as [`Self::volume_radiance`] with a fixed radius `r` [mm] (progressive photon
    /// mapping): Σ_{|x_p − x| ≤ r} p(d_p · wo) ΔΦ_p / (4/3 π r³).
    pub fn volume_radiance_radius(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        r: f64,
    ) -> Estimate {
        let mut sum = 0.0;
        let mut count = 0;
        self.for_each_within(x, r, |p, _| {
            sum += phase.eval(p.direction().dot(wo)) * p.power as f64;
            count += 1;
        });
        Estimate {
            value: sum / (4.0 / 3.0 * PI * r * r * r),
            radius: r,
            count,
        }
    }

    /// Irradiance with a fixed radius `r` [mm] (progressive photon mapping):
    /// Σ_{|x_p − x| ≤ r, d_p · n < 0} ΔΦ_p / (π r²).
    pub fn surface_irradiance_radius(&self, x: Vec3, n: Vec3, r: f64) -> Estimate {
        let mut sum = 0.0;
        let mut count = 0;
        self.for_each_within(x, r, |p, _| {
            if p.direction().dot(n) < 0.0 {
                sum += p.power as f64;
                count += 1;
            }
        });
        Estimate {
            value: sum / (PI * r * r),
            radius: r,
            count,
        }
    }

    /// [`Self::surface_irradiance`] with its disc cut by the faces that stand on the surface
    /// within the gathering radius r (a disc lying on the ribbon): photons stored beyond
    /// such a face (under the disc, where light that crossed the disc lands) would brighten
    /// the surface just outside it. Eight rays along the surface from `x` to distance r
    /// find the faces (`clip`: rays start at `x`, which the caller's `hit` offsets off the
    /// surface); photons beyond their tangent planes are dropped, the k-th photon (on the
    /// sphere) is left out, and the sum is divided by the area of the part of the disc on
    /// this side (512-point quadrature, rotated by `clip.u`). Without faces within r it is
    /// the plain estimate.
    pub fn surface_irradiance_clipped(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
        clip: &KernelClip,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let (r, unbias) = knn_radius(nb, k, r_max);
        let frame = Frame::from_axis(n);
        let rays = rotated_circle::<CLIP_RAYS>(clip.u);
        let (planes, count) = clip.faces(x, &frame, r, |j| {
            Vec3::new(r * rays[j][0], r * rays[j][1], 0.0)
        });
        let planes = &planes[..count];
        let (area, unbias) = if count == 0 {
            (PI * r * r, unbias)
        } else {
            (PI * r * r * disc_fraction_inside(planes, r, clip.u), 1.0)
        };
        let kth = (count > 0 && nb.len() >= k && k >= 2)
            .then(|| {
                nb.items()
                    .iter()
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|e| e.1)
            })
            .flatten();
        let mut sum = 0.0;
        let mut n_in = 0;
        for &(_, i) in nb.items() {
            let p = &self.photons[i as usize];
            if p.direction().dot(n) < 0.0
                && Some(i) != kth
                && (count == 0 || inside_planes(planes, frame.to_local(p.position() - x)))
            {
                sum += p.power as f64;
                n_in += 1;
            }
        }
        Estimate {
            value: if area > 0.0 { unbias * sum / area } else { 0.0 },
            radius: r,
            count: n_in,
        }
    }

    /// Irradiance at a surface point `x` with unit normal `n` (facing the side that is lit):
    /// Σ ΔΦ_p / (π r²) over the `k` nearest photons within `r_max` [mm] that arrived from the
    /// front (d_p · n < 0). Multiply by the BRDF (ρ/π) for reflected radiance.
    pub fn surface_irradiance(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        r_max: f64,
        nb: &mut Neighbours,
    ) -> Estimate {
        self.knn(x, k, r_max, nb);
        if nb.is_empty() {
            return Estimate::default();
        }
        let (r, unbias) = knn_radius(nb, k, r_max);
        let mut sum = 0.0;
        let mut count = 0;
        for &(_, i) in nb.items() {
            let p = &self.photons[i as usize];
            if p.direction().dot(n) < 0.0 {
                sum += p.power as f64;
                count += 1;
            }
        }
        Estimate {
            value: unbias * sum / (PI * r * r),
            radius: r,
            count,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rotated circle of the clip quadratures equals direct sin_cos at every point.
    #[test]
    fn rotated_circle_matches_sin_cos() {
        for u in [0.0, 0.37, 0.999] {
            for (j, [c, s]) in rotated_circle::<32>(u).into_iter().enumerate() {
                let (s1, c1) = (2.0 * PI * (j as f64 + u) / 32.0).sin_cos();
                assert!((c - c1).abs() < 1e-12 && (s - s1).abs() < 1e-12, "{u} {j}");
            }
        }
    }
    use crate::rng::Stream;
    use crate::sampling::uniform_sphere;

    /// Mean and its standard error.
    fn mean_se(vals: &[f64]) -> (f64, f64) {
        let m = vals.iter().sum::<f64>() / vals.len() as f64;
        let var = vals.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (vals.len() - 1) as f64;
        (m, (var / vals.len() as f64).sqrt())
    }

    /// The wall x = 0 as a scene's `hit` would report it (for the clip tests).
    fn wall_at_x0(o: Vec3, d: Vec3, t_max: f64) -> Option<(Vec3, Vec3)> {
        let t = -o.x / d.x;
        (t > 0.0 && t < t_max).then(|| (o + d * t, Vec3::X))
    }

    fn random_map(n: usize, seed: u64, clustered: bool) -> Vec<Photon> {
        let mut s = Stream::new(seed, 0, 0);
        (0..n)
            .map(|i| {
                let mut p = Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 10.0;
                if clustered && i % 3 == 0 {
                    p = Vec3::new(5.0, 5.0, 5.0) + (p - Vec3::splat(5.0)) * 0.01;
                }
                if clustered && i % 7 == 0 {
                    p = Vec3::new(1.0, 2.0, 3.0); // exact duplicates
                }
                Photon::new(p, uniform_sphere(s.uniform2()), 1.0)
            })
            .collect()
    }

    #[test]
    fn photon_is_compact_and_direction_roundtrips() {
        const { assert!(PHOTON_BYTES <= 20) };
        let mut s = Stream::new(9, 0, 0);
        let mut worst: f64 = 0.0;
        for i in 0..20_000 {
            let d = match i {
                0 => Vec3::Z,
                1 => -Vec3::Z,
                2 => Vec3::X,
                3 => -Vec3::Y,
                _ => uniform_sphere(s.uniform2()),
            };
            let mut p = Photon::new(Vec3::new(1.0, -2.0, 3.0), d, 0.5);
            p.set_axis(2);
            worst = worst.max(p.direction().angle_between(d));
            assert_eq!(p.axis(), 2);
        }
        assert!(worst < 2e-4, "worst direction error {worst} rad");
    }

    #[test]
    fn knn_and_radius_equal_brute_force() {
        for clustered in [false, true] {
            let raw = random_map(5_000, 1 + clustered as u64, clustered);
            let map = PhotonMap::build(raw.clone());
            assert_eq!(map.len(), raw.len());
            let mut s = Stream::new(77, 0, 0);
            let mut nb = Neighbours::new();
            for qi in 0..300 {
                let x = if qi % 5 == 0 {
                    Vec3::new(5.0, 5.0, 5.0)
                } else {
                    Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 12.0 - Vec3::ONE
                };
                let q = [x.x as f32, x.y as f32, x.z as f32];
                let (k, r_max) = (1 + qi % 50, 0.5 + (qi % 4) as f64);
                // brute force: sorted distances within r_max
                let mut all: Vec<f32> = map
                    .photons()
                    .iter()
                    .map(|p| dist2(&p.pos, &q))
                    .filter(|&d2| d2 <= (r_max * r_max) as f32)
                    .collect();
                all.sort_by(|a, b| a.total_cmp(b));
                map.knn(x, k, r_max, &mut nb);
                let mut got: Vec<f32> = nb.items().iter().map(|h| h.0).collect();
                got.sort_by(|a, b| a.total_cmp(b));
                all.truncate(k);
                assert_eq!(got, all, "knn mismatch at query {qi}");
                let mut count = 0;
                map.for_each_within(x, r_max, |_, _| count += 1);
                let brute = map
                    .photons()
                    .iter()
                    .filter(|p| dist2(&p.pos, &q) <= (r_max * r_max) as f32)
                    .count();
                assert_eq!(count, brute, "radius mismatch at query {qi}");
            }
        }
    }

    #[test]
    fn density_estimates_recover_uniform_density() {
        // N photons of power Φ/N uniform in a 10 mm cube: density Φ/1000 per mm³
        let n = 200_000;
        let total = 3.0;
        let mut raw = random_map(n, 5, false);
        for p in &mut raw {
            p.power = (total / n as f64) as f32;
        }
        let map = PhotonMap::build(raw);
        let rho = total / 1000.0;
        let iso = PhaseFunction::Isotropic;
        // fixed radius: photon count in a ball is Poisson; query balls on a grid do not overlap
        let r = 1.0;
        let mut sum = 0.0;
        let mut count = 0usize;
        let mut m = 0;
        for i in 0..3 {
            for j in 0..3 {
                for l in 0..3 {
                    let x = Vec3::new(
                        2.5 + 2.5 * i as f64,
                        2.5 + 2.5 * j as f64,
                        2.5 + 2.5 * l as f64,
                    );
                    let e = map.volume_radiance_radius(x, Vec3::Z, &iso, r);
                    sum += e.value;
                    count += e.count;
                    m += 1;
                }
            }
        }
        let mean = sum / m as f64;
        let expect = rho / (4.0 * PI);
        let rel_se = 1.0 / (count as f64).sqrt();
        assert!(
            ((mean - expect) / expect).abs() < 4.0 * rel_se,
            "radius estimate {mean} vs {expect}"
        );
        // k-nearest: the estimate uses (k−1)/V_k, unbiased for a Poisson process, with
        // relative standard deviation ≈ 1/sqrt(k − 2); estimates at the 27 grid points are
        // independent (balls of radius ≈ 0.5 mm do not overlap)
        let k = 100;
        let mut nb = Neighbours::new();
        let mut sum = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                for l in 0..3 {
                    let x = Vec3::new(
                        2.5 + 2.5 * i as f64,
                        2.5 + 2.5 * j as f64,
                        2.5 + 2.5 * l as f64,
                    );
                    let e = map.volume_radiance(x, Vec3::Z, &iso, k, 5.0, &mut nb);
                    assert_eq!(e.count, k);
                    sum += e.value;
                }
            }
        }
        let mean = sum / 27.0;
        let rel_se = 1.0 / ((k - 2) as f64).sqrt() / 27f64.sqrt();
        assert!(
            ((mean - expect) / expect).abs() < 4.0 * rel_se,
            "knn estimate {mean} vs {expect}"
        );
    }

    #[test]
    fn layer_estimate_follows_a_density_that_rises_with_depth() {
        // photons in z < 0 with density ∝ 1 + 0.3 |z| (z ∈ [−10, 0], 10 mm square): at and
        // near the plane z = 0 the sphere sees about half the density; the layer kernel
        // (k-NN and fixed radius), fitted where the plane cuts it, is right at every depth.
        // 4 independent maps × 16 queries far enough apart not to share photons.
        let n = 400_000;
        let a = 0.3;
        let norm = 10.0 + 50.0 * a;
        let maps: Vec<PhotonMap> = (0..4)
            .map(|seed| {
                let mut s = Stream::new(29, 0, seed);
                // inverse CDF of 1 + a t on [0, 10]: F(t) = (t + a t²/2) / (10 + 50 a)
                PhotonMap::build(
                    (0..n)
                        .map(|_| {
                            let c = s.uniform() * norm;
                            let t = ((1.0 + 2.0 * a * c).sqrt() - 1.0) / a;
                            let p = Vec3::new(s.uniform() * 10.0, s.uniform() * 10.0, -t);
                            Photon::new(p, uniform_sphere(s.uniform2()), 1.0 / n as f64)
                        })
                        .collect(),
                )
            })
            .collect();
        let iso = PhaseFunction::Isotropic;
        let mut nb = Neighbours::new();
        let planes = Planes {
            near: (Vec3::ZERO, Vec3::Z),
            far: None,
            clip: None,
        };
        for layer in [0.2, 0.5] {
            for depth in [0.0, 0.02, 0.1, 0.5] {
                // photons per mm³ at depth d: n (1 + a d) / (100 norm), each of power 1/n
                let expect = (1.0 + a * depth) / (100.0 * norm) / (4.0 * PI);
                let (mut knn, mut fixed, mut sphere) = (Vec::new(), Vec::new(), Vec::new());
                for map in &maps {
                    for q in 0..16 {
                        let x = Vec3::new(
                            1.7 + 2.2 * (q % 4) as f64,
                            1.7 + 2.2 * (q / 4) as f64,
                            -depth,
                        );
                        let e = map.volume_radiance_layer(
                            x,
                            Vec3::Z,
                            &iso,
                            100,
                            5.0,
                            layer,
                            planes,
                            &mut nb,
                        );
                        knn.push(e.value);
                        fixed.push(
                            map.volume_radiance_layer_radius(x, Vec3::Z, &iso, 0.5, layer, planes)
                                .value,
                        );
                        sphere.push(
                            map.volume_radiance(x, Vec3::Z, &iso, 100, 5.0, &mut nb)
                                .value,
                        );
                    }
                }
                for (name, vals) in [("k-NN", &knn), ("fixed radius", &fixed)] {
                    let (m, se) = mean_se(vals);
                    assert!(
                        (m - expect).abs() < 4.0 * se,
                        "{name}, layer {layer}, depth {depth}: {m} ± {se} vs {expect}"
                    );
                }
                if depth == 0.0 {
                    let m = mean_se(&sphere).0;
                    assert!(m < 0.7 * expect, "sphere at the plane: {m} vs {expect}");
                }
            }
        }
    }

    /// The clip tests' verdict: the clipped estimates' mean is `expect` within 4 standard
    /// errors, the plain estimates' mean lies beyond 4 of theirs on the side `sign` (−1: too
    /// dark, +1: too bright).
    fn assert_clip_corrects(plain: &[f64], clipped: &[f64], expect: f64, sign: f64) {
        let (m, se) = mean_se(clipped);
        assert!(
            (m - expect).abs() < 4.0 * se,
            "clipped: {m} ± {se} vs {expect}"
        );
        let (m0, se0) = mean_se(plain);
        assert!(
            sign * (m0 - expect) > 4.0 * se0,
            "plain: {m0} ± {se0} vs {expect}"
        );
    }

    /// Four maps, map i built from `photons(Stream::new(seed, 0, i))`.
    fn four_maps(seed: u64, photons: impl Fn(&mut Stream) -> Vec<Photon>) -> Vec<PhotonMap> {
        (0..4)
            .map(|i| PhotonMap::build(photons(&mut Stream::new(seed, 0, i))))
            .collect()
    }

    /// The clip tests' points: 16 per map, 0.05 mm outside the wall x = 0 ([`wall_at_x0`]),
    /// y from −4 to 3.5 mm, height `z`; `estimate(map, x, clip)` returns the plain and the
    /// clipped estimate there, the clip rotated by a uniform from `Stream::new(seed, 0, 0)`.
    fn along_the_wall(
        maps: &[PhotonMap],
        z: f64,
        seed: u64,
        mut estimate: impl FnMut(&PhotonMap, Vec3, &KernelClip) -> (f64, f64),
    ) -> (Vec<f64>, Vec<f64>) {
        let mut rng = Stream::new(seed, 0, 0);
        let (mut plain, mut clipped) = (Vec::new(), Vec::new());
        for map in maps {
            for q in 0..16 {
                let x = Vec3::new(0.05, -4.0 + 0.5 * q as f64, z);
                let clip = KernelClip {
                    hit: &wall_at_x0,
                    u: rng.uniform(),
                };
                let (a, b) = estimate(map, x, &clip);
                plain.push(a);
                clipped.push(b);
            }
        }
        (plain, clipped)
    }

    #[test]
    fn clipped_layer_kernel_is_right_at_a_rim() {
        // uniform photons in the quarter-space x > 0, z < 0 (a disc's rim: top face z = 0,
        // side wall x = 0), 10 × 10 × 10 mm. At points 0.05 mm from both faces the layer
        // kernel, cut by the top plane only, counts over a volume of which about half lies
        // beyond the wall: too dark by far more than its noise. Clipped by the wall's plane
        // (found by the clip's rays) it is right within 4 standard errors (4 maps × 16
        // points).
        let n = 400_000;
        let maps = four_maps(31, |s| {
            (0..n)
                .map(|_| {
                    let p = Vec3::new(s.uniform(), s.uniform() - 0.5, -s.uniform()) * 10.0;
                    Photon::new(p, uniform_sphere(s.uniform2()), 1.0 / n as f64)
                })
                .collect()
        });
        let expect = 1.0 / 1000.0 / (4.0 * PI);
        let iso = PhaseFunction::Isotropic;
        let mut nb = Neighbours::new();
        let (plain, clipped) = along_the_wall(&maps, -0.05, 5, |map, x, clip| {
            let mut planes = Planes {
                near: (Vec3::new(x.x, x.y, 0.0), Vec3::Z),
                far: None,
                clip: None,
            };
            let e = map.volume_radiance_layer(x, Vec3::Z, &iso, 100, 5.0, 0.3, planes, &mut nb);
            planes.clip = Some(*clip);
            let c = map.volume_radiance_layer(x, Vec3::Z, &iso, 100, 5.0, 0.3, planes, &mut nb);
            (e.value, c.value)
        });
        // too dark unclipped
        assert_clip_corrects(&plain, &clipped, expect, -1.0);
    }

    #[test]
    fn clipped_surface_estimate_ignores_light_beyond_a_standing_face() {
        // photons on the plane z = 0 arriving from above, 10× denser for x < 0 (under a disc
        // that stands on the plane; its wall is x = 0). 0.05 mm outside the wall the plain
        // k-NN disc takes in the dense side and reads high; clipped by the wall it is right
        // within 4 standard errors (4 maps × 16 points).
        let n_out = 200_000;
        let maps = four_maps(37, |s| {
            let mut v = Vec::new();
            for (x0, count) in [(0.0, n_out), (-10.0, 10 * n_out)] {
                for _ in 0..count {
                    let p = Vec3::new(x0 + 10.0 * s.uniform(), 10.0 * s.uniform() - 5.0, 0.0);
                    v.push(Photon::new(p, -Vec3::Z, 1.0 / n_out as f64));
                }
            }
            v
        });
        let expect = 1.0 / 100.0; // irradiance outside: power per mm²
        let mut nb = Neighbours::new();
        let (plain, clipped) = along_the_wall(&maps, 0.0, 6, |map, x, clip| {
            let e = map.surface_irradiance(x, Vec3::Z, 100, 5.0, &mut nb).value;
            let c = map.surface_irradiance_clipped(x, Vec3::Z, 100, 5.0, &mut nb, clip);
            (e, c.value)
        });
        // too bright unclipped
        assert_clip_corrects(&plain, &clipped, expect, 1.0);
    }

    #[test]
    fn surface_irradiance_of_uniform_flux() {
        // photons hitting the plane z = 0 from above, flux density E per mm²
        let n = 100_000;
        let e_true = 2.0;
        let side = 10.0;
        let mut s = Stream::new(11, 0, 0);
        let power = e_true * side * side / n as f64;
        let raw: Vec<Photon> = (0..n)
            .map(|_| {
                let p = Vec3::new(s.uniform() * side, s.uniform() * side, 0.0);
                Photon::new(p, -Vec3::Z, power)
            })
            .collect();
        let map = PhotonMap::build(raw);
        let mut nb = Neighbours::new();
        let e = map.surface_irradiance(Vec3::new(5.0, 5.0, 0.0), Vec3::Z, 400, 3.0, &mut nb);
        // relative sd ≈ 1/sqrt(k)
        let v = e.value;
        assert!(((v - e_true) / e_true).abs() < 4.0 / 398f64.sqrt(), "{v}");
        // back-facing photons are ignored
        let e_back = map.surface_irradiance(Vec3::new(5.0, 5.0, 0.0), -Vec3::Z, 400, 3.0, &mut nb);
        assert_eq!(e_back.count, 0);
    }

    /// Throughput figures for the report (slow: run with `--ignored --nocapture`).
    #[test]
    #[ignore]
    fn query_throughput() {
        let n = 4_000_000;
        let raw = random_map(n, 31, false);
        let t = std::time::Instant::now();
        let map = PhotonMap::build(raw);
        let build = t.elapsed().as_secs_f64();
        println!("{n} photons: build {build:.2} s");
        // r_max: twice the radius holding k photons at this density (the camera pass's default)
        for k in [64usize, 200] {
            let r_max = 2.0 * (3.0 * k as f64 * 1000.0 / (4.0 * PI * n as f64)).cbrt();
            let mut s = Stream::new(32, 0, 0);
            let mut nb = Neighbours::new();
            let q = 200_000;
            let t = std::time::Instant::now();
            let mut found = 0;
            for _ in 0..q {
                let x = Vec3::new(s.uniform(), s.uniform(), s.uniform()) * 10.0;
                map.knn(x, k, r_max, &mut nb);
                found += nb.len();
            }
            let knn = t.elapsed().as_secs_f64();
            println!(
                "k = {k} (r_max {r_max:.3} mm) queries {:.2} µs each ({found} found)",
                knn / q as f64 * 1e6
            );
        }
    }
}
