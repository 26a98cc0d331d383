//! `dentalux._core`: the thin binding between dentalux-core and Python. It converts types,
//! runs long calls without the GIL on a worker thread, and turns core errors into Python
//! exceptions. It holds no physics.

mod render;
mod runner;
mod slab;

use pyo3::prelude::*;

/// The private native module, re-exported by the `dentalux` package.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(slab::slab_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(slab::phase_sample_cos, m)?)?;
    m.add_function(wrap_pyfunction!(slab::phase_eval, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_band, m)?)?;
    Ok(())
}
