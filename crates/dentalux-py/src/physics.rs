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
