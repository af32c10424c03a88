//! Force-sensor calibration (paper III.C): from a static bench recording to the
//! `[calibration]` table the tension stage applies, with the paper's performance indexes before
//! and after, as a report and box plots.
//!
//! - [`recording`]: the CSV recording format (one row per raw frame), reader and writer.
//! - [`fit`](mod@fit): cell gains, per-axis polynomials, crossload matrix.
//! - [`metrics`] / [`report`]: hysteresis, non-linearity, repeatability, crossload (and error
//!   vs reference) in %FS per applied weight, through `tension::TensionStage`.
//! - [`plots`]: one box-plot PNG per metric.
//! - [`synthetic`]: the bench procedure on the emulated sensor (`sim_plant::sensor`).
//! - [`run()`]: the whole thing, for `taut calibrate`.
//!
//! The calibration is applied exactly as `tension::Calibration` does: `f_j = raw_j / gamma_j`,
//! equilibrium, `T' = poly_axis(T)`, `T'' = C T'`; the fit evaluates it with the same code.

pub mod fit;
mod lsq;
pub mod metrics;
pub mod plots;
pub mod recording;
pub mod report;
mod run;
pub mod synthetic;

pub use fit::{fit, FitError, FitOptions, LateralPoly};
pub use metrics::{MetricKind, Metrics};
pub use plots::PlotOptions;
pub use recording::{Axis, Direction, Recording, RecordingError, Step};
pub use report::Report;
pub use run::{
    calibration_toml, run, write_config_with_calibration, CalibrateError, CalibrateOptions,
    CalibrateOutcome,
};
pub use synthetic::{Synthetic, SyntheticOptions};
