//! Cooperative cancellation and progress: long loops poll a flag the caller can set
//! (Ctrl-C in Python) and add finished work to a counter the caller can display.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// Shared between a running computation and whoever watches it.
#[derive(Debug, Default)]
pub struct Control {
    cancel: AtomicBool,
    done: AtomicU64,
}

impl Control {
    /// A fresh control: not cancelled, nothing done.
    pub fn new() -> Self {
        Self::default()
    }
    /// Ask the computation to stop at its next check.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
    /// Whether a stop was requested.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
    /// Record `n` more units of finished work.
    pub fn add_done(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }
    /// Units of work finished so far.
    pub fn done(&self) -> u64 {
        self.done.load(Ordering::Relaxed)
    }
    /// `Err(Cancelled)` once a stop was requested.
    pub fn check(&self) -> crate::Result<()> {
        if self.is_cancelled() {
            Err(crate::Error::Cancelled)
        } else {
            Ok(())
        }
    }
}
