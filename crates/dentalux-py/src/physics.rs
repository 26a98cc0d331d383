//! Bindings of single formulas of the core that Python models reuse, so each has one home.

use pyo3::prelude::*;

/// Unpolarised Fresnel reflectance (fresnel.rs) for each incidence cosine in `cos_i`, light
/// arriving from index `eta_i` into `eta_t`; 1 under total internal reflection.
#[pyfunction]
pub fn fresnel_reflectance(cos_i: Vec<f64>, eta_i: f64, eta_t: f64) -> Vec<f64> {
    cos_i
        .into_iter()
        .map(|c| dentalux_core::fresnel::reflectance(c, eta_i, eta_t))
        .collect()
}

/// Fraction of a Lambertian exitance inside the detector cone `lo_deg`..`hi_deg` [deg]
/// (instrument.rs, as the core's windows read it).
#[pyfunction]
pub fn cone_fraction(lo_deg: f64, hi_deg: f64) -> f64 {
    dentalux_core::instrument::cone_fraction(lo_deg.to_radians(), hi_deg.to_radians())
}
