//! The geometry of the density kernels near boundaries: the planes that orient and cut the
//! layer kernel, the rays that find other faces within a kernel ([`KernelClip`]), and the
//! quadratures of the part of a kernel on the inside of those faces.

use crate::math::{Frame, Vec3};
use std::f64::consts::PI;

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
pub(super) const CLIP_RAYS: usize = 8;

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
/// docs/notes/2026-12-02-vpm-convergence.md.) Where no face is met, the kernel keeps its exact moments.
#[derive(Clone, Copy)]
pub struct KernelClip<'a> {
    /// The first surface on the segment from a point along a unit direction within a
    /// distance [mm]: (hit point, surface normal), any orientation.
    pub hit: &'a dyn Fn(Vec3, Vec3, f64) -> Option<(Vec3, Vec3)>,
    /// Random rotation of the rays and quadrature points about the kernel's axis, [0, 1).
    pub u: f64,
}

/// Whether offset `d` lies on the inner side of every plane (offset, outward unit normal).
pub(super) fn inside_planes(planes: &[(Vec3, Vec3)], d: Vec3) -> bool {
    planes.iter().all(|(o, nrm)| (d - *o).dot(*nrm) < 0.0)
}

/// ∫1, ∫z, ∫z² over a prism of cross-section `area` and z ∈ [a, b].
pub(super) fn prism_moments(area: f64, a: f64, b: f64) -> [f64; 3] {
    [
        area * (b - a),
        area * (b * b - a * a) / 2.0,
        area * (b * b * b - a * a * a) / 3.0,
    ]
}

/// The fraction of the disc of radius `r` about the origin of the (s, t) plane that lies
/// inside every plane (offset, outward normal; z ignored): a 512-point quadrature in
/// radius² and angle, rotated by `u` ∈ [0, 1).
pub(super) fn disc_fraction_inside(planes: &[(Vec3, Vec3)], r: f64, u: f64) -> f64 {
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
pub(super) fn rotated_circle<const N: usize>(u: f64) -> [[f64; 2]; N] {
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
    pub(super) fn faces(
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
    pub(super) fn moments(&self, x: Vec3, n: Vec3, a: f64, b: f64, big_r: f64) -> Option<[f64; 3]> {
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
