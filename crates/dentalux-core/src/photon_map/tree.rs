//! The photon record and the photon map: a balanced kd-tree over the records, with
//! k-nearest and fixed-radius queries.

use crate::control::Control;
use crate::error::{Error, Result};
use crate::math::Vec3;

/// Size of one stored photon [bytes].
pub const PHOTON_BYTES: usize = std::mem::size_of::<Photon>();

/// Subtrees at most this long are scanned linearly instead of descended (32 against 16: an
/// aimed Fig. 3 pass at 128x96, 0.98x the CPU time; 8: 1.05x).
pub(super) const LEAF: usize = 32;
// a leaf's photons fit one u32 bit mask (`set_bits`)
const _: () = assert!(LEAF <= 32);
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
    // + 0.5 and truncation rounds these non-negative values: `f32::round` is a libm call on
    // baseline x86-64 (1 % of a Fig. 3 pass, one per stored photon)
    let q = |v: f64| (((v * 0.5 + 0.5) as f32 * OCT_MAX + 0.5) as u32).min(OCT_MAX as u32);
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

/// The positions of the set bits of `mask`, lowest first (a leaf's photons in order).
#[inline]
fn set_bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

/// `out[j]` = the direction of `bits[j]` ([`Photon::direction_bits`]) dotted with `w`, the
/// same numbers as [`Photon::direction`]`.dot(w)`: on plain arrays, so the decoding and
/// normalising vectorise.
pub(super) fn direction_cosines(bits: &[u32], w: Vec3, out: &mut [f64]) {
    for (o, &b) in out.iter_mut().zip(bits) {
        *o = decode_dir(b).dot(w);
    }
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
        decode_dir(self.direction_bits())
    }
    /// The octahedral direction bits, for [`direction_cosines`].
    #[inline]
    pub(super) fn direction_bits(&self) -> u32 {
        self.packed & 0x3FFF_FFFF
    }
    #[inline]
    pub(super) fn axis(&self) -> usize {
        (self.packed >> 30) as usize
    }
    #[inline]
    pub(super) fn set_axis(&mut self, axis: usize) {
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

/// Photons arranged as an implicit balanced kd-tree.
#[derive(Debug, Clone, Default)]
pub struct PhotonMap {
    photons: Vec<Photon>,
}

/// Arrange `p` as a kd-tree; subtrees of at least [`PAR_BUILD`] photons first ask `stop`,
/// and a stopped build leaves its subtree unordered (the caller discards it). Each node
/// splits at the median along the longest side of its cell (`lo`, `hi`: the photons' box at
/// the root, then the parent's cell cut at the split), as Jensen's balanced photon map
/// does: scanning every node's photons for their own box was about 40 % of a build (perf,
/// Fig. 3's 4 M photons).
fn build_rec(p: &mut [Photon], lo: [f32; 3], hi: [f32; 3], stop: &(dyn Fn() -> bool + Sync)) {
    let n = p.len();
    if n <= LEAF || (n >= PAR_BUILD && stop()) {
        return;
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
    // partial_cmp, not total_cmp: positions are finite (`build_until`), and the plain
    // compare keeps the selection's inner loop short
    p.select_nth_unstable_by(mid, |a, b| {
        a.pos[axis]
            .partial_cmp(&b.pos[axis])
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    p[mid].set_axis(axis);
    let split = p[mid].pos[axis];
    let (mut hi_l, mut lo_r) = (hi, lo);
    hi_l[axis] = split;
    lo_r[axis] = split;
    let (l, r) = p.split_at_mut(mid);
    let r = &mut r[1..];
    if n >= PAR_BUILD {
        rayon::join(
            || build_rec(l, lo, hi_l, stop),
            || build_rec(r, lo_r, hi, stop),
        );
    } else {
        build_rec(l, lo, hi_l, stop);
        build_rec(r, lo_r, hi, stop);
    }
}

/// Bounding box of the photons' positions (inverted, +∞ to −∞, when empty).
fn bounds_of(photons: &[Photon]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in photons {
        for a in 0..3 {
            lo[a] = lo[a].min(p.pos[a]);
            hi[a] = hi[a].max(p.pos[a]);
        }
    }
    (lo, hi)
}

#[inline]
pub(super) fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    dx * dx + dy * dy + dz * dz
}

impl PhotonMap {
    /// Build the tree from photons (parallel for large maps; O(n log n)).
    pub fn build(photons: Vec<Photon>) -> Self {
        Self::build_until(photons, &|| false).expect("a build nobody stops")
    }

    /// [`PhotonMap::build`], stopping with [`Error::Cancelled`] once `control` is cancelled
    /// (a 100 M-photon map takes seconds to build; Ctrl-C must not wait for it).
    pub fn try_build(photons: Vec<Photon>, control: &Control) -> Result<Self> {
        Self::build_until(photons, &|| control.is_cancelled())
    }

    fn build_until(mut photons: Vec<Photon>, stop: &(dyn Fn() -> bool + Sync)) -> Result<Self> {
        // drop photons whose position is not finite: they would poison the ordering
        photons.retain(|p| p.pos.iter().all(|c| c.is_finite()) && p.power.is_finite());
        photons.shrink_to_fit();
        let (lo, hi) = bounds_of(&photons);
        build_rec(&mut photons, lo, hi, stop);
        if stop() {
            return Err(Error::Cancelled);
        }
        Ok(Self { photons })
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
    /// Bounding box of the photons' positions (inverted, +∞ to −∞, when empty).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        bounds_of(&self.photons)
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
            // the leaf's candidates under the bound as a bit mask without branches, then
            // pushed in order; a push can tighten the bound, so each is checked again
            let leaf = &ph[lo..hi];
            let mut d2s = [0.0f32; LEAF];
            let mut mask = 0u32;
            for (j, p) in leaf.iter().enumerate() {
                d2s[j] = dist2(&p.pos, &q);
                mask |= ((d2s[j] <= out.bound) as u32) << j;
            }
            for j in set_bits(mask) {
                if d2s[j] <= out.bound {
                    out.push(d2s[j], (lo + j) as u32);
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

    /// Call `f(photon, its index in [`Self::photons`])` for every photon within `r` [mm] of
    /// `x`.
    pub fn for_each_within<F: FnMut(&Photon, usize)>(&self, x: Vec3, r: f64, f: F) {
        self.for_each_within_box(x, r, [f64::INFINITY; 3], f);
    }

    /// [`Self::for_each_within`] restricted to the box |p − x|ᵢ ≤ `half[i]` [mm]: subtrees
    /// and photons outside it are skipped (a flat kernel inside a larger sphere reads only
    /// the photons near it). The photons both inside the sphere and the box are visited in
    /// the same order as by [`Self::for_each_within`], so sums over them are bit-identical.
    pub fn for_each_within_box<F: FnMut(&Photon, usize)>(
        &self,
        x: Vec3,
        r: f64,
        half: [f64; 3],
        mut f: F,
    ) {
        let q = [x.x as f32, x.y as f32, x.z as f32];
        let r2 = (r * r) as f32;
        // f32 rounding of x and of the photons' positions: widen the box by a hair
        let h = half.map(|h| (h * (1.0 + 1e-5) + 1e-4) as f32);
        // without branches, so a leaf's tests make a bit mask
        let inside = |p: &Photon| {
            (dist2(&p.pos, &q) <= r2)
                & ((p.pos[0] - q[0]).abs() <= h[0])
                & ((p.pos[1] - q[1]).abs() <= h[1])
                & ((p.pos[2] - q[2]).abs() <= h[2])
        };
        // explicit stack of [lo, hi) ranges; depth is log2(n) + 1 < 64
        let mut stack = [(0usize, 0usize); 64];
        let mut sp = 0;
        if !self.photons.is_empty() {
            stack[0] = (0, self.photons.len());
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            let (lo, hi) = stack[sp];
            if hi - lo <= LEAF {
                // which of the leaf's photons are in, as a bit mask without branches (a
                // branch per photon mispredicted about as often as it was taken), then
                // visited in order
                let leaf = &self.photons[lo..hi];
                let mut mask = 0u32;
                for (i, p) in leaf.iter().enumerate() {
                    mask |= (inside(p) as u32) << i;
                }
                for i in set_bits(mask) {
                    f(&leaf[i], lo + i);
                }
                continue;
            }
            let mid = (lo + hi) / 2;
            let p = &self.photons[mid];
            if inside(p) {
                f(p, mid);
            }
            let axis = p.axis();
            let delta = q[axis] - p.pos[axis];
            let reach = delta.abs() <= h[axis] && delta * delta <= r2;
            if (delta <= 0.0 || reach) && lo < mid {
                stack[sp] = (lo, mid);
                sp += 1;
            }
            if (delta >= 0.0 || reach) && mid + 1 < hi {
                stack[sp] = (mid + 1, hi);
                sp += 1;
            }
        }
    }
}
