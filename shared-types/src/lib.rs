//! The fixed-size samples that cross process boundaries in taut, and their service names.
//!
//! Every sample is `#[repr(C)]`, `Copy`, free of pointers and starts with a [`Header`], like a
//! PX4 uORB message: it can be placed in iceoryx2 shared memory as it is, and any stage can tell
//! the age of what it acts on. Times are CLOCK_MONOTONIC nanoseconds (system-wide on Linux, so
//! comparable between processes on one computer).
//!
//! Frames: NED (inertial) and FRD (body), as PX4 uses them; the force sensor's own frame `S` is
//! described on [`TensionSample`].

pub mod names;
mod samples;

pub use samples::*;

/// CLOCK_MONOTONIC now, in nanoseconds. The one clock every header uses.
///
/// This is the only clock read in this crate; pure step functions never call it, their shells do.
pub fn monotonic_ns() -> u64 {
    let mut ts = libc_timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes into the timespec we pass and has no other effect.
    unsafe { clock_gettime(CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

#[repr(C)]
struct libc_timespec {
    tv_sec: i64,
    tv_nsec: i64,
}
const CLOCK_MONOTONIC: i32 = 1;
extern "C" {
    fn clock_gettime(clk_id: i32, tp: *mut libc_timespec) -> i32;
}
