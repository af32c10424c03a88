//! The plant's configuration: physics, the emulated PX4's parameters, the perturbation and the
//! sensors' noise. Every section has PX4's or the paper's defaults; a TOML file may override
//! any key (`deny_unknown_fields` everywhere).

use serde::Deserialize;

use crate::commander::CommanderParams;
use crate::estimator::{EstimatorParams, ImuParams, PerturbationParams};
use crate::inner_loops::InnerLoopParams;
use crate::physics::WorldParams;

/// Everything that defines a plant run besides the scenario.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlantConfig {
    /// Seed of every random process; drone `k` derives its own streams from it.
    pub seed: u64,
    /// The motion-capture position perturbation (paper V.C) on or off.
    pub perturbation_enabled: bool,
    /// Physics step, s. RK4 at 0.5 ms keeps the 1500 N/m cables and the contacts stable and
    /// the energy honest (see `physics`).
    pub physics_dt_s: f64,
    /// PX4's rate loop (and attitude loop, estimator prediction, commander), Hz. Must divide
    /// the physics rate.
    pub rate_loop_hz: f64,
    /// Crash check: a drone's reach (arm plus propeller), m, against obstacles.
    pub drone_radius_m: f64,
    /// Crash check: vertical speed at ground contact above which a landing is a crash, m/s.
    pub crash_speed_m_s: f64,
    pub physics: WorldParams,
    pub inner_loops: InnerLoopParams,
    pub commander: CommanderParams,
    pub perturbation: PerturbationParams,
    pub estimator: EstimatorParams,
    pub imu: ImuParams,
}

impl Default for PlantConfig {
    fn default() -> Self {
        PlantConfig {
            seed: 1,
            perturbation_enabled: true,
            physics_dt_s: 0.0005,
            rate_loop_hz: 400.0,
            drone_radius_m: 0.35,
            crash_speed_m_s: 2.0,
            physics: WorldParams::default(),
            inner_loops: InnerLoopParams::default(),
            commander: CommanderParams::default(),
            perturbation: PerturbationParams::default(),
            estimator: EstimatorParams::default(),
            imu: ImuParams::default(),
        }
    }
}

impl PlantConfig {
    /// Physics steps per rate-loop tick; errors name the key.
    pub fn steps_per_tick(&self) -> Result<u64, String> {
        let ratio = 1.0 / (self.physics_dt_s * self.rate_loop_hz);
        if !(self.physics_dt_s > 0.0 && self.rate_loop_hz > 0.0 && ratio.is_finite()) {
            return Err(format!(
                "physics_dt_s = {} and rate_loop_hz = {} must be positive",
                self.physics_dt_s, self.rate_loop_hz
            ));
        }
        let n = ratio.round();
        if n < 1.0 || (ratio - n).abs() > 1e-6 {
            return Err(format!(
                "rate_loop_hz = {}: the physics rate 1/{} s must be a whole multiple of it",
                self.rate_loop_hz, self.physics_dt_s
            ));
        }
        Ok(n as u64)
    }
}
