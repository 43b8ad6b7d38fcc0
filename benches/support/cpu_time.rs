//! CPU-time measurement shared by the criterion benches and the
//! error-vs-time harness (included with `#[path]`; each bench uses a part).
//!
//! The development machine is shared with builds, so wall-clock per-call
//! times include preemption; thread or process CPU time is what the code
//! itself costs.
#![allow(dead_code)]

use criterion::Throughput;
use criterion::measurement::{Measurement, ValueFormatter};

/// Linux clock id of the process CPU-time clock.
pub const PROCESS: i32 = 2;
/// Linux clock id of the calling thread's CPU-time clock.
pub const THREAD: i32 = 3;

/// Nanoseconds of CPU time of `clock` (Linux clock ids: 2 process, 3 thread).
#[cfg(target_os = "linux")]
pub fn cpu_ns(clock: i32) -> f64 {
    #[repr(C)]
    struct Timespec {
        sec: i64,
        nsec: i64,
    }
    unsafe extern "C" {
        fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
    }
    let mut t = Timespec { sec: 0, nsec: 0 };
    // SAFETY: `t` is a valid, writable timespec and `clock` a Linux CPU-time clock id.
    let rc = unsafe { clock_gettime(clock, &mut t) };
    assert_eq!(rc, 0, "clock_gettime({clock}) failed");
    t.sec as f64 * 1e9 + t.nsec as f64
}

/// Elsewhere, fall back to wall-clock time.
#[cfg(not(target_os = "linux"))]
pub fn cpu_ns(_clock: i32) -> f64 {
    use std::sync::OnceLock;
    static START: OnceLock<std::time::Instant> = OnceLock::new();
    START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_nanos() as f64
}

/// A criterion measurement reading a CPU-time clock, in ns.
pub struct Cpu(pub i32);

impl Measurement for Cpu {
    type Intermediate = f64;
    type Value = f64;
    fn start(&self) -> f64 {
        cpu_ns(self.0)
    }
    fn end(&self, start: f64) -> f64 {
        cpu_ns(self.0) - start
    }
    fn add(&self, a: &f64, b: &f64) -> f64 {
        a + b
    }
    fn zero(&self) -> f64 {
        0.0
    }
    fn to_f64(&self, v: &f64) -> f64 {
        *v
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        &Ns
    }
}

pub struct Ns;

impl ValueFormatter for Ns {
    fn scale_values(&self, typical: f64, values: &mut [f64]) -> &'static str {
        let (k, unit) = match typical {
            t if t < 1e3 => (1.0, "ns"),
            t if t < 1e6 => (1e-3, "µs"),
            t if t < 1e9 => (1e-6, "ms"),
            _ => (1e-9, "s"),
        };
        values.iter_mut().for_each(|v| *v *= k);
        unit
    }
    fn scale_throughputs(
        &self,
        _typical: f64,
        throughput: &Throughput,
        values: &mut [f64],
    ) -> &'static str {
        let n = match *throughput {
            Throughput::Bytes(n)
            | Throughput::BytesDecimal(n)
            | Throughput::Elements(n)
            | Throughput::Bits(n) => n as f64,
            Throughput::ElementsAndBytes { elements, .. } => elements as f64,
        };
        values.iter_mut().for_each(|v| *v = n * 1e9 / *v);
        "elem/s (CPU)"
    }
    fn scale_for_machines(&self, _values: &mut [f64]) -> &'static str {
        "ns"
    }
}
