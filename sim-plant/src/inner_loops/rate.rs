//! PX4's multicopter rate controller (mc_rate_control with `RateControl`).
//!
//! Followed: PX4-Autopilot src/lib/rate_control/rate_control.cpp (the PID and its integrator)
//! and, for what wraps it, mc_rate_control/MulticopterRateControl.cpp and
//! src/modules/sensors/vehicle_angular_velocity/VehicleAngularVelocity.cpp (read as
//! excerpts from the code index):
//!
//! - The measured rate goes through a 2nd-order low-pass at IMU_GYRO_CUTOFF (40 Hz); the
//!   angular acceleration is the difference quotient of the unfiltered rate through a
//!   2nd-order low-pass at IMU_DGYRO_CUTOFF (20 Hz). PX4 runs both at the gyro rate; here they
//!   run at the loop rate (1/dt, nominally 400 Hz) and are re-tuned when dt changes by > 5 %.
//! - `torque = P (sp - rate) + I_state - D accel + FF sp`: D acts on the measured angular
//!   acceleration, not on the error, so a setpoint step gives no derivative kick.
//! - Integrator: not updated while landed; per axis, the error is clipped to the sign that
//!   unsaturates an actuator the allocation flagged as saturated in that direction; the I
//!   gain fades with large errors (`1 - (e / 400 deg/s)^2`); the state is clamped to
//!   MC_*R_INT_LIM (0.3).
//! - Gains in PX4's "ideal" form: P, I, D each multiplied by MC_*RATE_K (1).
//! - The yaw torque goes through PX4's first-order low-pass MC_YAW_TQ_CUTOFF (2 Hz, v1.16
//!   default); 0 disables it.
//! - dt is constrained to [0.125 ms, 20 ms] as MulticopterRateControl does.
//!
//! Output: normalized torque setpoint (body FRD), clamped to [-1, 1] per axis.

use nalgebra::Vector3;
use serde::Deserialize;

use super::errors::{check_dt, check_finite3, check_non_negative, check_positive};
use super::errors::{ParamsError, StepError};
use super::filters::{AlphaFilter, LowPassFilter2p};

/// Rate controller parameters, per axis `[roll, pitch, yaw]`; defaults are PX4 v1.16's.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RateControlParams {
    /// MC_ROLLRATE_P, MC_PITCHRATE_P, MC_YAWRATE_P. Default [0.15, 0.15, 0.2].
    pub p: [f64; 3],
    /// MC_*RATE_I. Default [0.2, 0.2, 0.1].
    pub i: [f64; 3],
    /// MC_*RATE_D. Default [0.003, 0.003, 0.0].
    pub d: [f64; 3],
    /// MC_*RATE_FF. Default [0, 0, 0].
    pub ff: [f64; 3],
    /// MC_*RATE_K, overall gain on P, I and D. Default [1, 1, 1].
    pub k: [f64; 3],
    /// MC_RR_INT_LIM, MC_PR_INT_LIM, MC_YR_INT_LIM. Default [0.3, 0.3, 0.3].
    pub integrator_limit: [f64; 3],
    /// IMU_GYRO_CUTOFF, Hz. Default 40.
    pub gyro_cutoff_hz: f64,
    /// IMU_DGYRO_CUTOFF (D-term filter), Hz. Default 20.
    pub dgyro_cutoff_hz: f64,
    /// MC_YAW_TQ_CUTOFF, Hz; 0 disables. Default 2.
    pub yaw_torque_cutoff_hz: f64,
    /// Nominal loop rate the filters are designed for, Hz. Default 400.
    pub loop_rate_hz: f64,
}

impl Default for RateControlParams {
    fn default() -> Self {
        RateControlParams {
            p: [0.15, 0.15, 0.2],
            i: [0.2, 0.2, 0.1],
            d: [0.003, 0.003, 0.0],
            ff: [0.0; 3],
            k: [1.0; 3],
            integrator_limit: [0.3; 3],
            gyro_cutoff_hz: 40.0,
            dgyro_cutoff_hz: 20.0,
            yaw_torque_cutoff_hz: 2.0,
            loop_rate_hz: 400.0,
        }
    }
}

impl RateControlParams {
    /// Gains and limits finite and >= 0, loop rate > 0.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let per_axis: [(&'static str, &[f64; 3]); 6] = [
            ("rate.p", &self.p),
            ("rate.i", &self.i),
            ("rate.d", &self.d),
            ("rate.ff", &self.ff),
            ("rate.k", &self.k),
            ("rate.integrator_limit", &self.integrator_limit),
        ];
        for (key, v) in per_axis {
            for x in v {
                check_non_negative(key, *x)?;
            }
        }
        check_non_negative("rate.gyro_cutoff_hz", self.gyro_cutoff_hz)?;
        check_non_negative("rate.dgyro_cutoff_hz", self.dgyro_cutoff_hz)?;
        check_non_negative("rate.yaw_torque_cutoff_hz", self.yaw_torque_cutoff_hz)?;
        check_positive("rate.loop_rate_hz", self.loop_rate_hz)
    }
}

/// Rate-error magnitude at which PX4 fades the I gain to zero (400 deg/s).
const I_FADE_RATE_RAD_S: f64 = 400.0 * std::f64::consts::PI / 180.0;
/// MulticopterRateControl's bounds on dt, s.
const DT_MIN_S: f64 = 0.000125;
const DT_MAX_S: f64 = 0.02;

/// The rate PID with its gyro and D-term filters.
#[derive(Debug, Clone, PartialEq)]
pub struct RateControl {
    gain_p: Vector3<f64>,
    gain_i: Vector3<f64>,
    gain_d: Vector3<f64>,
    gain_ff: Vector3<f64>,
    integrator_limit: Vector3<f64>,
    gyro_cutoff_hz: f64,
    dgyro_cutoff_hz: f64,
    /// Integrator state, normalized torque, body FRD.
    rate_int: Vector3<f64>,
    saturation_positive: [bool; 3],
    saturation_negative: [bool; 3],
    gyro_lpf: [LowPassFilter2p; 3],
    dgyro_lpf: [LowPassFilter2p; 3],
    yaw_torque_lpf: AlphaFilter,
    /// Last unfiltered measured rate, body FRD, rad/s (for the angular acceleration).
    previous_rate_frd: Vector3<f64>,
    filtered_rate_frd: Vector3<f64>,
    angular_accel_frd: Vector3<f64>,
    initialized: bool,
}

impl RateControl {
    pub fn new(params: &RateControlParams) -> Result<Self, ParamsError> {
        params.validate()?;
        let k = Vector3::from(params.k);
        let fs = params.loop_rate_hz;
        Ok(RateControl {
            gain_p: k.component_mul(&Vector3::from(params.p)),
            gain_i: k.component_mul(&Vector3::from(params.i)),
            gain_d: k.component_mul(&Vector3::from(params.d)),
            gain_ff: Vector3::from(params.ff),
            integrator_limit: Vector3::from(params.integrator_limit),
            gyro_cutoff_hz: params.gyro_cutoff_hz,
            dgyro_cutoff_hz: params.dgyro_cutoff_hz,
            rate_int: Vector3::zeros(),
            saturation_positive: [false; 3],
            saturation_negative: [false; 3],
            gyro_lpf: std::array::from_fn(|_| LowPassFilter2p::new(fs, params.gyro_cutoff_hz)),
            dgyro_lpf: std::array::from_fn(|_| LowPassFilter2p::new(fs, params.dgyro_cutoff_hz)),
            yaw_torque_lpf: AlphaFilter::new(params.yaw_torque_cutoff_hz),
            previous_rate_frd: Vector3::zeros(),
            filtered_rate_frd: Vector3::zeros(),
            angular_accel_frd: Vector3::zeros(),
            initialized: false,
        })
    }

    /// Saturation of the allocation in the last step, per torque axis (PX4 takes it from
    /// `control_allocator_status`, one step late, exactly as the chain feeds it here).
    pub fn set_saturation(&mut self, positive: [bool; 3], negative: [bool; 3]) {
        self.saturation_positive = positive;
        self.saturation_negative = negative;
    }

    /// Clears the integrator (PX4 does this while disarmed).
    pub fn reset_integral(&mut self) {
        self.rate_int = Vector3::zeros();
    }

    /// Integrator state, normalized torque, body FRD.
    pub fn integral(&self) -> Vector3<f64> {
        self.rate_int
    }

    /// Gyro-filtered rate of the last step, body FRD, rad/s.
    pub fn filtered_rate_frd(&self) -> Vector3<f64> {
        self.filtered_rate_frd
    }

    /// Filtered angular acceleration of the last step (the D-term input), body FRD, rad/s^2.
    pub fn angular_accel_frd(&self) -> Vector3<f64> {
        self.angular_accel_frd
    }

    /// One step: measured body rate and rate setpoint (body FRD, rad/s) to normalized torque.
    /// `landed` freezes the integrator (PX4 passes `maybe_landed || landed`).
    pub fn update(
        &mut self,
        dt: f64,
        rate_frd: &Vector3<f64>,
        rate_sp_frd: &Vector3<f64>,
        landed: bool,
    ) -> Result<Vector3<f64>, StepError> {
        check_dt(dt)?;
        check_finite3("rate_frd", rate_frd)?;
        check_finite3("rate_sp_frd", rate_sp_frd)?;
        let dt = dt.clamp(DT_MIN_S, DT_MAX_S);
        self.prepare_filters(dt, rate_frd);

        let mut accel_raw = (rate_frd - self.previous_rate_frd) / dt;
        if !self.initialized {
            accel_raw = Vector3::zeros();
            self.initialized = true;
        }
        self.previous_rate_frd = *rate_frd;
        for i in 0..3 {
            self.filtered_rate_frd[i] = self.gyro_lpf[i].apply(rate_frd[i]);
            self.angular_accel_frd[i] = self.dgyro_lpf[i].apply(accel_raw[i]);
        }

        let rate_error = rate_sp_frd - self.filtered_rate_frd;
        let mut torque = self.gain_p.component_mul(&rate_error) + self.rate_int
            - self.gain_d.component_mul(&self.angular_accel_frd)
            + self.gain_ff.component_mul(rate_sp_frd);
        if !landed {
            self.update_integral(rate_error, dt);
        }
        torque.z = self.yaw_torque_lpf.update(torque.z, dt);
        Ok(torque.map(|t| t.clamp(-1.0, 1.0)))
    }

    fn update_integral(&mut self, mut rate_error: Vector3<f64>, dt: f64) {
        for i in 0..3 {
            if self.saturation_positive[i] {
                rate_error[i] = rate_error[i].min(0.0);
            }
            if self.saturation_negative[i] {
                rate_error[i] = rate_error[i].max(0.0);
            }
            let fade = rate_error[i] / I_FADE_RATE_RAD_S;
            let i_factor = (1.0 - fade * fade).max(0.0);
            let rate_i = self.rate_int[i] + i_factor * self.gain_i[i] * rate_error[i] * dt;
            if rate_i.is_finite() {
                let lim = self.integrator_limit[i];
                self.rate_int[i] = rate_i.clamp(-lim, lim);
            }
        }
    }

    /// First step: start the filters at the measured rate (PX4 resets them to the current
    /// sample). Later: re-design them if the step rate moved by more than 5 %.
    fn prepare_filters(&mut self, dt: f64, rate_frd: &Vector3<f64>) {
        let fs = 1.0 / dt;
        let designed = self.gyro_lpf[0].sample_hz();
        let retune = (fs - designed).abs() > 0.05 * designed;
        if retune {
            for i in 0..3 {
                self.gyro_lpf[i].set_cutoff_frequency(fs, self.gyro_cutoff_hz);
                self.dgyro_lpf[i].set_cutoff_frequency(fs, self.dgyro_cutoff_hz);
            }
        }
        if !self.initialized {
            for i in 0..3 {
                self.gyro_lpf[i].reset(rate_frd[i]);
                self.dgyro_lpf[i].reset(0.0);
            }
        } else if retune {
            for i in 0..3 {
                self.gyro_lpf[i].reset(self.filtered_rate_frd[i]);
                self.dgyro_lpf[i].reset(self.angular_accel_frd[i]);
            }
        }
    }
}

#[cfg(test)]
#[path = "rate_tests.rs"]
mod tests;
