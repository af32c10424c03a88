//! The fixed-size samples that cross process boundaries in taut, and their service names.
//!
//! Every sample is `#[repr(C)]`, `Copy`, free of pointers and starts with a [`Header`], like a
//! PX4 uORB message: it can be placed in iceoryx2 shared memory as it is, and any stage can tell
//! the age of what it acts on. Times are CLOCK_MONOTONIC nanoseconds (system-wide on Linux, so
//! comparable between processes on one computer; `rt_config::periodic::now_ns` reads it).
//!
//! Frames: NED (inertial) and FRD (body), as PX4 uses them; the force sensor's own frame `S` is
//! described on [`TensionSample`].

mod flight;
pub mod names;
mod samples;
mod truth;

pub use flight::*;
pub use samples::*;
pub use truth::*;
