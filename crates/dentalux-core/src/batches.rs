//! Batches of photons on the rayon pool, handed out one at a time.
//!
//! A run is cut into batches, each with its own random stream keyed by its index, so its
//! numbers do not depend on which thread ran which batch. One worker per thread takes the
//! batches from a shared counter, the next as soon as it is done, so a thread that runs
//! slower (its CPU busy with something else) takes fewer. A parallel iterator's split gives
//! each thread a fixed share up front and leaves the faster one idle at the end; split into
//! single batches, its speed varied widely from run to run
//! (docs/notes/2026-12-07-threads-and-start-up.md has the measurements).

use crate::Result;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// `run(b)` for every batch `b` in `0..n`, on the current rayon pool, with the results in
/// batch order. After the first error no batch is started, and that error is returned.
pub fn in_order<T, F>(n: u64, run: F) -> Result<Vec<T>>
where
    T: Send,
    F: Fn(u64) -> Result<T> + Sync,
{
    let next = AtomicU64::new(0);
    let failed = AtomicBool::new(false);
    let workers = (rayon::current_num_threads() as u64).clamp(1, n.max(1));
    let parts: Vec<Result<Vec<(u64, T)>>> = (0..workers)
        .into_par_iter()
        .map(|_| {
            let mut mine = Vec::new();
            while !failed.load(Ordering::Relaxed) {
                let b = next.fetch_add(1, Ordering::Relaxed);
                if b >= n {
                    break;
                }
                match run(b) {
                    Ok(t) => mine.push((b, t)),
                    Err(e) => {
                        failed.store(true, Ordering::Relaxed);
                        return Err(e);
                    }
                }
            }
            Ok(mine)
        })
        .collect();
    let mut all = Vec::with_capacity(n as usize);
    for part in parts {
        all.extend(part?);
    }
    all.sort_unstable_by_key(|(b, _)| *b);
    Ok(all.into_iter().map(|(_, t)| t).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
    }

    #[test]
    fn every_batch_once_in_order_on_any_pool() {
        for threads in [1, 2, 3, 8] {
            for n in [0, 1, 2, 7, 100] {
                let out = pool(threads).install(|| in_order(n, |b| Ok(b * b)));
                let want: Vec<u64> = (0..n).map(|b| b * b).collect();
                assert_eq!(
                    out.expect("no error"),
                    want,
                    "{threads} threads, {n} batches"
                );
            }
        }
    }

    #[test]
    fn an_error_stops_the_run_and_is_returned() {
        let started = AtomicU64::new(0);
        let out = pool(2).install(|| {
            in_order(10_000, |b| {
                started.fetch_add(1, Ordering::Relaxed);
                if b == 5 {
                    Err(Error::InvalidInput("batch 5".into()))
                } else {
                    std::thread::sleep(std::time::Duration::from_micros(50));
                    Ok(b)
                }
            })
        });
        assert!(matches!(out, Err(Error::InvalidInput(m)) if m == "batch 5"));
        // the other worker sees the failure within a batch or two of it
        assert!(started.load(Ordering::Relaxed) < 100);
    }
}
