//! The beam radiance estimate (Jarosz, Zwicker & Jensen, EG 2008): every volume photon is a
//! disc of radius r_p, and one query along a ray segment gathers every photon whose disc the
//! segment passes through. With the disc facing the ray (their form),
//!
//!   L_m = Σ_p K_{r_p}(d_p) · e^(−σt t_p) · p(d_p · wo) · ΔΦ_p,
//!
//! d_p the photon's distance from the ray, t_p its projection on the ray, K the 2-D biweight
//! kernel 3/(π r²) (1 − d²/r²)² (it integrates to 1 over the disc). It is eq. 11's
//! multiple-scattering integral ∫ e^(−σt s) Σ p ΔΦ K₃(x(s) − x_p) ds with the 3-D kernel
//! integrated along the ray in closed form: no marching, no per-step k-NN. Near faces the
//! discs turn to lie along the face (below).
//!
//! One radius per medium, fixed (per-photon radii from the k-th neighbour distance,
//! Jarosz 2008's choice, measured noisier on the Fig. 3 discs at the same cost:
//! docs/notes/2026-12-06-bre.md). The query walks the photon map's own implicit kd-tree, each cell's box grown
//! by the radius, so the estimate needs no memory beyond the map. Hand-written because the
//! photons already sit in that tree: a BVH library (`bvh`, `parry`) would keep its own
//! nodes and boxes, ≥ 32 bytes per photon more, against the 100 M photons in 3 GB target.
//!
//! Boundaries. The 2-D kernel stands for a 3-D one that is a disc across and a delta along
//! one direction; which direction is free. Facing the ray, a disc near a face mixes depths
//! below it: in a dense medium the camera sees 1/σt deep (0.05 mm in the Fig. 3 disc), far
//! less than a useful radius, and a disc facing an oblique ray reaches from the surface to
//! many times that depth, weighted by e^(−σt t) at its projection (measured +10 … +20 % on the
//! Fig. 3 discs at r = 0.4 mm). So each photon's disc lies in the plane of the nearer of the
//! faces where the ray entered and leaves the medium: the photon at height z over that face
//! (normal n) meets the ray where the ray is at that height, s_p = (x_p − o)·n / (d·n), its
//! offset there lies in the face's plane, and the integral over s becomes one over z with
//! ds = dz / |d·n|:
//!
//!   L_m = Σ_p K_{r_p}(|x_p − x(s_p)|) · e^(−σt s_p) / |d·n| · p(d_p · wo) · ΔΦ_p,
//!
//! with no blur in depth and, by a flat face, no kernel outside the medium. The photons are
//! those of one medium on the inner side of both faces. Faces standing beside the ray (a
//! disc's rim) are not clipped: docs/notes/2026-12-06-bre.md measures the bias there.

use super::kernel::{inside_planes, rotated_circle, KernelClip, CLIP_RAYS};
use super::tree::{Photon, PhotonMap, LEAF};
use crate::math::{Frame, Vec3};
use crate::phase::PhaseFunction;
use std::f64::consts::PI;

/// The disc radius and bounding box over a photon map, for beam queries.
#[derive(Debug, Clone, Default)]
pub struct BeamMap {
    /// Disc radius [mm].
    radius: f64,
    /// Bounding box of the photons.
    lo: [f32; 3],
    hi: [f32; 3],
}

/// One side of a ray segment's medium: a point of the face and its outward normal.
pub type Face = (Vec3, Vec3);

/// A ray segment inside one medium, for [`BeamMap::estimate`].
#[derive(Clone, Copy)]
pub struct Segment<'a> {
    /// Start (the camera-path vertex or the entry point) [mm].
    pub o: Vec3,
    /// Unit direction.
    pub d: Vec3,
    /// Length to the exit (∞ when the ray never leaves) [mm].
    pub t_end: f64,
    /// The faces where the ray entered and leaves, when there are such.
    pub entry: Option<Face>,
    /// The exit face.
    pub exit: Option<Face>,
    /// Extinction coefficient σt of the medium [1/mm].
    pub sigma_t: f64,
    /// The medium's phase function.
    pub phase: &'a PhaseFunction,
    /// Rays that find faces beside the segment (a disc's rim), to renormalise the discs
    /// they cut; `None` leaves the discs whole.
    pub clip: Option<KernelClip<'a>>,
}

/// What a beam query found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BeamEstimate {
    /// The radiance the segment's in-scattered light sends to the ray's origin.
    pub value: f64,
    /// Photons that contributed.
    pub count: usize,
}

/// Transmittance below which a photon's contribution is not sought: the walk stops where
/// e^(−σt t) < this, a relative bias of at most this much (0.1 %, a tenth of the smallest
/// error the benchmarks measure; the tail beyond it is 40 % of the photons the walk met at
/// 1e-5).
const MIN_TRANSMITTANCE: f64 = 1e-3;
/// How far beyond the segment's ends a photon's projection on the ray may lie, in its radii
/// (a disc in a face's plane reaches at most one radius along the ray from its centre).
const END_REACH: f64 = 1.0;
/// Smallest |cos| between the ray and the face that orients a photon's disc; a ray more
/// grazing than this (possible only after total internal reflection) keeps discs facing it.
const MIN_FACE_COS: f64 = 0.25;

/// Smallest fraction of a disc's kernel inside the medium that the estimate divides by (a
/// ray grazing a rim from outside would otherwise divide by almost nothing).
const MIN_FRACTION: f64 = 0.25;
/// Quadrature of the biweight kernel over a disc cut by faces: strata in radius² and angle.
const FRACTION_GRID: [usize; 2] = [16, 32];

/// The fraction of the biweight kernel of radius `r` about the origin of the (s, t) plane
/// that lies inside every plane (offset, outward normal; z ignored): a 512-point quadrature
/// in radius² (each stratum weighted by the kernel's mass in it) and angle, rotated by `u`.
pub(super) fn biweight_fraction_inside(planes: &[(Vec3, Vec3)], r: f64, u: f64) -> f64 {
    let [nr, na] = FRACTION_GRID;
    let dirs = rotated_circle::<{ FRACTION_GRID[1] }>(u);
    let mut inside = 0.0;
    for ir in 0..nr {
        // mass of the stratum v = ρ²/r² in [a, b]: ∫ 3 (1 − v)² dv / ... = (1 − a)³ − (1 − b)³
        let (a, b) = (ir as f64 / nr as f64, (ir + 1) as f64 / nr as f64);
        let mass = (1.0 - a).powi(3) - (1.0 - b).powi(3);
        let rho = r * (0.5 * (a + b)).sqrt();
        let hits = dirs
            .iter()
            .filter(|[c, s]| inside_planes(planes, Vec3::new(rho * c, rho * s, 0.0)))
            .count();
        inside += mass * hits as f64 / na as f64;
    }
    inside
}

/// The 2-D biweight kernel at squared distance `d2` for radius² `r2`: 3/(π r²) (1 − d²/r²)².
#[inline]
pub fn biweight(d2: f64, r2: f64) -> f64 {
    let u = 1.0 - d2 / r2;
    if u <= 0.0 {
        0.0
    } else {
        3.0 / (PI * r2) * u * u
    }
}

/// Where the ray `o + t d` (inverse direction `inv`) meets the box `[lo − g, hi + g]` within
/// `[t0, t1]`: whether it does.
#[inline]
fn hits_box(
    o: &[f64; 3],
    inv: &[f64; 3],
    lo: &[f32; 3],
    hi: &[f32; 3],
    g: f32,
    t0: f64,
    t1: f64,
) -> bool {
    let (mut a, mut b) = (t0, t1);
    for k in 0..3 {
        let (l, h) = ((lo[k] - g) as f64, (hi[k] + g) as f64);
        let (mut ta, mut tb) = ((l - o[k]) * inv[k], (h - o[k]) * inv[k]);
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        // a ray parallel to the slab: inside it (inf·0 = NaN is not < anything) or not
        if ta.is_nan() || tb.is_nan() {
            if o[k] < l || o[k] > h {
                return false;
            }
            continue;
        }
        a = a.max(ta);
        b = b.min(tb);
        if a > b {
            return false;
        }
    }
    true
}

impl BeamMap {
    /// Discs of radius `radius` [mm] for the photons of `map`.
    pub fn build(map: &PhotonMap, radius: f64) -> Self {
        let (lo, hi) = map.bounds();
        Self { radius, lo, hi }
    }

    /// Disc radius [mm].
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The fraction of a disc's kernel inside the medium at two depths along `seg`, (s, F):
    /// half and twice the camera's visible depth 1/σt (within the segment), the discs lying
    /// in the entry face's plane (else the exit's, else facing the ray). [`KernelClip`]'s
    /// rays in that plane find the faces beside the segment; between and beyond the two
    /// depths F is interpolated linearly (the faces a camera ray passes beside, a rim or a
    /// curved wall, change little over the depth it sees).
    fn rim_fraction(&self, seg: &Segment, clip: &KernelClip, t1: f64) -> [(f64, f64); 2] {
        let n = match seg.entry.or(seg.exit) {
            Some((_, n)) if seg.d.dot(n).abs() >= MIN_FACE_COS => n,
            _ => seg.d,
        };
        let frame = Frame::from_axis(n);
        let r = self.radius;
        let rays = rotated_circle::<CLIP_RAYS>(clip.u);
        let visible = if seg.sigma_t > 0.0 {
            1.0 / seg.sigma_t
        } else {
            t1
        };
        let at = |s: f64| {
            let x = seg.o + seg.d * s;
            let (planes, count) = clip.faces(x, &frame, r, |j| {
                Vec3::new(r * rays[j][0], r * rays[j][1], 0.0)
            });
            let f = if count == 0 {
                1.0
            } else {
                biweight_fraction_inside(&planes[..count], r, clip.u)
            };
            (s, f.max(MIN_FRACTION))
        };
        [
            at((0.5 * visible).min(0.5 * t1)),
            at((2.0 * visible).min(0.9 * t1)),
        ]
    }

    /// Call `f(photon)` for every photon of `map` whose disc the line `o + t d` (unit `d`)
    /// passes through with t in `[t0, t1]` widened by [`END_REACH`] radii.
    fn for_each_crossing<F: FnMut(&Photon)>(
        &self,
        map: &PhotonMap,
        o: Vec3,
        d: Vec3,
        t0: f64,
        t1: f64,
        mut f: F,
    ) {
        let ph = map.photons();
        if ph.is_empty() {
            return;
        }
        let of = [o.x, o.y, o.z];
        let df = [d.x, d.y, d.z];
        let inv = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        let (r2, g) = (self.radius * self.radius, self.radius as f32);
        let (lo_t, hi_t) = (t0 - END_REACH * self.radius, t1 + END_REACH * self.radius);
        let visit = |i: usize, f: &mut F| {
            let p = &ph[i];
            let x = [
                p.pos[0] as f64 - of[0],
                p.pos[1] as f64 - of[1],
                p.pos[2] as f64 - of[2],
            ];
            let t = x[0] * df[0] + x[1] * df[1] + x[2] * df[2];
            if t < lo_t || t > hi_t {
                return;
            }
            // squared distance from the line
            if (x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - t * t) < r2 {
                f(p);
            }
        };
        // explicit stack of (lo, hi, cell box); the tree is balanced, depth < 64
        let mut stack: Vec<(usize, usize, [f32; 3], [f32; 3])> = Vec::with_capacity(64);
        stack.push((0, ph.len(), self.lo, self.hi));
        while let Some((lo, hi, blo, bhi)) = stack.pop() {
            if hi - lo <= LEAF {
                for i in lo..hi {
                    visit(i, &mut f);
                }
                continue;
            }
            let mid = (lo + hi) / 2;
            if !hits_box(&of, &inv, &blo, &bhi, g, lo_t, hi_t) {
                continue;
            }
            visit(mid, &mut f);
            let axis = ph[mid].axis();
            let split = ph[mid].pos[axis];
            let (mut lhi, mut rlo) = (bhi, blo);
            lhi[axis] = split;
            rlo[axis] = split;
            if lo < mid {
                stack.push((lo, mid, blo, lhi));
            }
            if mid + 1 < hi {
                stack.push((mid + 1, hi, rlo, bhi));
            }
        }
    }

    /// The beam radiance estimate along `seg` over `map` (discs of this map's radius): the
    /// radiance that multiply scattered light in the segment sends back along the ray,
    /// attenuated to its start, each photon's disc lying in the nearer face's plane (module
    /// doc).
    pub fn estimate(&self, map: &PhotonMap, seg: &Segment) -> BeamEstimate {
        let t_cut = if seg.sigma_t > 0.0 {
            -MIN_TRANSMITTANCE.ln() / seg.sigma_t
        } else {
            f64::INFINITY
        };
        let t1 = seg.t_end.min(t_cut);
        if !t1.is_finite() {
            return BeamEstimate::default();
        }
        let (o, d, wo) = (seg.o, seg.d, -seg.d);
        let faces = [seg.entry, seg.exit];
        let fraction = seg.clip.map(|clip| self.rim_fraction(seg, &clip, t1));
        let r2 = self.radius * self.radius;
        let mut out = BeamEstimate::default();
        self.for_each_crossing(map, o, d, 0.0, t1, |p| {
            let x = p.position();
            // the nearer face orients the disc; a ray grazing it, or no face, keeps the disc
            // facing the ray (n = d)
            let height = |f: &Face| (x - f.0).dot(f.1);
            // (face, whether it is the one `rim_fraction` lays its discs along)
            let near = match faces {
                [Some(a), Some(b)] if height(&a).abs() <= height(&b).abs() => Some((a, true)),
                [Some(_), Some(b)] => Some((b, false)),
                [a, b] => a.or(b).map(|f| (f, true)),
            };
            let primary = near.is_none_or(|(_, p)| p);
            let near = near.map(|(f, _)| f);
            let (n, dn) = match near {
                Some((_, n)) if d.dot(n).abs() >= MIN_FACE_COS => (n, d.dot(n)),
                _ => (d, 1.0),
            };
            // the ray point at the photon's height above that face, and the offset in its plane
            let rel = x - o;
            let s = rel.dot(n) / dn;
            if !(0.0..=t1).contains(&s) {
                return;
            }
            let v = rel - d * s;
            let d2 = v.dot(v);
            // photons of the medium lie on the inner side of both faces
            if d2 >= r2 || faces.iter().flatten().any(|f| height(f) >= 0.0) {
                return;
            }
            // a disc along the other face (the exit, near it) is not cut by what cuts these
            let f = fraction
                .filter(|_| primary)
                .map_or(1.0, |[(sa, fa), (sb, fb)]| {
                    if sb > sa {
                        fa + (fb - fa) * ((s - sa) / (sb - sa)).clamp(0.0, 1.0)
                    } else {
                        fa
                    }
                });
            out.value += biweight(d2, r2) * (-seg.sigma_t * s).exp() / (dn.abs() * f)
                * seg.phase.eval(p.direction().dot(wo))
                * p.power as f64;
            out.count += 1;
        });
        out
    }
}
