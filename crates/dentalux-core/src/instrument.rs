//! The measuring geometry of a spectrophotometer, as the slab simulator sees it.
//!
//! A real instrument lights a spot of finite size and looks at a window of finite size, with
//! the specimen lying on a backing. Light that enters inside the spot and travels sideways
//! leaves outside the window (or through the specimen's rim) and is not read: edge loss.
//! [`Window`] puts that geometry into the slab run: photons enter uniformly over the lit
//! disc (or ring: a fibre probe's illuminating ring, read at the centre or over another
//! ring), a Lambertian backing of reflectance `backing` lies under the stack (zero gap, in
//! the medium of index `n_below`), and the exits are tallied inside and outside the window.
//!
//! The reading is a reflectance factor: the power leaving the window divided by what an
//! ideal (non-penetrating) Lambertian white would send through it, which for uniform light
//! over radius a and a window of radius b is min(a, b)² / a² of the incident power, and, for
//! a detector cone [θ₁, θ₂] (directional geometries), a further sin²θ₂ − sin²θ₁. The
//! directional geometries are simulated in their reciprocal form (lit along the detector's
//! axis, collected over the illuminator's cone): the reading is the same for a reciprocal
//! specimen and the collecting cone is wide, so fewer photons are needed.

use crate::error::{check_range, Error, Result};

/// Finite lit spot, viewed window, backing and specimen size of one slab run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Outer radius of the lit region [mm]; photons enter uniformly over it (0: a pencil
    /// beam).
    pub illuminated_radius: f64,
    /// Inner radius of the lit region [mm]: 0 for a disc, else the lit region is the ring
    /// (annulus) between it and [`Window::illuminated_radius`] (a fibre probe's source ring).
    pub illuminated_inner_radius: f64,
    /// Outer radius of the viewed window [mm], centred on the lit region, on both faces.
    pub viewed_radius: f64,
    /// Inner radius of the viewed window [mm]: 0 for a disc, else an exit is read when its
    /// distance r from the centre has `viewed_inner_radius <= r <= viewed_radius`.
    pub viewed_inner_radius: f64,
    /// Radius of the specimen [mm]; light crossing it is lost at the rim (∞: no rim).
    pub specimen_radius: f64,
    /// Reflectance of the Lambertian backing under the stack, in [0, 1].
    pub backing: f64,
    /// Detector cone on the top face, polar angles [rad] in the medium above; `None`
    /// collects the whole hemisphere (an integrating sphere).
    pub cone: Option<(f64, f64)>,
}

/// Tallies of a run with a [`Window`], in this order in the result's `window` arrays.
pub const WINDOW_KEYS: [&str; 6] = [
    "viewed_reflectance",
    "viewed_specular",
    "viewed_cone_reflectance",
    "outside_reflectance",
    "rim_loss",
    "viewed_transmittance",
];
/// Power leaving the top inside the window (all angles, first-surface specular included).
pub const VIEWED_R: usize = 0;
/// The first-surface specular part of [`VIEWED_R`].
pub const VIEWED_SPEC: usize = 1;
/// Power leaving the top inside the window and inside the detector cone, divided by the
/// Lambertian fraction of the cone (equals [`VIEWED_R`] without a cone).
pub const VIEWED_CONE: usize = 2;
/// Power leaving the top outside the window (edge loss through the face).
pub const OUTSIDE_R: usize = 3;
/// Power lost through the specimen's rim.
pub const RIM: usize = 4;
/// Power lost into the backing inside the window (the transmitted reading for backing 0).
pub const VIEWED_T: usize = 5;

impl Window {
    /// Check every field; messages name the field and its allowed range.
    pub fn validate(&self) -> Result<()> {
        let inf = f64::INFINITY;
        check_range(
            "illuminated_radius",
            self.illuminated_radius,
            0.0,
            false,
            inf,
            true,
            "mm",
        )?;
        // the window and the specimen may be unbounded (+inf), never 0, negative or NaN
        for (field, value) in [
            ("viewed_radius", self.viewed_radius),
            ("specimen_radius", self.specimen_radius),
        ] {
            if value != inf {
                check_range(field, value, 0.0, true, inf, true, "mm")?;
            }
        }
        // an inner radius makes a ring: 0 (a disc) or inside [0, outer)
        for (field, inner, outer) in [
            (
                "illuminated_inner_radius",
                self.illuminated_inner_radius,
                self.illuminated_radius,
            ),
            (
                "viewed_inner_radius",
                self.viewed_inner_radius,
                self.viewed_radius,
            ),
        ] {
            if inner != 0.0 {
                check_range(field, inner, 0.0, false, outer, true, "mm")?;
            }
        }
        check_range("backing", self.backing, 0.0, false, 1.0, false, "")?;
        if let Some((lo, hi)) = self.cone {
            let deg = |x: f64| x.to_degrees();
            check_range("cone low", deg(lo), 0.0, false, 90.0, true, "deg")?;
            check_range("cone high", deg(hi), deg(lo), true, 90.0, false, "deg")?;
        }
        if self.illuminated_radius > self.specimen_radius {
            return Err(Error::InvalidInput(format!(
                "illuminated_radius = {} mm is larger than specimen_radius = {} mm: the light \
                 would miss the specimen",
                self.illuminated_radius, self.specimen_radius
            )));
        }
        Ok(())
    }

    /// Fraction of a Lambertian exitance that falls inside the detector cone (1 without one).
    pub fn cone_fraction(&self) -> f64 {
        match self.cone {
            None => 1.0,
            Some((lo, hi)) => cone_fraction(lo, hi),
        }
    }

    /// Whether an exit direction with |cos θ| = `cos_exit` (in the medium above) is seen.
    #[inline]
    pub fn in_cone(&self, cos_exit: f64) -> bool {
        match self.cone {
            None => true,
            Some((lo, hi)) => {
                let c = cos_exit.abs();
                c <= lo.cos() && c >= hi.cos()
            }
        }
    }

    /// Whether the lit region and the window are both discs (no inner radius): today's
    /// geometry, whose arithmetic is kept exactly as it was.
    #[inline]
    pub fn is_discs(&self) -> bool {
        self.illuminated_inner_radius == 0.0 && self.viewed_inner_radius == 0.0
    }

    /// Whether an exit at squared distance `r2` [mm²] from the centre is inside the window.
    #[inline]
    pub fn in_window(&self, r2: f64) -> bool {
        // with viewed_inner_radius = 0 the first test always holds (r2 >= 0)
        r2 >= self.viewed_inner_radius * self.viewed_inner_radius
            && r2 <= self.viewed_radius * self.viewed_radius
    }

    /// Probability that a point uniform over the lit region, moved by a distance `d`, lands
    /// inside the viewed window: the area the two regions (centres `d` apart) share, over the
    /// lit area. For discs of radii a and b, the lens of the two discs over π a²; for rings,
    /// by inclusion–exclusion of disc lenses, area(A ∩ (B + d)) = L(a, b) − L(a₀, b) −
    /// L(a, b₀) + L(a₀, b₀) (a₀, b₀ the inner radii, L(r₁, r₂) the lens of discs r₁, r₂ at
    /// distance d), over π (a² − a₀²). The reading of a laterally uniform specimen,
    /// integrated over the entry point instead of sampling it (see the slab walk's backing
    /// orders).
    pub fn overlap_fraction(&self, d: f64) -> f64 {
        let (a, b) = (self.illuminated_radius, self.viewed_radius);
        if self.is_discs() {
            return disc_overlap_fraction(a, b, d);
        }
        let (a0, b0) = (self.illuminated_inner_radius, self.viewed_inner_radius);
        let area =
            lens_area(a, b, d) - lens_area(a0, b, d) - lens_area(a, b0, d) + lens_area(a0, b0, d);
        (area / (std::f64::consts::PI * (a * a - a0 * a0))).clamp(0.0, 1.0)
    }

    /// Power an ideal Lambertian white would send through the window, as a fraction of the
    /// incident power: the lit area inside the window over the lit area, min(a, b)² / a²
    /// for discs (1 for a pencil beam inside the window); 0 where the lit region and the
    /// window do not overlap (a ring-lit, centre-read probe), which an ideal white cannot
    /// normalise.
    pub fn white_fraction(&self) -> f64 {
        let a = self.illuminated_radius;
        let b = self.viewed_radius;
        if self.is_discs() {
            return if a <= b { 1.0 } else { (b / a).powi(2) };
        }
        let a0 = self.illuminated_inner_radius;
        let b0 = self.viewed_inner_radius;
        let (lo, hi) = (a0.max(b0), a.min(b));
        if hi <= lo {
            return 0.0;
        }
        ((hi * hi - lo * lo) / (a * a - a0 * a0)).clamp(0.0, 1.0)
    }
}

/// The area [mm²] two discs of radii `r1`, `r2` with centres `d` apart share (0 where
/// either radius is 0).
pub fn lens_area(r1: f64, r2: f64, d: f64) -> f64 {
    if r1 <= 0.0 || r2 <= 0.0 || d >= r1 + r2 {
        return 0.0;
    }
    if d <= (r2 - r1).abs() {
        let r = r1.min(r2);
        return std::f64::consts::PI * r * r;
    }
    let c1 = ((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1)).clamp(-1.0, 1.0);
    let c2 = ((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2)).clamp(-1.0, 1.0);
    let k = ((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)).max(0.0);
    (r1 * r1 * c1.acos() + r2 * r2 * c2.acos() - 0.5 * k.sqrt()).max(0.0)
}

/// [`Window::overlap_fraction`] of two discs, lit radius `a` and window radius `b`: the
/// arithmetic of the concentric-disc model, unchanged.
fn disc_overlap_fraction(a: f64, b: f64, d: f64) -> f64 {
    if d >= a + b {
        return 0.0;
    }
    if d <= (b - a).abs() {
        return if a <= b { 1.0 } else { (b / a).powi(2) };
    }
    // the lens of two circles: each circle's segment beyond the common chord
    let ca = ((d * d + a * a - b * b) / (2.0 * d * a)).clamp(-1.0, 1.0);
    let cb = ((d * d + b * b - a * a) / (2.0 * d * b)).clamp(-1.0, 1.0);
    let k = ((-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b)).max(0.0);
    let lens = a * a * ca.acos() + b * b * cb.acos() - 0.5 * k.sqrt();
    (lens / (std::f64::consts::PI * a * a)).clamp(0.0, 1.0)
}

/// Fraction of a Lambertian exitance that leaves within polar angles `lo`..`hi` [rad] of
/// the normal: the exitance goes as cos θ sin θ dθ, which integrates to sin² hi − sin² lo.
pub fn cone_fraction(lo: f64, hi: f64) -> f64 {
    hi.sin().powi(2) - lo.sin().powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window() -> Window {
        Window {
            illuminated_radius: 1.5,
            illuminated_inner_radius: 0.0,
            viewed_radius: 1.5,
            viewed_inner_radius: 0.0,
            specimen_radius: f64::INFINITY,
            backing: 0.0,
            cone: None,
        }
    }

    #[test]
    fn cone_fraction_of_the_hemisphere_is_one() {
        let mut w = window();
        assert_eq!(w.cone_fraction(), 1.0);
        w.cone = Some((0.0, std::f64::consts::FRAC_PI_2));
        assert!((w.cone_fraction() - 1.0).abs() < 1e-15);
        w.cone = Some((40f64.to_radians(), 50f64.to_radians()));
        let f = 50f64.to_radians().sin().powi(2) - 40f64.to_radians().sin().powi(2);
        assert!((w.cone_fraction() - f).abs() < 1e-15);
        assert!(w.in_cone(45f64.to_radians().cos()));
        assert!(!w.in_cone(1.0));
    }

    #[test]
    fn overlap_fraction_matches_counting_points() {
        // a grid of points over the lit disc, each moved by d, counted inside the window
        for (a, b) in [(1.5, 1.5), (1.0, 2.0), (2.0, 1.0)] {
            let mut w = window();
            w.illuminated_radius = a;
            w.viewed_radius = b;
            for d in [0.0, 0.3, 0.9, 1.7, 2.6, 3.1] {
                let c = counted(0.0, a, 0.0, b, d);
                let f = w.overlap_fraction(d);
                assert!((f - c).abs() < 3e-3, "a {a} b {b} d {d}: {f} vs {c}");
            }
        }
    }

    /// Points of a grid over the lit ring [a0, a] moved by `d`: the fraction inside [b0, b].
    fn counted(a0: f64, a: f64, b0: f64, b: f64, d: f64) -> f64 {
        let (mut inside, mut total) = (0u64, 0u64);
        let n = 800;
        for i in 0..n {
            for j in 0..n {
                let x = a * (2.0 * (i as f64 + 0.5) / n as f64 - 1.0);
                let y = a * (2.0 * (j as f64 + 0.5) / n as f64 - 1.0);
                let r2 = x * x + y * y;
                if r2 <= a * a && r2 >= a0 * a0 {
                    total += 1;
                    let e2 = (x + d).powi(2) + y * y;
                    inside += u64::from(e2 <= b * b && e2 >= b0 * b0);
                }
            }
        }
        inside as f64 / total as f64
    }

    #[test]
    fn ring_overlap_fraction_matches_counting_points() {
        // (a0, a, b0, b): a lit ring read at the centre, a lit centre read over a ring, two
        // overlapping rings, a ring inside a disc, and a disc given as a ring of inner 0
        let cases = [
            (1.0, 1.5, 0.0, 0.6),
            (0.0, 0.6, 1.0, 1.5),
            (0.5, 1.5, 1.0, 2.0),
            (0.4, 1.0, 0.0, 2.0),
            (0.0, 1.0, 0.0, 2.0),
        ];
        for (a0, a, b0, b) in cases {
            let mut w = window();
            w.illuminated_inner_radius = a0;
            w.illuminated_radius = a;
            w.viewed_inner_radius = b0;
            w.viewed_radius = b;
            w.validate().unwrap();
            for d in [0.0, 0.3, 0.9, 1.2, 1.7, 2.6, 3.1, 4.0] {
                let c = counted(a0, a, b0, b, d);
                let f = w.overlap_fraction(d);
                assert!(
                    (f - c).abs() < 3e-3,
                    "a0 {a0} a {a} b0 {b0} b {b} d {d}: {f} vs {c}"
                );
            }
            let c = counted(a0, a, b0, b, 0.0);
            assert!(
                (w.white_fraction() - c).abs() < 3e-3,
                "white {a0} {a} {b0} {b}"
            );
        }
    }

    #[test]
    fn rings_of_inner_radius_zero_are_the_discs_exactly() {
        // the ring formula with inner radii 0 agrees with the disc arithmetic to rounding,
        // and a window with inner radii 0 takes the disc arithmetic itself (bit for bit)
        for (a, b) in [(1.5, 1.5), (1.0, 2.0), (2.0, 1.0)] {
            for d in [0.0, 0.3, 0.9, 1.7, 2.6, 3.1] {
                let ring = (lens_area(a, b, d) - lens_area(0.0, b, d) - lens_area(a, 0.0, d)
                    + lens_area(0.0, 0.0, d))
                    / (std::f64::consts::PI * a * a);
                let disc = disc_overlap_fraction(a, b, d);
                assert!((ring - disc).abs() < 1e-12, "a {a} b {b} d {d}");
                let mut w = window();
                w.illuminated_radius = a;
                w.viewed_radius = b;
                assert_eq!(w.overlap_fraction(d).to_bits(), disc.to_bits());
            }
        }
    }

    #[test]
    fn disjoint_rings_have_no_white_normalisation() {
        let mut w = window();
        w.illuminated_inner_radius = 1.0;
        w.illuminated_radius = 1.5;
        w.viewed_radius = 0.6;
        assert_eq!(w.white_fraction(), 0.0);
        assert!(w.in_window(0.25) && !w.in_window(1.0));
        w.viewed_inner_radius = 0.3;
        assert!(!w.in_window(0.04) && w.in_window(0.25));
    }

    #[test]
    fn bad_inner_radii_are_refused_with_the_field_named() {
        for (lit, value) in [
            (true, -0.1),
            (true, f64::NAN),
            (true, 1.5),
            (true, 2.0),
            (false, -1.0),
            (false, f64::NAN),
            (false, 1.5),
        ] {
            let mut w = window();
            let field = if lit {
                w.illuminated_inner_radius = value;
                "illuminated_inner_radius"
            } else {
                w.viewed_inner_radius = value;
                "viewed_inner_radius"
            };
            let msg = w.validate().unwrap_err().to_string();
            assert!(msg.contains(field), "{field} = {value}: {msg}");
        }
        // a pencil beam (outer 0) with inner 0 stays valid
        let mut w = window();
        w.illuminated_radius = 0.0;
        w.validate().unwrap();
    }

    #[test]
    fn white_fraction_is_symmetric_in_the_overlap() {
        let mut w = window();
        w.illuminated_radius = 4.0;
        w.viewed_radius = 1.0;
        assert!((w.white_fraction() - 1.0 / 16.0).abs() < 1e-15);
        w.illuminated_radius = 1.0;
        w.viewed_radius = 4.0;
        assert_eq!(w.white_fraction(), 1.0);
    }

    #[test]
    fn bad_geometry_is_refused_with_the_field_named() {
        let mut w = window();
        w.viewed_radius = 0.0;
        assert!(w
            .validate()
            .unwrap_err()
            .to_string()
            .contains("viewed_radius"));
        let mut w = window();
        w.backing = 1.5;
        assert!(w.validate().unwrap_err().to_string().contains("backing"));
        let mut w = window();
        w.illuminated_radius = f64::NAN;
        assert!(w.validate().is_err());
        let mut w = window();
        w.specimen_radius = 1.0;
        assert!(w
            .validate()
            .unwrap_err()
            .to_string()
            .contains("specimen_radius"));
        let mut w = window();
        w.cone = Some((0.5, 0.2));
        assert!(w.validate().unwrap_err().to_string().contains("cone"));
    }
}
