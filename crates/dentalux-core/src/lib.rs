//! dentalux-core: everything dentalux does per photon and per ray.
//!
//! Crate map (data flows top to bottom):
//! - [`math`], [`rng`], [`sampling`]: vectors and frames, deterministic random streams, warps.
//! - [`phase`]: phase functions of the paper (eqs. 7–10).
//! - [`fresnel`]: smooth dielectric interfaces (unpolarised Fresnel, refraction, TIR).
//! - [`medium`]: one homogeneous participating medium for one band (eqs. 1–6).
//! - [`integrators`]: the slab simulator (what a spectrophotometer measures).
//! - [`control`]: cancellation and progress shared with the caller.
//! - [`error`]: input validation errors that name the field and its allowed range.
//!
//! Units: millimetres, 1/mm, nanometres. No Python in this crate.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod camera;
pub mod contract;
pub mod control;
pub mod error;
pub mod film;
pub mod fresnel;
pub mod geometry;
pub mod instrument;
pub mod integrators;
pub mod lights;
pub mod math;
pub mod medium;
pub mod phase;
pub mod photon_map;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod surface;

pub use error::{Error, Result};
