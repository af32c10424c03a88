//! Latency measurement for taut's pipelines.
//!
//! - [`SpanHistograms`]: one HDR histogram per measured span (a hop between two stamps of the
//!   sample headers, or end to end), allocated up front so recording in a loop never allocates.
//! - [`ramp_lag`]: how far a force reading lags the true force, when the true force is a known
//!   piecewise-linear profile: the time at which the truth had the value that was read,
//!   subtracted from the time the reading was published. This is the physical filter budget
//!   (conversion window + moving average) plus all the software in between.

mod lag;
mod spans;

pub use lag::{ramp_lag, triangle_wave};
pub use spans::{Percentiles, SpanHistograms};
