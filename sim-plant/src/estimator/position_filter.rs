//! An EKF2-like position/velocity estimator: per NED axis a two-state Kalman filter
//! `[position, velocity]`, predicted with the accelerometer rotated to NED plus gravity at the
//! IMU rate and corrected with the (perturbed) motion-capture position at its rate.
//!
//! What it keeps from EKF2, with EKF2's defaults:
//!
//! - process noise from the accelerometer noise EKF2_ACC_NOISE = 0.35 m/s^2, added the way EKF2
//!   adds it on its 10 ms prediction step: velocity variance `(0.01 s * 0.35)^2` per 10 ms, i.e.
//!   a white acceleration of PSD `0.35^2 * 0.01` m^2/s^3 whatever our own step;
//! - external-vision position noise EKF2_EVP_NOISE = 0.1 m (what EKF2 uses when the vision
//!   message carries no smaller covariance) and the innovation gate EKF2_EVP_GATE = 5 sigma;
//! - initialisation at the first vision sample (position from it, velocity zero).
//!
//! What it leaves out: the attitude (taken from truth, optionally with small noise; EKF2's
//! attitude is far better than anything that matters here), the accelerometer-bias states, the
//! delayed-horizon buffer (the measurement is fused at the time it is given) and the output
//! predictor. Accelerometer bias therefore shows up as a small position offset.

use nalgebra::{Matrix2, UnitQuaternion, Vector2, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use serde::Deserialize;

use super::{ImuSample, VehicleEstimate, GRAVITY_MPS2};

/// EKF2 adds its process noise per 10 ms filter step; we keep the same noise per unit time.
const EKF2_FILTER_PERIOD_S: f64 = 0.01;

/// Estimator tuning.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EstimatorParams {
    /// Vision position noise std per NED axis, m. Default 0.1 (EKF2_EVP_NOISE).
    pub ev_pos_noise_std_m: [f64; 3],
    /// Accelerometer noise driving the process noise, m/s^2. Default 0.35 (EKF2_ACC_NOISE).
    pub accel_noise_std_mps2: f64,
    /// Innovation gate, in standard deviations of the innovation. Default 5 (EKF2_EVP_GATE).
    pub ev_gate_sigma: f64,
    /// Initial velocity std at initialisation, m/s. Default 0.5.
    pub init_velocity_std_mps: f64,
    /// Std of the small-angle noise put on the true attitude, rad. Default 0 (exact).
    pub attitude_noise_std_rad: f64,
    /// Gravity along NED +z, m/s^2. Default 9.81.
    pub gravity_mps2: f64,
}

impl Default for EstimatorParams {
    fn default() -> Self {
        EstimatorParams {
            ev_pos_noise_std_m: [0.1; 3],
            accel_noise_std_mps2: 0.35,
            ev_gate_sigma: 5.0,
            init_velocity_std_mps: 0.5,
            attitude_noise_std_rad: 0.0,
            gravity_mps2: GRAVITY_MPS2,
        }
    }
}

/// An estimator parameter the filter cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("estimator parameter `{key}` = {value}: {msg}")]
pub struct EstimatorParamsError {
    pub key: &'static str,
    pub value: f64,
    pub msg: &'static str,
}

impl EstimatorParams {
    /// Checks that noise stds and the gate are finite and > 0 (attitude noise >= 0).
    pub fn validate(&self) -> Result<(), EstimatorParamsError> {
        let positive = self
            .ev_pos_noise_std_m
            .iter()
            .map(|v| ("ev_pos_noise_std_m", *v));
        let positive = positive.chain([
            ("accel_noise_std_mps2", self.accel_noise_std_mps2),
            ("ev_gate_sigma", self.ev_gate_sigma),
            ("init_velocity_std_mps", self.init_velocity_std_mps),
            ("gravity_mps2", self.gravity_mps2),
        ]);
        for (key, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                let msg = "must be finite and > 0";
                return Err(EstimatorParamsError { key, value, msg });
            }
        }
        let value = self.attitude_noise_std_rad;
        if !(value.is_finite() && value >= 0.0) {
            let key = "attitude_noise_std_rad";
            let msg = "must be finite and >= 0";
            return Err(EstimatorParamsError { key, value, msg });
        }
        Ok(())
    }
}

/// Per-axis position/velocity Kalman filter with attitude and rates from (near) truth.
#[derive(Debug, Clone)]
pub struct PositionEstimator {
    params: EstimatorParams,
    rng: StdRng,
    /// Per NED axis: state `[p, v]` and its covariance.
    state: [Vector2<f64>; 3],
    covariance: [Matrix2<f64>; 3],
    initialized: bool,
    last: VehicleEstimate,
    fused: u64,
    gated: u64,
    rejected_inputs: u64,
}

impl PositionEstimator {
    /// A filter waiting for its first position measurement; `seed` drives the optional
    /// attitude noise.
    pub fn new(params: EstimatorParams, seed: u64) -> Result<Self, EstimatorParamsError> {
        params.validate()?;
        let mut last = VehicleEstimate::at_rest(0, Vector3::zeros());
        last.specific_force_frd = Vector3::new(0.0, 0.0, -params.gravity_mps2);
        last.position_valid = false;
        Ok(PositionEstimator {
            params,
            rng: StdRng::seed_from_u64(seed),
            state: [Vector2::zeros(); 3],
            covariance: [Matrix2::zeros(); 3],
            initialized: false,
            last,
            fused: 0,
            gated: 0,
            rejected_inputs: 0,
        })
    }

    /// The tuning in use.
    pub fn params(&self) -> &EstimatorParams {
        &self.params
    }

    /// Prediction step at `t_ns` over `dt_s` (> 0, <= 1 s) with an IMU sample and the true
    /// attitude (body FRD -> NED). Non-finite inputs or a bad `dt_s` are counted and skipped.
    pub fn predict(
        &mut self,
        t_ns: u64,
        dt_s: f64,
        imu: &ImuSample,
        attitude_truth: &UnitQuaternion<f64>,
    ) {
        let finite = imu
            .specific_force_frd
            .iter()
            .chain(imu.angular_rate_frd.iter())
            .all(|v| v.is_finite())
            && attitude_truth.coords.iter().all(|v| v.is_finite());
        if !(finite && dt_s.is_finite() && dt_s > 0.0 && dt_s <= 1.0) {
            self.rejected_inputs += 1;
            return;
        }
        let attitude = self.noisy_attitude(attitude_truth);
        self.last.t_ns = t_ns;
        self.last.attitude = attitude;
        self.last.rate_frd = imu.angular_rate_frd;
        self.last.specific_force_frd = imu.specific_force_frd;
        if !self.initialized {
            return;
        }
        let accel_ned =
            attitude * imu.specific_force_frd + Vector3::new(0.0, 0.0, self.params.gravity_mps2);
        let transition = Matrix2::new(1.0, dt_s, 0.0, 1.0);
        let q = self.params.accel_noise_std_mps2.powi(2) * EKF2_FILTER_PERIOD_S;
        let process = q * Matrix2::new(
            dt_s.powi(3) / 3.0,
            dt_s.powi(2) / 2.0,
            dt_s.powi(2) / 2.0,
            dt_s,
        );
        for axis in 0..3 {
            let a = accel_ned[axis];
            let x = &mut self.state[axis];
            x[0] += x[1] * dt_s + 0.5 * a * dt_s * dt_s;
            x[1] += a * dt_s;
            let p = &mut self.covariance[axis];
            *p = transition * *p * transition.transpose() + process;
        }
        self.publish_state();
    }

    /// Correction with a motion-capture position (NED, m) at `t_ns`. The first valid one
    /// initialises the filter. Each axis whose innovation exceeds the gate is skipped and
    /// counted. Returns true when every axis was fused.
    pub fn correct(&mut self, t_ns: u64, position_ned: &Vector3<f64>) -> bool {
        if !position_ned.iter().all(|v| v.is_finite()) {
            self.rejected_inputs += 1;
            return false;
        }
        self.last.t_ns = self.last.t_ns.max(t_ns);
        if !self.initialized {
            let v_var = self.params.init_velocity_std_mps.powi(2);
            for axis in 0..3 {
                self.state[axis] = Vector2::new(position_ned[axis], 0.0);
                let r = self.params.ev_pos_noise_std_m[axis].powi(2);
                self.covariance[axis] = Matrix2::new(r, 0.0, 0.0, v_var);
            }
            self.initialized = true;
            self.fused += 1;
            self.publish_state();
            return true;
        }
        let mut all_fused = true;
        for axis in 0..3 {
            let r = self.params.ev_pos_noise_std_m[axis].powi(2);
            let p = self.covariance[axis];
            let innovation = position_ned[axis] - self.state[axis][0];
            let s = p[(0, 0)] + r;
            if innovation * innovation > self.params.ev_gate_sigma.powi(2) * s {
                self.gated += 1;
                all_fused = false;
                continue;
            }
            let gain = Vector2::new(p[(0, 0)], p[(1, 0)]) / s;
            self.state[axis] += gain * innovation;
            // Joseph form keeps the covariance symmetric and positive.
            let i_kh = Matrix2::identity() - Matrix2::new(gain[0], 0.0, gain[1], 0.0);
            self.covariance[axis] = i_kh * p * i_kh.transpose() + gain * gain.transpose() * r;
        }
        self.fused += 1;
        self.publish_state();
        all_fused
    }

    fn noisy_attitude(&mut self, truth: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
        let std = self.params.attitude_noise_std_rad;
        if std == 0.0 {
            return *truth;
        }
        let mut v = Vector3::zeros();
        for axis in 0..3 {
            let n: f64 = self.rng.sample(StandardNormal);
            v[axis] = std * n;
        }
        truth * UnitQuaternion::from_scaled_axis(v)
    }

    fn publish_state(&mut self) {
        for axis in 0..3 {
            self.last.position_ned[axis] = self.state[axis][0];
            self.last.velocity_ned[axis] = self.state[axis][1];
        }
        self.last.position_valid = self.initialized;
    }

    /// The current estimate (position/velocity zero and `position_valid` false before the
    /// first measurement).
    pub fn estimate(&self) -> VehicleEstimate {
        self.last
    }

    /// One-sigma position uncertainty per NED axis, m (zero before initialisation).
    pub fn position_std_m(&self) -> Vector3<f64> {
        Vector3::from_fn(|axis, _| self.covariance[axis][(0, 0)].max(0.0).sqrt())
    }

    /// Position measurements fused (including the initialising one).
    pub fn fused_measurements(&self) -> u64 {
        self.fused
    }

    /// Axis innovations rejected by the gate.
    pub fn gated_innovations(&self) -> u64 {
        self.gated
    }

    /// Predictions or corrections skipped for non-finite input or a bad `dt_s`.
    pub fn rejected_inputs(&self) -> u64 {
        self.rejected_inputs
    }
}

#[cfg(test)]
#[path = "position_filter_tests.rs"]
mod tests;
