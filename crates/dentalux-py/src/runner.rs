//! Run a core computation off the Python thread: the GIL is released, Ctrl-C (a pending
//! signal) cancels the computation promptly, a progress callback sees finished work, and a
//! panic becomes a Python `RuntimeError` instead of taking the interpreter down.

use dentalux_core::control::Control;
use dentalux_core::Error;
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Condvar, Mutex, PoisonError};
use std::time::Duration;

/// Map a core error to the Python exception a user expects.
pub fn to_py_err(e: Error) -> PyErr {
    match e {
        Error::InvalidInput(msg) => PyValueError::new_err(msg),
        Error::Cancelled => PyKeyboardInterrupt::new_err("cancelled"),
    }
}

/// Run `work` on a worker thread with `threads` rayon threads (None: all cores), polling
/// for signals and reporting `control.done()` to `progress` about ten times a second.
pub fn run<T, F>(
    py: Python<'_>,
    threads: Option<usize>,
    progress: Option<PyObject>,
    work: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Control) -> dentalux_core::Result<T> + Send,
{
    if threads == Some(0) {
        return Err(PyValueError::new_err(
            "threads = 0 is out of range: allowed ≥ 1",
        ));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start threads: {e}")))?;
    let control = Control::new();
    let mut py_error: Option<PyErr> = None;
    // the worker says when it ends, so that the end is seen at once (not at the next poll)
    // and the waiting thread sleeps between its checks instead of waking the CPUs
    let ended = (Mutex::new(false), Condvar::new());
    let outcome = std::thread::scope(|s| {
        let handle = s.spawn(|| {
            let out = catch_unwind(AssertUnwindSafe(|| pool.install(|| work(&control))));
            *ended.0.lock().unwrap_or_else(PoisonError::into_inner) = true;
            ended.1.notify_all();
            out
        });
        loop {
            let finished = py.allow_threads(|| {
                let done = ended.0.lock().unwrap_or_else(PoisonError::into_inner);
                let wait = ended
                    .1
                    .wait_timeout_while(done, Duration::from_millis(100), |d| !*d);
                *wait.unwrap_or_else(PoisonError::into_inner).0
            });
            if finished {
                break;
            }
            if py_error.is_some() {
                continue;
            }
            if let Err(e) = py.check_signals() {
                control.cancel();
                py_error = Some(e);
                continue;
            }
            if let Some(cb) = &progress {
                if let Err(e) = cb.call1(py, (control.done(),)) {
                    control.cancel();
                    py_error = Some(e);
                }
            }
        }
        handle.join()
    });
    if let Some(e) = py_error {
        return Err(e);
    }
    match outcome {
        Ok(Ok(result)) => result.map_err(to_py_err),
        Ok(Err(panic)) | Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            Err(PyRuntimeError::new_err(format!(
                "internal error in dentalux core: {msg}"
            )))
        }
    }
}
