//! The measuring geometry of a spectrophotometer, as the slab simulator sees it.
//!
//! A real instrument lights a spot of finite size and looks at a window of finite size, with
//! the specimen lying on a backing. Light that enters inside the spot and travels sideways
//! leaves outside the window (or through the specimen's rim) and is not read: edge loss.
//! [`Window`] puts that geometry into the slab run: photons enter uniformly over the lit
//! disc, a Lambertian backing of reflectance `backing` lies under the stack (zero gap, in
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
    /// Radius of the lit disc [mm]; photons enter uniformly over it (0: a pencil beam).
    pub illuminated_radius: f64,
    /// Radius of the viewed window [mm], centred on the lit disc, on both faces.
    pub viewed_radius: f64,
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
            Some((lo, hi)) => hi.sin().powi(2) - lo.sin().powi(2),
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

    /// Probability that a point uniform over the lit disc, moved by a distance `d`, lands
    /// inside the viewed window: the area the two discs (radii a and b, centres `d` apart)
    /// share, over π a². The reading of a laterally uniform specimen, integrated over the
    /// entry point instead of sampling it (see the slab walk's backing orders).
    pub fn overlap_fraction(&self, d: f64) -> f64 {
        let (a, b) = (self.illuminated_radius, self.viewed_radius);
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

    /// Power an ideal Lambertian white would send through the window, as a fraction of the
    /// incident power: min(a, b)² / a² (1 for a pencil beam inside the window).
    pub fn white_fraction(&self) -> f64 {
        let a = self.illuminated_radius;
        let b = self.viewed_radius;
        if a <= b {
            1.0
        } else {
            (b / a).powi(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window() -> Window {
        Window {
            illuminated_radius: 1.5,
            viewed_radius: 1.5,
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
                let (mut inside, mut total) = (0u64, 0u64);
                let n = 800;
                for i in 0..n {
                    for j in 0..n {
                        let x = a * (2.0 * (i as f64 + 0.5) / n as f64 - 1.0);
                        let y = a * (2.0 * (j as f64 + 0.5) / n as f64 - 1.0);
                        if x * x + y * y <= a * a {
                            total += 1;
                            inside += u64::from((x + d).powi(2) + y * y <= b * b);
                        }
                    }
                }
                let counted = inside as f64 / total as f64;
                let f = w.overlap_fraction(d);
                assert!(
                    (f - counted).abs() < 3e-3,
                    "a {a} b {b} d {d}: {f} vs {counted}"
                );
            }
        }
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
