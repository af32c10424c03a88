//! taut's per-drone configuration (one TOML file per drone), its validation, and the
//! real-time setup every service applies at start: memory locking, SCHED_FIFO priority,
//! core pinning, and an absolute-deadline periodic loop with an overrun counter.

mod config;
mod controller_config;
mod estimator_config;
mod mission_config;
pub mod periodic;
mod px4_config;
mod recorder_config;
pub mod rt;
mod validate;

pub use config::*;
pub use controller_config::*;
pub use estimator_config::*;
pub use mission_config::*;
pub use px4_config::*;
pub use recorder_config::*;
pub use validate::ConfigError;
