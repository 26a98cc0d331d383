//! Integrators: each one a way of turning photons or rays into a measured quantity.
//!
//! - [`slab`]: layered slab lit by a beam or diffuse light; what a spectrophotometer with
//!   an integrating sphere measures (total transmittance, reflectance, absorption);
//!   [`slab_spectral`] reads every band of an instrument window from shared walks.
//! - [`photon_trace`]: the photon pass (eqs. 1–10) filling volume and surface photon maps,
//!   its energy [`ledger`]; [`aim`] sends part of the volume pass straight at the media;
//!   [`hero`] weighs a spectral pass's walks between its bands.
//! - [`vpm`]: volume photon mapping's camera pass (eqs. 11–13), modes `vpm` and `vpm-full`;
//!   [`hero_camera`] runs it over every band of a render with one camera path.
//! - [`ppm`]: probabilistic progressive photon mapping (bounded memory, consistent).
//! - [`volpath`]: the unbiased volumetric path tracer that judges them; [`planar_nee`] lets
//!   it connect to lights through flat refracting faces (a faster reference).
//! - [`pm`]: surface photon mapping for opaque scenes with clear media; [`path`] the path
//!   tracer that judges it; [`direct`] the direct light both take at a surface.
//! - [`transport`]: boundary crossing, shadow-ray transmittance (eqs. 12–13), ray spawning.
//! - [`settings`]: the render settings, their defaults and ranges, and the returned statistics;
//!   [`tiles`]: the tile loop every camera pass shares; [`render`]: the dispatch on
//!   `settings.integrator`.
//!
//! Layering (no module uses one above it): `settings`, `transport`, `tiles`, `ledger` →
//! `hero` → `direct`, `photon_trace`, `aim`, `planar_nee` → `path`, `pm`, `vpm`, `volpath` →
//! `ppm`, `hero_camera` → `render` (tests/test_import_graph.py checks that the graph has no
//! circle).

pub mod aim;
pub mod direct;
pub mod hero;
pub mod hero_camera;
pub mod ledger;
pub mod path;
pub mod photon_trace;
pub mod planar_nee;
pub mod pm;
pub mod ppm;
pub mod render;
pub mod settings;
pub mod slab;
pub mod slab_spectral;
pub mod tiles;
pub mod transport;
pub mod volpath;
pub mod vpm;
