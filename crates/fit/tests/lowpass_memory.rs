//! Peak heap use of the two-scale low-pass. Its own test binary: the counting allocator
//! sees every allocation of the process, so nothing else may run beside it.

use fit::Topography;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded unchanged to the system allocator.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::SeqCst) + layout.size();
            PEAK.fetch_max(now, Ordering::SeqCst);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::SeqCst);
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

#[test]
fn gaussian_lowpass_needs_about_one_copy_of_the_map() {
    let n = 512;
    let t = Topography {
        nx: n,
        ny: n,
        dx: 1e-8,
        dy: 1e-8,
        heights: (0..n * n)
            .map(|i| ((i * 7919) % 1013) as f64 * 1e-9)
            .collect(),
        channel: "test".into(),
        format: "test",
    };
    let map_bytes = n * n * 8;
    let before = LIVE.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    let large = fit::two_scale::gaussian_lowpass(&t, 5e-7);
    let extra = PEAK.load(Ordering::SeqCst) - before;
    assert_eq!(large.heights.len(), n * n);
    // The result is one copy; the 2D complex FFT of the mirrored map with its transposes
    // needed 24 copies (192 bytes per point).
    assert!(
        extra < 2 * map_bytes,
        "low-pass of a {n}² map allocated {extra} bytes at peak, {:.1} bytes per point",
        extra as f64 / (n * n) as f64
    );
}
