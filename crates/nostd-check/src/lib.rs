//! Proof that `brdf` builds without `std`: this staticlib is `#![no_std]` and
//! supplies its own panic handler, so any dependency that links `std` fails
//! with a duplicate `panic_impl` lang item. Build it with
//! `RUSTFLAGS="-C panic=abort" cargo build -p nostd-check` (see `.ci/run`).
#![no_std]

extern crate alloc;

use core::alloc::{GlobalAlloc, Layout};

/// Never actually called: the check only links.
struct NullAlloc;

unsafe impl GlobalAlloc for NullAlloc {
    unsafe fn alloc(&self, _layout: Layout) -> *mut u8 {
        core::ptr::null_mut()
    }
    unsafe fn dealloc(&self, _ptr: *mut u8, _layout: Layout) {}
}

#[global_allocator]
static ALLOC: NullAlloc = NullAlloc;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}

/// Evaluates a GGX copper BRDF so the linker keeps the whole model path.
#[unsafe(no_mangle)]
pub extern "C" fn nostd_check_ggx(cos_i: f64, cos_o: f64, lambda_nm: f64) -> f64 {
    brdf::nostd_smoke(cos_i, cos_o, lambda_nm)
}
