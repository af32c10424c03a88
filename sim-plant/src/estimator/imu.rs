//! Accelerometer and gyro of the emulated Pixhawk 6C: truth plus white noise (and an optional
//! constant bias), one sample per call at whatever rate the plant runs the estimator.
//!
//! Default noise, per sample, for PX4's filtered IMU data at 50-400 Hz (our pick):
//!
//! - The ICM-42688-P's datasheet noise densities are 70 ug/sqrt(Hz) (accel) and
//!   2.8 mdps/sqrt(Hz) (gyro). Over the ~125 Hz bandwidth of PX4's 250 Hz integrated samples that
//!   is a floor of about 0.008 m/s^2 and 0.0006 rad/s.
//! - In flight, propeller vibration that survives PX4's low-pass filters (IMU_ACCEL_CUTOFF 30 Hz,
//!   IMU_GYRO_CUTOFF 40 Hz) dominates; on a well-balanced X500 it is several times the floor. We
//!   take 0.05 m/s^2 and 0.005 rad/s (0.29 deg/s), independent per axis and sample.
//! - For comparison, EKF2's own (deliberately conservative) process-noise tuning is
//!   EKF2_ACC_NOISE = 0.35 m/s^2 and EKF2_GYR_NOISE = 0.015 rad/s.
//!
//! The std applies per sample whatever the call rate; the constant biases default to zero.

use nalgebra::Vector3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use serde::Deserialize;

/// IMU noise configuration.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ImuParams {
    /// Accelerometer white-noise std per axis and sample, m/s^2. Default 0.05.
    pub accel_noise_std_mps2: f64,
    /// Gyro white-noise std per axis and sample, rad/s. Default 0.005.
    pub gyro_noise_std_radps: f64,
    /// Constant accelerometer bias in FRD, m/s^2. Default zero.
    pub accel_bias_frd_mps2: [f64; 3],
    /// Constant gyro bias in FRD, rad/s. Default zero.
    pub gyro_bias_frd_radps: [f64; 3],
}

impl Default for ImuParams {
    fn default() -> Self {
        ImuParams {
            accel_noise_std_mps2: 0.05,
            gyro_noise_std_radps: 0.005,
            accel_bias_frd_mps2: [0.0; 3],
            gyro_bias_frd_radps: [0.0; 3],
        }
    }
}

/// An IMU parameter the model cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("IMU parameter `{key}` = {value}: {msg}")]
pub struct ImuParamsError {
    pub key: &'static str,
    pub value: f64,
    pub msg: &'static str,
}

impl ImuParams {
    /// An ideal IMU: no noise, no bias.
    pub fn ideal() -> Self {
        ImuParams {
            accel_noise_std_mps2: 0.0,
            gyro_noise_std_radps: 0.0,
            ..ImuParams::default()
        }
    }

    /// Checks that the stds are finite and >= 0 and the biases finite.
    pub fn validate(&self) -> Result<(), ImuParamsError> {
        for (key, value) in [
            ("accel_noise_std_mps2", self.accel_noise_std_mps2),
            ("gyro_noise_std_radps", self.gyro_noise_std_radps),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                let msg = "must be finite and >= 0";
                return Err(ImuParamsError { key, value, msg });
            }
        }
        let biases = self
            .accel_bias_frd_mps2
            .iter()
            .map(|v| ("accel_bias_frd_mps2", *v));
        let biases = biases.chain(
            self.gyro_bias_frd_radps
                .iter()
                .map(|v| ("gyro_bias_frd_radps", *v)),
        );
        for (key, value) in biases {
            if !value.is_finite() {
                let msg = "must be finite";
                return Err(ImuParamsError { key, value, msg });
            }
        }
        Ok(())
    }
}

/// One IMU reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// Specific force (what the accelerometer measures, acceleration minus gravity) in FRD,
    /// m/s^2; (0, 0, -9.81) for a level vehicle at rest.
    pub specific_force_frd: Vector3<f64>,
    /// Angular rate in FRD, rad/s.
    pub angular_rate_frd: Vector3<f64>,
}

/// Noisy accelerometer and gyro with their own random stream.
#[derive(Debug, Clone)]
pub struct ImuModel {
    params: ImuParams,
    rng: StdRng,
    rejected_inputs: u64,
}

impl ImuModel {
    /// An IMU whose noise comes from a stream seeded by `seed`.
    pub fn new(params: ImuParams, seed: u64) -> Result<Self, ImuParamsError> {
        params.validate()?;
        Ok(ImuModel {
            params,
            rng: StdRng::seed_from_u64(seed),
            rejected_inputs: 0,
        })
    }

    /// The configuration in use.
    pub fn params(&self) -> &ImuParams {
        &self.params
    }

    /// Measures the true specific force (FRD, m/s^2) and angular rate (FRD, rad/s). A
    /// non-finite truth is counted and yields `None` without touching the random stream.
    pub fn measure(
        &mut self,
        specific_force_frd: &Vector3<f64>,
        angular_rate_frd: &Vector3<f64>,
    ) -> Option<ImuSample> {
        let finite = specific_force_frd
            .iter()
            .chain(angular_rate_frd.iter())
            .all(|v| v.is_finite());
        if !finite {
            self.rejected_inputs += 1;
            return None;
        }
        let mut accel = specific_force_frd + Vector3::from(self.params.accel_bias_frd_mps2);
        let mut gyro = angular_rate_frd + Vector3::from(self.params.gyro_bias_frd_radps);
        for axis in 0..3 {
            let n: f64 = self.rng.sample(StandardNormal);
            accel[axis] += self.params.accel_noise_std_mps2 * n;
        }
        for axis in 0..3 {
            let n: f64 = self.rng.sample(StandardNormal);
            gyro[axis] += self.params.gyro_noise_std_radps * n;
        }
        Some(ImuSample {
            specific_force_frd: accel,
            angular_rate_frd: gyro,
        })
    }

    /// Calls to [`measure`](Self::measure) rejected for a non-finite truth.
    pub fn rejected_inputs(&self) -> u64 {
        self.rejected_inputs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_std_and_bias_match_the_config() {
        let params = ImuParams {
            accel_bias_frd_mps2: [0.1, 0.0, 0.0],
            ..ImuParams::default()
        };
        let mut imu = ImuModel::new(params, 5).unwrap();
        let f = Vector3::new(0.0, 0.0, -9.81);
        let w = Vector3::new(0.2, 0.0, 0.0);
        let n = 50_000;
        let (mut sum_ax, mut sq_ay, mut sq_wz) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let s = imu.measure(&f, &w).unwrap();
            sum_ax += s.specific_force_frd.x;
            sq_ay += s.specific_force_frd.y.powi(2);
            sq_wz += s.angular_rate_frd.z.powi(2);
        }
        let nf = n as f64;
        assert!(
            (sum_ax / nf - 0.1).abs() < 0.002,
            "accel bias {}",
            sum_ax / nf
        );
        assert!(((sq_ay / nf).sqrt() / 0.05 - 1.0).abs() < 0.03);
        assert!(((sq_wz / nf).sqrt() / 0.005 - 1.0).abs() < 0.03);
    }

    #[test]
    fn ideal_is_exact_and_nan_is_rejected() {
        let mut imu = ImuModel::new(ImuParams::ideal(), 1).unwrap();
        let f = Vector3::new(1.0, 2.0, -9.0);
        let w = Vector3::new(0.1, -0.2, 0.3);
        let s = imu.measure(&f, &w).unwrap();
        assert_eq!((s.specific_force_frd, s.angular_rate_frd), (f, w));
        assert!(imu.measure(&Vector3::new(f64::NAN, 0.0, 0.0), &w).is_none());
        assert_eq!(imu.rejected_inputs(), 1);
        let bad = ImuParams {
            gyro_noise_std_radps: f64::INFINITY,
            ..ImuParams::default()
        };
        assert_eq!(
            ImuModel::new(bad, 0).unwrap_err().key,
            "gyro_noise_std_radps"
        );
    }
}
