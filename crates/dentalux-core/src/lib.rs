//! dentalux-core: everything dentalux does per photon and per ray.
//!
//! Crate map (lower layers first):
//! - [`math`], [`rng`], [`sampling`]: vectors and frames, deterministic random streams and
//!   their tags, warps from uniforms to distributions.
//! - [`error`], [`control`], [`batches`]: input errors that name the field and its allowed
//!   range; cancellation and progress shared with the caller; a run's batches on the thread
//!   pool.
//! - [`phase`]: phase functions of the paper (eqs. 7–10).
//! - [`fresnel`]: smooth dielectric interfaces (unpolarised Fresnel, refraction, TIR).
//! - [`medium`]: one homogeneous participating medium for one band (eqs. 1–6).
//! - [`geometry`]: rays, hits, shapes, triangle meshes, transforms and the BVH.
//! - [`camera`], [`film`], [`surface`], [`lights`]: the pinhole camera, the image and its
//!   tiles, opaque surface materials, light sources.
//! - [`scene`]: one band's scene as plain data, with the BVH over every shape (shared by
//!   the bands of one render).
//! - [`photon_map`]: photon records, the kd-tree, the density estimates (eq. 11) and the
//!   beam radiance estimate.
//! - [`instrument`]: a spectrophotometer's measuring geometry (lit spot, window, backing) as
//!   the slab simulator sees it.
//! - [`integrators`]: the slab simulator (what a spectrophotometer measures) and the
//!   renderers (`pm`, `path`, `vpm`, `bre`, `vpm-full`, `ppm`, `volpath`, `volpath-nee`),
//!   with the render settings and the dispatch on them, one band or all bands of a scene.
//! - [`contract`]: the render contract's JSON (docs/render-contract.md) decoded into a
//!   [`scene::Scene`] (one per band, sharing their shapes) and
//!   [`integrators::settings::Settings`], and the settings' schema.
//!
//! Units: millimetres, 1/mm, nanometres. No Python in this crate.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod batches;
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
