//! Integrators: each one a way of turning photons or rays into a measured quantity.
//!
//! - [`slab`]: layered slab lit by a beam or diffuse light; what a spectrophotometer with
//!   an integrating sphere measures (total transmittance, reflectance, absorption).

pub mod slab;
pub mod photon_trace;
pub mod transport;
pub mod vpm;
pub mod volpath;
pub mod path;
pub mod pm;
pub mod render;
