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
//! equilibrium, `T' = poly_axis(T)`, `T'' = C T'`; the fit and the metrics use that same code
//! (the metrics run every frame through `tension::TensionStage`).
//!
//! # Choices worth knowing
//!
//! - Cell gains come from all three axis tests, not from z alone: on z, crossload and gain
//!   errors are indistinguishable (details in [`fit`](mod@fit)).
//! - x/y polynomials are odd cubics about the zero reading, because only +x/+y are loaded on the
//!   bench and flight also sees -x/-y ([`LateralPoly`]).
//! - Non-linearity is the independent (best-fit line) kind; a linear z correction cannot change
//!   it, so the paper's "1 -> 0.5 %FS after a linear regression" is not reproducible with that
//!   definition. The emulated sensor of [`synthetic`] therefore carries its ~1 %FS
//!   non-linearity on the lateral axes (corrected by the cubics) and keeps z nearly linear.
//! - The lateral full scale is limited by the amplifiers' compression headroom (5.0 kg with the
//!   default geometry, see [`synthetic`]); FS of each axis is its heaviest recorded weight.

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
