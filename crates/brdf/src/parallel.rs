//! Building independent table rows on all cores (with `std`), or in turn.
//!
//! Table builds (the full-GHS S̃ table, the two-scale D_eff table) are the
//! start-up cost of a scene; their rows are independent, so with the `std`
//! feature they are spread over rayon's global thread pool (the renderer's
//! and the Python package's pool too, so a table built inside their
//! parallel loops does not oversubscribe the cores). Each row is computed by
//! the same code from the same inputs whichever thread runs it, so the table
//! is bit-identical to a sequential build. Without `std` the rows are built
//! in order.

use alloc::vec::Vec;

/// `(0..n).map(f).collect()`, with the calls spread over rayon's pool when
/// the `std` feature is on. A build fans out four or five times in ~2 ms:
/// the pool's threads are woken, not spawned (a scoped thread cost 20–35 µs
/// a fan-out, 4–7 % of a full-GHS build), and they steal rows, which differ
/// in cost.
pub(crate) fn map_rows<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    #[cfg(feature = "std")]
    {
        use rayon::prelude::*;
        if n > 1 && rayon::current_num_threads() > 1 {
            let f = &f;
            return (0..n).into_par_iter().map(f).collect();
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
