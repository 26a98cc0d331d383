//! Bessel functions of the first kind, J0 and J1, elementwise over numpy arrays: the
//! layered solver's window kernels need them (the Hankel transforms of discs), and taking
//! libm's (the FreeBSD msun algorithms, within 5e-15 of scipy's cephes ones over 0-6000)
//! spares a reading the import of scipy.special.

use numpy::{IntoPyArray, PyArrayDyn, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// J_order(x) for every element of `x`, order 0 or 1.
#[pyfunction]
pub fn bessel_j<'py>(
    py: Python<'py>,
    order: u32,
    x: PyReadonlyArrayDyn<'py, f64>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let f = match order {
        0 => libm::j0,
        1 => libm::j1,
        _ => {
            return Err(PyValueError::new_err(format!(
                "order = {order}: allowed 0 or 1"
            )))
        }
    };
    Ok(x.as_array().mapv(f).into_pyarray(py))
}
