//! `dentalux._core`: the thin binding between dentalux-core and Python. It converts types,
//! runs long calls without the GIL on a worker thread, and turns core errors into Python
//! exceptions. It holds no physics.

mod geometry;
mod physics;
mod render;
mod runner;
mod slab;
mod special;

use pyo3::prelude::*;

/// The private native module, re-exported by the `dentalux` package.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    quiet_panics();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // facts Python reads instead of keeping copies
    m.add(
        "SLAB_MAX_PROFILE_BINS",
        dentalux_core::integrators::slab::MAX_PROFILE_BINS,
    )?;
    m.add(
        "SLAB_SCALAR_KEYS",
        dentalux_core::integrators::slab::SCALAR_KEYS.to_vec(),
    )?;
    m.add("PHOTON_BYTES", dentalux_core::photon_map::PHOTON_BYTES)?;
    m.add(
        "SLAB_MAX_BACKING_ORDER",
        dentalux_core::integrators::slab::MAX_BACKING_ORDER,
    )?;
    m.add(
        "SLAB_WINDOW_KEYS",
        dentalux_core::instrument::WINDOW_KEYS.to_vec(),
    )?;
    m.add("DIFFUSE_RUN_KEY", dentalux_core::rng::DIFFUSE_RUN_KEY)?;
    m.add(
        "TRANSMITTED_RUN_KEY",
        dentalux_core::rng::TRANSMITTED_RUN_KEY,
    )?;
    m.add("RIM_RUN_KEY", dentalux_core::rng::RIM_RUN_KEY)?;
    m.add(
        "SLAB_MIN_BATCH",
        dentalux_core::integrators::slab::MIN_BATCH,
    )?;
    m.add(
        "SLAB_MIN_RIM_BATCH",
        dentalux_core::integrators::slab::MIN_RIM_BATCH,
    )?;
    m.add_function(wrap_pyfunction!(slab::slab_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(slab::slab_read_bands, m)?)?;
    m.add_function(wrap_pyfunction!(slab::slab_read_spectral, m)?)?;
    m.add_function(wrap_pyfunction!(slab::phase_sample_cos, m)?)?;
    m.add_function(wrap_pyfunction!(slab::phase_eval, m)?)?;
    m.add_function(wrap_pyfunction!(physics::fresnel_reflectance, m)?)?;
    m.add_function(wrap_pyfunction!(physics::cone_fraction, m)?)?;
    m.add_function(wrap_pyfunction!(special::bessel_j, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_band, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_bands, m)?)?;
    m.add_function(wrap_pyfunction!(render::camera_project, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::shape_contains, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::mesh_topology, m)?)?;
    m.add_function(wrap_pyfunction!(render::settings_schema, m)?)?;
    m.add_function(wrap_pyfunction!(render::photons_traced, m)?)?;
    m.add_function(wrap_pyfunction!(panic_in_worker, m)?)?;
    Ok(())
}

/// A panic in the core reaches Python as `RuntimeError` carrying the panic's message
/// (runner.rs); the default hook would also print the panic text and a backtrace on
/// stderr. Keep stderr clean unless `DENTALUX_PANIC_TRACE` is set (for debugging).
fn quiet_panics() {
    if std::env::var_os("DENTALUX_PANIC_TRACE").is_none() {
        std::panic::set_hook(Box::new(|_| {}));
    }
}

/// Panic inside a worker thread, as a bug in the core would: for the test that a panic
/// reaches Python as `RuntimeError` instead of aborting the interpreter.
#[pyfunction]
fn panic_in_worker(py: Python<'_>) -> PyResult<()> {
    runner::run(py, Some(2), None, |_| -> dentalux_core::Result<()> {
        let v: Vec<u32> = (0..4).collect();
        rayon::scope(|s| s.spawn(|_| panic!("deliberate test panic at index {}", v[3])));
        Ok(())
    })
}
