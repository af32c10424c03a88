use serde::{Deserialize, Serialize};

use crate::{
    ControllerConfig, EstimatorConfig, MissionConfig, Px4Config, RecorderConfig, VehicleConfig,
};
use std::path::Path;

use crate::validate::{self, ConfigError};

/// The embedded default: a simulated drone `uav1` whose sensor is served by the emulator.
pub const EMBEDDED_SIM_CONFIG: &str = include_str!("../../configs/sim-uav1.toml");

/// One drone's whole configuration. Unknown keys anywhere are rejected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// Drone id; names its services `taut/<uav>/<topic>`. Letters, digits, `-`, `_`.
    pub uav: String,
    /// Prefix under which this drone's iceoryx2 services live (separates test runs). May be empty.
    #[serde(default)]
    pub ipc_root: String,
    pub sensor: SensorConfig,
    #[serde(default)]
    pub filter: FilterConfig,
    /// Absent means "not calibrated": nominal constants are used and every sample is flagged.
    #[serde(default)]
    pub calibration: Option<CalibrationConfig>,
    #[serde(default)]
    pub vehicle: VehicleConfig,
    #[serde(default)]
    pub controller: ControllerConfig,
    #[serde(default)]
    pub estimator: EstimatorConfig,
    #[serde(default)]
    pub px4: Px4Config,
    #[serde(default)]
    pub mission: MissionConfig,
    #[serde(default)]
    pub recorder: RecorderConfig,
    #[serde(default)]
    pub services: ServicesConfig,
    #[serde(default)]
    pub supervisor: SupervisorConfig,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SamplingModeConfig {
    /// Chips free-run at 240 SPS; the sampler reads each one every period.
    #[default]
    Continuous,
    /// A general-call one-shot starts all four conversions at once, every period.
    Synchronous,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    /// `/dev/i2c-N` on the Pi, or `sim:<socket path>` for the emulated bus.
    pub bus: String,
    /// 7-bit addresses of the chips of cells 1..4 (0x68..=0x6F, distinct).
    pub addresses: [u8; 4],
    #[serde(default)]
    pub mode: SamplingModeConfig,
    /// Frame rate of the sampler, Hz (the MCP3423 gives 240 SPS at 12 bits).
    #[serde(default = "default_rate_hz")]
    pub rate_hz: f64,
    /// How many times a failed bus transfer is retried within one period.
    #[serde(default = "default_bus_retries")]
    pub bus_retries: u32,
    /// Board centre to cell distance d0, m.
    #[serde(default = "default_d0")]
    pub d0_m: f64,
    /// Board centre to anchor distance h, m.
    #[serde(default = "default_h")]
    pub h_m: f64,
    /// Rotation from the sensor frame S to body FRD, row-major (identity: mounted aligned).
    #[serde(default = "identity3")]
    pub mounting_rotation: [[f64; 3]; 3],
    /// Flag a sample as near the lateral singularity when |T_z| < ratio * |T_xy|.
    #[serde(default = "default_singularity_ratio")]
    pub singularity_ratio: f64,
    #[serde(default)]
    pub cell: CellConfig,
}

/// Load cell and amplifier constants (nominal, before calibration).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellConfig {
    /// Rated capacity of one cell, N (5 kg).
    pub capacity_n: f64,
    /// Rated output at capacity, mV per V of excitation.
    pub sensitivity_mv_per_v: f64,
    pub excitation_v: f64,
    /// AD8293 fixed gain.
    pub amplifier_gain: f64,
    /// Reference on the amplifier's negative input: the at-rest output, V.
    pub reference_v: f64,
}

impl Default for CellConfig {
    fn default() -> Self {
        Self {
            capacity_n: 5.0 * 9.80665,
            sensitivity_mv_per_v: 1.0,
            excitation_v: 5.0,
            amplifier_gain: 160.0,
            reference_v: 0.5,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterConfig {
    /// Moving-average window in samples (4 at 240 Hz: 1.5 samples = 6.25 ms of lag).
    pub window: usize,
}

impl Default for FilterConfig {
    fn default() -> Self {
        Self { window: 4 }
    }
}

/// Written by `taut calibrate`. Applied in this order: cell gains, equilibrium, per-axis
/// polynomials, crossload matrix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    /// gamma_j = raw cell force / true cell force (paper III.C); corrected = raw / gamma_j.
    pub cell_gain: [f64; 4],
    /// Per-axis correction of the equilibrium force in S: T' = c0 + c1 T + c2 T^2 + c3 T^3.
    pub poly_x: [f64; 4],
    pub poly_y: [f64; 4],
    pub poly_z: [f64; 4],
    /// Crossload compensation, row-major: T'' = C T'.
    pub crossload: [[f64; 3]; 3],
}

impl CalibrationConfig {
    /// The calibration that changes nothing.
    pub fn identity() -> Self {
        Self {
            cell_gain: [1.0; 4],
            poly_x: [0.0, 1.0, 0.0, 0.0],
            poly_y: [0.0, 1.0, 0.0, 0.0],
            poly_z: [0.0, 1.0, 0.0, 0.0],
            crossload: identity3(),
        }
    }
}

/// What to do when the OS refuses a real-time setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RtPolicy {
    /// Report it and run without it (simulation, CI, a desk).
    #[default]
    Warn,
    /// Refuse to start (flight).
    Require,
}

/// Real-time settings of one service process.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ServiceRt {
    /// CPU core to pin the process to; none = let the OS choose.
    #[serde(default)]
    pub core: Option<usize>,
    /// SCHED_FIFO priority 1..=99; none = SCHED_OTHER.
    #[serde(default)]
    pub priority: Option<u8>,
    #[serde(default)]
    pub policy: RtPolicy,
    /// Lock all memory (mlockall) so page faults cannot stall the loop.
    #[serde(default)]
    pub lock_memory: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct ServicesConfig {
    #[serde(default)]
    pub adc_sampler: ServiceRt,
    #[serde(default)]
    pub tension: ServiceRt,
    #[serde(default)]
    pub controller: ServiceRt,
    #[serde(default)]
    pub px4_bridge: ServiceRt,
    #[serde(default)]
    pub mission: ServiceRt,
    #[serde(default)]
    pub force_estimator: ServiceRt,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OnDeath {
    /// Restart the dead service with exponential backoff, up to `max_restarts`.
    #[default]
    Restart,
    /// Stop every service and exit non-zero.
    StopAll,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupervisorConfig {
    pub on_death: OnDeath,
    /// First restart delay, doubled per consecutive death up to `backoff_max_s`.
    pub backoff_initial_s: f64,
    pub backoff_max_s: f64,
    /// After this many restarts of one service, stop everything.
    pub max_restarts: u32,
    /// A service that stayed up this long has its backoff reset.
    pub healthy_after_s: f64,
}

impl Default for SupervisorConfig {
    fn default() -> Self {
        Self {
            on_death: OnDeath::Restart,
            backoff_initial_s: 0.1,
            backoff_max_s: 5.0,
            max_restarts: 10,
            healthy_after_s: 10.0,
        }
    }
}

fn default_rate_hz() -> f64 {
    240.0
}
fn default_bus_retries() -> u32 {
    2
}
fn default_d0() -> f64 {
    0.03
}
fn default_h() -> f64 {
    0.03
}
fn default_singularity_ratio() -> f64 {
    0.25
}
/// The 3x3 identity, row-major.
pub fn identity3() -> [[f64; 3]; 3] {
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
}

impl Config {
    /// Parses and validates a config from TOML text. `origin` names the file in messages.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self, ConfigError> {
        let cfg: Config = toml::from_str(text).map_err(|e| ConfigError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        validate::validate(&cfg).map_err(|problem| ConfigError::Invalid {
            origin: origin.to_string(),
            problem,
        })?;
        Ok(cfg)
    }

    /// Reads, parses and validates a config file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError::Read {
            path: path.display().to_string(),
            source: e,
        })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// The embedded simulation default.
    pub fn embedded_sim() -> Self {
        Self::from_toml_str(EMBEDDED_SIM_CONFIG, "<embedded sim-uav1.toml>")
            .expect("the embedded config is validated by a unit test")
    }

    /// The effective config (defaults filled in) as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot print config: {e}\n"))
    }
}
