//! The tension stage: from four ADC codes to the cable's 3-D pull on the drone.
//!
//! code -> volts -> raw cell force -> per-cell gain -> moving average -> static equilibrium
//! -> per-axis regression -> crossload compensation -> rotation into body FRD, plus flags.
//! Everything here is pure (no I/O, no clock) and allocation-free per sample; the iceoryx2
//! shell that feeds it lives in `taut`'s service runner.

pub mod calibration;
pub mod cells;
pub mod equilibrium;
pub mod filter;
mod stage;

pub use calibration::Calibration;
pub use cells::CellConversion;
pub use equilibrium::Geometry;
pub use filter::MovingAverage;
pub use stage::{TensionStage, TensionStageConfig};
