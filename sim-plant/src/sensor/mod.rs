//! The emulated force sensor: a load profile pulls on the cable anchor, a model of the four
//! load cells and their amplifiers turns that into four analog voltages, four emulated
//! MCP3423s digitise them on an emulated I2C bus, and a Unix-socket link serves that bus to
//! the real sampler in another process.
//!
//! It is an independent model (it shares no code with the driver or the tension stage), so
//! those can be tested against it.
//!
//! - [`profile`]: [`LoadProfile`], the cable pull over time, from the CLI or a TOML/CSV file.
//! - [`params`], [`model`]: [`SensorParams`] and [`SensorModel`], geometry, analog chain and
//!   imperfections.
//! - [`mcp3423`]: [`Mcp3423`], the ADC as a pure state machine driven by timestamps.
//! - [`bus`]: [`SensorBus`], four chips, faults, counters, ground truth.
//! - [`link`]: [`BusServer`] and [`SimI2c`] (`embedded_hal::i2c::I2c`) over SOCK_SEQPACKET.

pub mod bus;
pub mod link;
mod link_sys;
pub mod mcp3423;
pub mod model;
pub mod params;
pub mod profile;

pub use bus::{BusConfig, BusConfigError, ChipCounters, Faults, ForcedInput, Nack, SensorBus};
pub use link::{monotonic_ns, BusServer, SimI2c, SimI2cError};
pub use mcp3423::{ConversionWindow, GeneralCall, Mcp3423};
pub use model::{split_cell_forces, tension_from_cells, SensorModel};
pub use params::{ParamsError, SensorParams};
pub use profile::{LoadProfile, ProfileError};
