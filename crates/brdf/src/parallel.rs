//! Building independent table rows on all cores (with `std`), or in turn.
//!
//! Table builds (the full-GHS S̃ table, the two-scale D_eff table) are the
//! start-up cost of a scene; their rows are independent, so with the `std`
//! feature they are spread over `std::thread::available_parallelism()`
//! scoped threads. Each row is computed by the same code from the same
//! inputs whichever thread runs it, so the table is bit-identical to a
//! sequential build. Without `std` the rows are built in order.

use alloc::vec::Vec;

/// `(0..n).map(f).collect()`, with the calls spread over the available cores
/// when the `std` feature is on. Threads take the next row from a shared
/// counter, because rows differ in cost (contiguous blocks left one core
/// idle for up to a third of a two-scale or GHS build). The calling thread
/// is one of the workers: a table build fans out several times, and each
/// spawned thread costs tens of microseconds.
pub(crate) fn map_rows<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    #[cfg(feature = "std")]
    {
        use core::sync::atomic::{AtomicUsize, Ordering};
        let threads = cores().min(n);
        if threads > 1 {
            let next = AtomicUsize::new(0);
            let (f, next) = (&f, &next);
            let work = move || {
                let mut done = Vec::new();
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= n {
                        break done;
                    }
                    done.push((i, f(i)));
                }
            };
            let parts: Vec<Vec<(usize, T)>> = std::thread::scope(|s| {
                let handles: Vec<_> = (1..threads).map(|_| s.spawn(work)).collect();
                let mut parts = Vec::with_capacity(threads);
                parts.push(work());
                parts.extend(
                    handles
                        .into_iter()
                        .map(|h| h.join().expect("table row builder panicked")),
                );
                parts
            });
            let mut slots: Vec<Option<T>> = (0..n).map(|_| None).collect();
            for (i, v) in parts.into_iter().flatten() {
                slots[i] = Some(v);
            }
            return slots
                .into_iter()
                .map(|v| v.expect("every row is built once"))
                .collect();
        }
    }
    (0..n).map(f).collect()
}

/// The cores the process may use, asked once: `available_parallelism` reads
/// the cgroup quota files on every call (4 % of a full-GHS table build).
#[cfg(feature = "std")]
fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |t| t.get()))
}

#[cfg(test)]
mod tests {
    #[test]
    fn rows_come_back_in_order() {
        for n in [0, 1, 2, 3, 7, 64, 101] {
            let v = super::map_rows(n, |i| i * i);
            assert_eq!(v, (0..n).map(|i| i * i).collect::<alloc::vec::Vec<_>>());
        }
    }
}
