//! Config of the model-based external-force estimator (the paper's baseline, MODEL.md
//! "Baselines"): f_ext = m a − T z_thrust from the accelerometer and the motor speeds.

use serde::{Deserialize, Serialize};

/// `[estimator]`: the estimator's model constants and filter. The vehicle mass is
/// `vehicle.mass_kg`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimatorConfig {
    /// Cut-off of the first-order low-pass applied identically to the accelerometer term and
    /// the thrust term, Hz.
    pub cutoff_hz: f64,
    /// Rotor thrust coefficient c_t: thrust of one rotor = c_t ω², N/(rad/s)² (X500 in PX4's
    /// Gazebo model: 8.54858e-6).
    pub thrust_coefficient_n_per_rad2_s2: f64,
    /// Motor speeds older than this (against the IMU sample) are flagged STALE_INPUT, s.
    pub motor_speeds_max_age_s: f64,
    /// An IMU gap longer than this re-seeds the filter (flagged INPUT_GAP), s.
    pub imu_max_gap_s: f64,
    /// Samples within this many filter time constants of a (re-)seed are flagged
    /// FILTER_WARMUP.
    pub warmup_time_constants: f64,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        Self {
            cutoff_hz: 10.0,
            thrust_coefficient_n_per_rad2_s2: 8.54858e-6,
            motor_speeds_max_age_s: 0.1,
            imu_max_gap_s: 0.1,
            warmup_time_constants: 3.0,
        }
    }
}

impl EstimatorConfig {
    /// Checks every key; the error names the first bad one (`estimator.cutoff_hz`, ...).
    pub fn validate(&self) -> Result<(), String> {
        for (key, v) in [
            ("estimator.cutoff_hz", self.cutoff_hz),
            (
                "estimator.thrust_coefficient_n_per_rad2_s2",
                self.thrust_coefficient_n_per_rad2_s2,
            ),
            (
                "estimator.motor_speeds_max_age_s",
                self.motor_speeds_max_age_s,
            ),
            ("estimator.imu_max_gap_s", self.imu_max_gap_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("key `{key}` = {v}: must be finite and > 0"));
            }
        }
        let w = self.warmup_time_constants;
        if !(w.is_finite() && w >= 0.0) {
            return Err(format!(
                "key `estimator.warmup_time_constants` = {w}: must be finite and >= 0"
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_errors_name_the_key() {
        EstimatorConfig::default().validate().unwrap();
        let c = EstimatorConfig {
            cutoff_hz: 0.0,
            ..Default::default()
        };
        assert!(c.validate().unwrap_err().contains("estimator.cutoff_hz"));
        let c = EstimatorConfig {
            thrust_coefficient_n_per_rad2_s2: f64::NAN,
            ..Default::default()
        };
        let e = c.validate().unwrap_err();
        assert!(
            e.contains("estimator.thrust_coefficient_n_per_rad2_s2"),
            "{e}"
        );
    }
}
