//! The model-based external-force estimator the paper compares its sensor against (MODEL.md
//! "Baselines"): from Newton's law of the drone, the force not explained by gravity and the
//! rotors' thrust is the cable's pull.
//!
//! # The estimate, in body FRD
//!
//! NED: m a = −T R e3 + m g e3 + f_ext, and the accelerometer reads the specific force
//! sf = Rᵀ (a − g e3) (body FRD). Hence, exactly and without the attitude:
//!
//! ```text
//! f_ext,FRD = Rᵀ f_ext = m sf + T e3,        T = Σ c_t ω_i²
//! ```
//!
//! The paper's form f_ext = m a_f − T_f z_body (NED) needs R to bring a to NED and back; in
//! body FRD both terms are already in one frame, so the attitude estimate's error and lag never
//! enter. Both terms go through the SAME first-order low-pass (cut-off
//! `estimator.cutoff_hz`, α = 1 − exp(−2π f_c dt), seeded by the first sample). The filter is
//! linear, so filtering the sum is filtering each term with identical filters: a thrust step
//! with the acceleration step it causes (in the same sample) gives no transient at all.
//!
//! # Rates and timing
//!
//! One estimate per IMU sample (`on_imu`), with the newest motor speeds held since their
//! arrival (`on_motor_speeds`); the paper had ~900 Hz accelerometer and ~60 Hz motor speeds.
//! The hold is the estimator's main dynamic error: between two ESC_STATUS messages a thrust
//! change shows in the accelerometer term only. dt comes from PX4's own IMU times
//! (`px4_time_us`), or from the receipt times when those do not advance.
//!
//! # Flags (`shared_types::tension_flags`) and safety
//!
//! - STALE_INPUT: the motor speeds are older than `motor_speeds_max_age_s` against the IMU
//!   sample's receipt (or none yet: the thrust is then taken as 0).
//! - FILTER_WARMUP: within `warmup_time_constants` filter time constants of a (re-)seed.
//! - INPUT_GAP: IMU samples were lost (sequence jump) or the IMU was silent for more than
//!   `imu_max_gap_s`; a silence re-seeds the filter.
//! - NON_FINITE: a non-finite accelerometer sample; the last finite estimate is repeated and
//!   the filter is untouched. Non-finite motor speeds are dropped (counted).
//!
//! The output's `force_body_n` is the estimated pull of the cable on the drone (body FRD, the
//! sensor's convention); `force_sensor_n` and `cell_force_n` are zero (there is no sensor
//! frame), `raw_sequence` is the IMU sample's sequence and `t_origin_ns` its receipt time.

pub mod shell;

use nalgebra::Vector3;
use rt_config::{EstimatorConfig, VehicleConfig};
use shared_types::{tension_flags, ImuSample, MotorSpeeds, TensionSample};

/// The config cannot drive an estimator; the message names the key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimatorParamsError {
    #[error("{0}")]
    Vehicle(String),
    #[error("{0}")]
    Estimator(String),
}

/// What the estimator has seen since `new`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EstimatorCounters {
    pub imu_samples: u64,
    pub motor_samples: u64,
    /// Estimates made with motor speeds too old (or none).
    pub stale_motor_estimates: u64,
    pub non_finite_imu: u64,
    pub non_finite_motors: u64,
    /// IMU sequence jumps and silences.
    pub imu_gaps: u64,
}

/// f_ext = m sf + T e3 (body FRD), low-passed. See the crate doc.
#[derive(Debug, Clone)]
pub struct ForceEstimator {
    mass_kg: f64,
    thrust_coefficient: f64,
    cutoff_hz: f64,
    motor_max_age_ns: u64,
    imu_max_gap_ns: u64,
    warmup_ns: u64,
    /// Newest finite motor speeds: (receipt time ns, total thrust N).
    thrust: Option<(u64, f64)>,
    filtered: Vector3<f64>,
    /// Time of the last IMU sample used: (PX4 µs, receipt ns, sequence).
    last_imu: Option<(u64, u64, u64)>,
    seeded_at_ns: u64,
    counters: EstimatorCounters,
}

impl ForceEstimator {
    pub fn new(
        vehicle: &VehicleConfig,
        cfg: &EstimatorConfig,
    ) -> Result<Self, EstimatorParamsError> {
        vehicle.validate().map_err(EstimatorParamsError::Vehicle)?;
        cfg.validate().map_err(EstimatorParamsError::Estimator)?;
        let tau_s = 1.0 / (2.0 * std::f64::consts::PI * cfg.cutoff_hz);
        let ns = |s: f64| (s * 1e9).round() as u64;
        Ok(Self {
            mass_kg: vehicle.mass_kg,
            thrust_coefficient: cfg.thrust_coefficient_n_per_rad2_s2,
            cutoff_hz: cfg.cutoff_hz,
            motor_max_age_ns: ns(cfg.motor_speeds_max_age_s),
            imu_max_gap_ns: ns(cfg.imu_max_gap_s),
            warmup_ns: ns(cfg.warmup_time_constants * tau_s),
            thrust: None,
            filtered: Vector3::zeros(),
            last_imu: None,
            seeded_at_ns: 0,
            counters: EstimatorCounters::default(),
        })
    }

    pub fn counters(&self) -> EstimatorCounters {
        self.counters
    }

    /// Total rotor thrust Σ c_t ω², N.
    pub fn thrust_n(&self, speeds_rad_s: &[f64; 4]) -> f64 {
        speeds_rad_s
            .iter()
            .map(|w| self.thrust_coefficient * w * w)
            .sum()
    }

    /// Holds the newest motor speeds until the next ones.
    pub fn on_motor_speeds(&mut self, m: &MotorSpeeds) {
        self.counters.motor_samples += 1;
        let thrust = self.thrust_n(&m.rotor_speed_rad_s);
        if thrust.is_finite() {
            self.thrust = Some((m.header.t_origin_ns, thrust));
        } else {
            self.counters.non_finite_motors += 1;
        }
    }

    /// One estimate from the IMU sample `imu` and the motor speeds held. Never panics, never
    /// allocates.
    pub fn on_imu(&mut self, imu: &ImuSample) -> TensionSample {
        self.counters.imu_samples += 1;
        let now_ns = imu.header.t_origin_ns;
        let mut flags = 0;
        let (thrust_at_ns, thrust_n) = self.thrust.unwrap_or((0, 0.0));
        if self.thrust.is_none() || now_ns.saturating_sub(thrust_at_ns) > self.motor_max_age_ns {
            flags |= tension_flags::STALE_INPUT;
            self.counters.stale_motor_estimates += 1;
        }
        let sf = Vector3::from(imu.specific_force_frd_m_s2);
        let raw = sf * self.mass_kg + Vector3::new(0.0, 0.0, thrust_n);
        if raw.iter().all(|v| v.is_finite()) {
            self.filter(imu, &raw, &mut flags);
        } else {
            flags |= tension_flags::NON_FINITE;
            self.counters.non_finite_imu += 1;
        }
        if now_ns.saturating_sub(self.seeded_at_ns) < self.warmup_ns {
            flags |= tension_flags::FILTER_WARMUP;
        }
        let mut out = TensionSample {
            force_body_n: self.filtered.into(),
            flags,
            raw_sequence: imu.header.sequence,
            ..Default::default()
        };
        out.header.t_origin_ns = now_ns;
        out
    }

    fn filter(&mut self, imu: &ImuSample, raw: &Vector3<f64>, flags: &mut u32) {
        let now = (imu.px4_time_us, imu.header.t_origin_ns, imu.header.sequence);
        let dt_ns = self.last_imu.map(|(us, ns, seq)| {
            if imu.header.sequence > seq + 1 {
                *flags |= tension_flags::INPUT_GAP;
                self.counters.imu_gaps += 1;
            }
            if imu.px4_time_us > us && us > 0 {
                (imu.px4_time_us - us) * 1000
            } else {
                now.1.saturating_sub(ns)
            }
        });
        self.last_imu = Some(now);
        match dt_ns {
            Some(dt) if dt <= self.imu_max_gap_ns => {
                let alpha =
                    1.0 - (-2.0 * std::f64::consts::PI * self.cutoff_hz * dt as f64 * 1e-9).exp();
                self.filtered += (raw - self.filtered) * alpha;
            }
            gap => {
                if gap.is_some() {
                    *flags |= tension_flags::INPUT_GAP;
                    self.counters.imu_gaps += 1;
                }
                self.filtered = *raw;
                self.seeded_at_ns = now.1;
            }
        }
    }
}

#[cfg(test)]
mod tests;
