//! What the emulated PX4 believes about its own state: the motion-capture position with the
//! paper's perturbation, a noisy IMU, and a small EKF2-like filter that fuses the two.
//!
//! On the real drones the paper's perturbation (V.C) is added to the motion-capture position
//! that PX4's EKF2 fuses with the IMU, so the controller sees a smoothed, biased position. The
//! plant reproduces that chain:
//!
//! ```text
//! truth --[MocapPerturbation, 100 Hz]--> perturbed position --+
//!                                                              v
//! truth specific force, rates --[ImuModel]--> IMU --> [PositionEstimator] --> VehicleEstimate
//! truth attitude ----------------------------------------------^ (attitude from truth)
//! ```
//!
//! - [`perturbation`]: [`MocapPerturbation`], white noise plus a Gauss-Markov bias; the module doc
//!   states our reading of the paper's Sigma and Q and the magnitudes that result.
//! - [`imu`]: [`ImuModel`], accelerometer and gyro white noise.
//! - [`position_filter`]: [`PositionEstimator`], a per-axis position/velocity Kalman filter.
//!
//! [`VehicleEstimate`] is the shared output type; the commander consumes it too.

pub mod imu;
pub mod perturbation;
pub mod position_filter;

pub use imu::{ImuModel, ImuParams, ImuParamsError, ImuSample};
pub use perturbation::{MocapPerturbation, MocapSample, PerturbationError, PerturbationParams};
pub use position_filter::{EstimatorParams, EstimatorParamsError, PositionEstimator};

use nalgebra::{UnitQuaternion, Vector3};

/// Standard gravity used by the estimator's prediction (common.md: +9.81 m/s^2 along NED +z).
pub const GRAVITY_MPS2: f64 = 9.81;

/// The vehicle state as the emulated autopilot estimates it (PX4's `vehicle_local_position`,
/// `vehicle_attitude` and `vehicle_angular_velocity` in one value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleEstimate {
    /// Time of the estimate, ns (same clock as every other plant timestamp).
    pub t_ns: u64,
    /// Position of the body origin in NED, m.
    pub position_ned: Vector3<f64>,
    /// Velocity in NED, m/s.
    pub velocity_ned: Vector3<f64>,
    /// Attitude, rotating body FRD -> NED (`v_ned = attitude * v_body`).
    pub attitude: UnitQuaternion<f64>,
    /// Body angular rate in FRD, rad/s.
    pub rate_frd: Vector3<f64>,
    /// Specific force (accelerometer reading) in FRD, m/s^2; about (0, 0, -9.81) at rest.
    pub specific_force_frd: Vector3<f64>,
    /// False until the first position measurement has been fused.
    pub position_valid: bool,
}

impl VehicleEstimate {
    /// A vehicle at rest, level, facing north at `position_ned` with a valid position.
    pub fn at_rest(t_ns: u64, position_ned: Vector3<f64>) -> Self {
        VehicleEstimate {
            t_ns,
            position_ned,
            velocity_ned: Vector3::zeros(),
            attitude: UnitQuaternion::identity(),
            rate_frd: Vector3::zeros(),
            specific_force_frd: Vector3::new(0.0, 0.0, -GRAVITY_MPS2),
            position_valid: true,
        }
    }

    /// True when every number in the estimate is finite.
    pub fn is_finite(&self) -> bool {
        let q = self.attitude.quaternion();
        self.position_ned.iter().all(|v| v.is_finite())
            && self.velocity_ned.iter().all(|v| v.is_finite())
            && self.rate_frd.iter().all(|v| v.is_finite())
            && self.specific_force_frd.iter().all(|v| v.is_finite())
            && q.coords.iter().all(|v| v.is_finite())
    }

    /// Heading (yaw about NED z), rad, in (-pi, pi].
    pub fn yaw(&self) -> f64 {
        self.attitude.euler_angles().2
    }
}
