//! One homogeneous participating medium for one band (paper eqs. 1–6): absorption and
//! scattering coefficients, refractive index and phase function.

use crate::error::{check_range, Result};
use crate::phase::PhaseFunction;

/// A homogeneous medium at one wavelength.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Medium {
    /// Absorption coefficient σa = μa [1/mm].
    pub sigma_a: f64,
    /// Scattering coefficient σs = μs [1/mm].
    pub sigma_s: f64,
    /// Refractive index n (≥ 1).
    pub eta: f64,
    /// Phase function (eqs. 7–10).
    pub phase: PhaseFunction,
}

impl Medium {
    /// A medium, validated; `name` prefixes the field names in error messages.
    pub fn new(
        name: &str,
        sigma_a: f64,
        sigma_s: f64,
        eta: f64,
        phase: PhaseFunction,
    ) -> Result<Self> {
        check_range(
            &format!("{name}mua"),
            sigma_a,
            0.0,
            false,
            f64::INFINITY,
            true,
            "1/mm",
        )?;
        check_range(
            &format!("{name}mus"),
            sigma_s,
            0.0,
            false,
            f64::INFINITY,
            true,
            "1/mm",
        )?;
        check_range(
            &format!("{name}n"),
            eta,
            1.0,
            false,
            f64::INFINITY,
            true,
            "",
        )?;
        phase.validate().map_err(|e| match e {
            crate::Error::InvalidInput(m) => crate::Error::InvalidInput(format!("{name}{m}")),
            other => other,
        })?;
        Ok(Self {
            sigma_a,
            sigma_s,
            eta,
            phase,
        })
    }

    /// Extinction σt = σa + σs [1/mm] (eq. 1).
    #[inline]
    pub fn sigma_t(&self) -> f64 {
        self.sigma_a + self.sigma_s
    }

    /// Single-scattering albedo σs/σt (eq. 3); 0 for a vacuum-like medium.
    #[inline]
    pub fn albedo(&self) -> f64 {
        let t = self.sigma_t();
        if t > 0.0 {
            self.sigma_s / t
        } else {
            0.0
        }
    }
}
