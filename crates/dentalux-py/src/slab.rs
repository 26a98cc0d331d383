//! Binding of the slab simulator and of the phase functions (for tests and plots).

use crate::runner;
use dentalux_core::instrument::{Window, WINDOW_KEYS};
use dentalux_core::integrators::slab::{
    simulate_all, simulate_with, BackingOrders, Estimator, Incidence, SlabConfig, SlabLayer,
    SCALAR_KEYS,
};
use dentalux_core::integrators::slab_spectral::{simulate_spectral, SpectralConfig};
use dentalux_core::medium::Medium;
use dentalux_core::phase::PhaseFunction;
use dentalux_core::rng::Stream;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Phase function from g, f_d and optional (weight, g) lobes; `name` prefixes errors.
pub fn phase_from(
    name: &str,
    g: f64,
    fd: f64,
    lobes: Option<Vec<(f64, f64)>>,
) -> PyResult<PhaseFunction> {
    PhaseFunction::from_params(g, fd, lobes.as_deref().unwrap_or_default())
        .map_err(|e| PyValueError::new_err(format!("{name}{e}")))
}

/// One layer as Python passes it: `dentalux.slab.Layer`'s fields in their order (mua, mus,
/// g, n, thickness, fd, lobes).
type LayerTuple = (f64, f64, f64, f64, f64, f64, Option<Vec<(f64, f64)>>);
/// An instrument window as Python passes it: (illuminated inner radius, illuminated radius,
/// viewed inner radius, viewed radius, specimen radius [mm], backing reflectance, detector
/// cone (low, high) [deg] or None). Inner radii 0 are discs; others make rings.
type WindowTuple = (f64, f64, f64, f64, f64, f64, Option<(f64, f64)>);

/// Simulate a layered slab; returns a dict of the results (see `dentalux.slab`).
#[pyfunction]
#[pyo3(signature = (layers, n_photons, seed, n_above=1.0, n_below=1.0, incidence="normal",
    angle_deg=0.0, estimator="analog", threads=None, band=0, radial=None, angular_bins=None,
    window=None, progress=None, lanes=true))]
#[allow(clippy::too_many_arguments)]
pub fn slab_simulate<'py>(
    py: Python<'py>,
    layers: Vec<LayerTuple>,
    n_photons: u64,
    seed: u64,
    n_above: f64,
    n_below: f64,
    incidence: &str,
    angle_deg: f64,
    estimator: &str,
    threads: Option<usize>,
    band: u64,
    radial: Option<(usize, f64)>,
    angular_bins: Option<usize>,
    window: Option<WindowTuple>,
    progress: Option<PyObject>,
    lanes: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let stack = stack_from(layers, "")?;
    let incidence = Incidence::parse(incidence, angle_deg).map_err(runner::to_py_err)?;
    let estimator = Estimator::parse(estimator).map_err(runner::to_py_err)?;
    let cfg = SlabConfig {
        layers: stack,
        n_above,
        n_below,
        incidence,
        estimator,
        n_photons,
        seed,
        band,
        radial,
        angular_bins,
        window: window.map(window_from),
        backing_orders: None,
    };
    cfg.validate().map_err(runner::to_py_err)?;
    let res = runner::run(py, threads, progress, |c| simulate_with(&cfg, c, lanes))?;
    let out = PyDict::new(py);
    let err = PyDict::new(py);
    for (i, k) in SCALAR_KEYS.iter().enumerate() {
        out.set_item(*k, res.values[i])?;
        err.set_item(*k, res.stderr[i])?;
    }
    out.set_item("stderr", err)?;
    out.set_item("absorbed_per_layer", res.absorbed_per_layer)?;
    out.set_item("photons", res.photons)?;
    out.set_item("walk", if res.lanes { "lanes" } else { "scalar" })?;
    out.set_item("radial_reflectance", res.radial_reflectance)?;
    out.set_item("radial_transmittance", res.radial_transmittance)?;
    out.set_item("angular_reflectance", res.angular_reflectance)?;
    out.set_item("angular_transmittance", res.angular_transmittance)?;
    if cfg.window.is_some() {
        let win = PyDict::new(py);
        let win_err = PyDict::new(py);
        for (i, k) in WINDOW_KEYS.iter().enumerate() {
            win.set_item(*k, res.window[i])?;
            win_err.set_item(*k, res.window_stderr[i])?;
        }
        out.set_item("window", win)?;
        out.set_item("window_stderr", win_err)?;
    }
    Ok(out)
}

/// The core's window from Python's tuple (cone in degrees).
fn window_from((a0, a, b0, b, rs, backing, cone): WindowTuple) -> Window {
    Window {
        illuminated_radius: a,
        illuminated_inner_radius: a0,
        viewed_radius: b,
        viewed_inner_radius: b0,
        specimen_radius: rs,
        backing,
        cone: cone.map(|(lo, hi)| (lo.to_radians(), hi.to_radians())),
    }
}

/// Layers of one stack, checked, with `name` prefixing errors.
fn stack_from(layers: Vec<LayerTuple>, prefix: &str) -> PyResult<Vec<SlabLayer>> {
    let mut stack = Vec::with_capacity(layers.len());
    for (i, (mua, mus, g, n, thickness, fd, lobes)) in layers.into_iter().enumerate() {
        let name = format!("{prefix}layers[{i}].");
        let phase = phase_from(&name, g, fd, lobes)?;
        let medium = Medium::new(&name, mua, mus, n, phase).map_err(runner::to_py_err)?;
        stack.push(SlabLayer { medium, thickness });
    }
    Ok(stack)
}

/// Read a specimen through an instrument window in every band at once, tallying the window
/// by backing order (`dentalux.reading`): one stack per band, each band's stream keyed by
/// `band_keys`. Returns `order_sums` as an array (bands, replicates, orders + 1, window
/// keys), `batch_photons` (photons per replicate) and `truncated` (per band).
#[pyfunction]
#[pyo3(signature = (bands, band_keys, n_photons, seed, window, max_order, survival,
    n_above=1.0, n_below=1.0, incidence="normal", angle_deg=0.0, estimator="weighted",
    threads=None, progress=None, past_rim_only=false))]
#[allow(clippy::too_many_arguments)]
pub fn slab_read_bands<'py>(
    py: Python<'py>,
    bands: Vec<Vec<LayerTuple>>,
    band_keys: Vec<u64>,
    n_photons: u64,
    seed: u64,
    window: WindowTuple,
    max_order: usize,
    survival: f64,
    n_above: f64,
    n_below: f64,
    incidence: &str,
    angle_deg: f64,
    estimator: &str,
    threads: Option<usize>,
    progress: Option<PyObject>,
    past_rim_only: bool,
) -> PyResult<Bound<'py, PyDict>> {
    if bands.len() != band_keys.len() || bands.is_empty() {
        return Err(PyValueError::new_err(
            "bands and band_keys: one stream key per band, at least one band",
        ));
    }
    let incidence = Incidence::parse(incidence, angle_deg).map_err(runner::to_py_err)?;
    let estimator = Estimator::parse(estimator).map_err(runner::to_py_err)?;
    // the backing is the polynomial's variable: the walk's own is unused
    let window = Window {
        backing: 0.0,
        ..window_from(window)
    };
    let mut cfgs = Vec::with_capacity(bands.len());
    for (k, (layers, key)) in bands.into_iter().zip(band_keys).enumerate() {
        cfgs.push(SlabConfig {
            layers: stack_from(layers, &format!("bands[{k}]."))?,
            n_above,
            n_below,
            incidence,
            estimator,
            n_photons,
            seed,
            band: key,
            radial: None,
            angular_bins: None,
            window: Some(window),
            backing_orders: Some(BackingOrders {
                max_order,
                survival,
                past_rim_only,
            }),
        });
    }
    for cfg in &cfgs {
        cfg.validate().map_err(runner::to_py_err)?;
    }
    let results = runner::run(py, threads, progress, |c| simulate_all(&cfgs, c))?;
    let n_bands = results.len();
    let n_batches = results[0].batch_photons.len();
    let sums: Vec<f64> = results
        .iter()
        .flat_map(|r| r.order_sums.iter().copied())
        .collect();
    let shape = [n_bands, n_batches, max_order + 1, WINDOW_KEYS.len()];
    let out = PyDict::new(py);
    out.set_item("order_sums", PyArray1::from_vec(py, sums).reshape(shape)?)?;
    out.set_item("batch_photons", results[0].batch_photons.clone())?;
    out.set_item(
        "truncated",
        results.iter().map(|r| r.truncated).collect::<Vec<_>>(),
    )?;
    out.set_item("window_keys", WINDOW_KEYS.to_vec())?;
    Ok(out)
}

/// Read a specimen through an instrument window in every band from shared walks (a hero
/// band per photon, `dentalux.reading`): one stack per band, the same thicknesses and
/// indices in all. Returns `order_sums` as an array (replicates, bands, orders + 1, window
/// keys), `replicate_photons`, `truncated` (per band) and `concentration`.
#[pyfunction]
#[pyo3(signature = (bands, n_photons, seed, key, window, max_order, survival, n_above=1.0,
    n_below=1.0, incidence="normal", angle_deg=0.0, threads=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn slab_read_spectral<'py>(
    py: Python<'py>,
    bands: Vec<Vec<LayerTuple>>,
    n_photons: u64,
    seed: u64,
    key: u64,
    window: WindowTuple,
    max_order: usize,
    survival: f64,
    n_above: f64,
    n_below: f64,
    incidence: &str,
    angle_deg: f64,
    threads: Option<usize>,
    progress: Option<PyObject>,
) -> PyResult<Bound<'py, PyDict>> {
    let incidence = Incidence::parse(incidence, angle_deg).map_err(runner::to_py_err)?;
    let n_bands = bands.len();
    let mut stacks = Vec::with_capacity(n_bands);
    for (k, layers) in bands.into_iter().enumerate() {
        stacks.push(stack_from(layers, &format!("bands[{k}]."))?);
    }
    let cfg = SpectralConfig {
        bands: stacks,
        n_above,
        n_below,
        incidence,
        n_photons,
        seed,
        key,
        window: Window {
            backing: 0.0,
            ..window_from(window)
        },
        orders: BackingOrders {
            max_order,
            survival,
            past_rim_only: false,
        },
    };
    cfg.validate().map_err(runner::to_py_err)?;
    let res = runner::run(py, threads, progress, |c| simulate_spectral(&cfg, c))?;
    let shape = [
        res.replicate_photons.len(),
        n_bands,
        max_order + 1,
        WINDOW_KEYS.len(),
    ];
    let out = PyDict::new(py);
    out.set_item(
        "order_sums",
        PyArray1::from_vec(py, res.sums).reshape(shape)?,
    )?;
    out.set_item("replicate_photons", res.replicate_photons)?;
    out.set_item("truncated", res.truncated)?;
    out.set_item("concentration", res.concentration)?;
    Ok(out)
}

/// Draw `n` cosines from a phase function (for statistical tests from Python).
#[pyfunction]
#[pyo3(signature = (n, g, fd=0.0, lobes=None, seed=0))]
pub fn phase_sample_cos(
    n: usize,
    g: f64,
    fd: f64,
    lobes: Option<Vec<(f64, f64)>>,
    seed: u64,
) -> PyResult<Vec<f64>> {
    let p = phase_from("", g, fd, lobes)?;
    let mut rng = Stream::new(seed, 0, 0);
    Ok((0..n).map(|_| p.sample_cos(rng.uniform2())).collect())
}

/// Evaluate a phase function [1/sr] at the given cosines.
#[pyfunction]
#[pyo3(signature = (cos_theta, g, fd=0.0, lobes=None))]
pub fn phase_eval(
    cos_theta: Vec<f64>,
    g: f64,
    fd: f64,
    lobes: Option<Vec<(f64, f64)>>,
) -> PyResult<Vec<f64>> {
    let p = phase_from("", g, fd, lobes)?;
    Ok(cos_theta.iter().map(|&c| p.eval(c)).collect())
}
