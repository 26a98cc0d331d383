//! Bessel functions of the first kind, J0 and J1, elementwise over numpy arrays: the
//! layered solver's window kernels need them (the Hankel transforms of discs), and taking
//! libm's (the FreeBSD msun algorithms, within about 1e-16 of scipy's cephes ones) spares a
//! reading the import of scipy.special.

use numpy::{IntoPyArray, PyArrayDyn, PyReadonlyArrayDyn};
use pyo3::prelude::*;

/// J0(x) for every element of `x`.
#[pyfunction]
pub fn bessel_j0<'py>(
    py: Python<'py>,
    x: PyReadonlyArrayDyn<'py, f64>,
) -> Bound<'py, PyArrayDyn<f64>> {
    x.as_array().mapv(libm::j0).into_pyarray(py)
}

/// J1(x) for every element of `x`.
#[pyfunction]
pub fn bessel_j1<'py>(
    py: Python<'py>,
    x: PyReadonlyArrayDyn<'py, f64>,
) -> Bound<'py, PyArrayDyn<f64>> {
    x.as_array().mapv(libm::j1).into_pyarray(py)
}
