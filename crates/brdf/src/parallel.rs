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
/// when the `std` feature is on. Rows are assigned in contiguous blocks.
pub(crate) fn map_rows<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    #[cfg(feature = "std")]
    {
        let threads = std::thread::available_parallelism()
            .map_or(1, |t| t.get())
            .min(n);
        if threads > 1 {
            let chunk = n.div_ceil(threads);
            let f = &f;
            return std::thread::scope(|s| {
                let handles: Vec<_> = (0..threads)
                    .map(|t| {
                        s.spawn(move || {
                            (t * chunk..((t + 1) * chunk).min(n))
                                .map(f)
                                .collect::<Vec<T>>()
                        })
                    })
                    .collect();
                handles
                    .into_iter()
                    .flat_map(|h| h.join().expect("table row builder panicked"))
                    .collect()
            });
        }
    }
    (0..n).map(f).collect()
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
