//! PX4's multicopter position controller (mc_pos_control, `PositionControl`).
//!
//! Followed: PX4-Autopilot src/modules/mc_pos_control/PositionControl/PositionControl.cpp
//! (`_positionControl`, `_velocityControl`, `_accelerationControl`, `_inputValid`),
//! ControlMath.cpp (see [`super::control_math`]) and, for what wraps it,
//! MulticopterPositionControl.cpp (velocity derivative through `BlockDerivative` at
//! MPC_VELD_LP, dt constrained to [2 ms, 40 ms], NaN yaw = current yaw, NaN yaw rate = 0, the
//! not-yet-flying substitution of a 100 m/s^2 downward acceleration with integrator reset).
//!
//! Cascade: position P -> velocity setpoint (NaN entries of the setpoint are "not
//! controlled", feed-forward velocity added where finite, horizontal norm limited giving the
//! position part priority, vertical limited to MPC_Z_VEL_MAX_UP/DN) -> velocity PID with D on
//! the velocity derivative -> acceleration (feed-forward added where finite) -> thrust vector
//! assuming hover throttle gives g, tilt limited to MPC_TILTMAX_AIR, collective thrust in
//! [MPC_THR_MIN, MPC_THR_MAX] with vertical priority and MPC_THR_XY_MARG horizontal margin.
//! Anti-windup: vertical integration stops against the thrust limits; horizontal tracking
//! anti-windup with gain 2 / MPC_XY_VEL_P_ACC; |vertical integral| <= g.
//!
//! Not emulated: the hover thrust estimator (MPC_USE_HTE; hover throttle is fixed here), the
//! takeoff ramp and the flight tasks' smoothing (the caller provides the setpoints).

use nalgebra::{UnitQuaternion, Vector2, Vector3};
use serde::Deserialize;

use super::errors::{check_non_negative, check_positive, check_range, ParamsError};

/// PX4's CONSTANTS_ONE_G, m/s^2 (the controller's own gravity constant).
pub const PX4_ONE_G: f64 = 9.80665;

/// Position controller parameters; defaults are PX4 v1.16's (hover 0.6 as the gz x500).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PositionControlParams {
    /// MPC_XY_P, 1/s. Default 0.95.
    pub xy_p: f64,
    /// MPC_Z_P, 1/s. Default 1.0.
    pub z_p: f64,
    /// MPC_XY_VEL_P_ACC, 1/s. Default 1.8.
    pub xy_vel_p_acc: f64,
    /// MPC_XY_VEL_I_ACC, 1/s^2. Default 0.4.
    pub xy_vel_i_acc: f64,
    /// MPC_XY_VEL_D_ACC, dimensionless. Default 0.2.
    pub xy_vel_d_acc: f64,
    /// MPC_Z_VEL_P_ACC, 1/s. Default 4.0.
    pub z_vel_p_acc: f64,
    /// MPC_Z_VEL_I_ACC, 1/s^2. Default 2.0.
    pub z_vel_i_acc: f64,
    /// MPC_Z_VEL_D_ACC. Default 0.
    pub z_vel_d_acc: f64,
    /// MPC_XY_VEL_MAX, m/s: the controller's horizontal velocity limit. Default 12.
    pub xy_vel_max_m_s: f64,
    /// MPC_XY_CRUISE, m/s: speed of PX4's auto modes; for setpoint generators, not used by
    /// the controller. Default 5.
    pub xy_cruise_m_s: f64,
    /// MPC_Z_VEL_MAX_UP, m/s. Default 3.
    pub z_vel_max_up_m_s: f64,
    /// MPC_Z_VEL_MAX_DN, m/s. Default 1.5.
    pub z_vel_max_dn_m_s: f64,
    /// MPC_LAND_SPEED, m/s down: used by [`TrajectorySetpoint::land`]. Default 0.7.
    pub land_speed_m_s: f64,
    /// MPC_TILTMAX_AIR, deg. Default 45.
    pub tilt_max_air_deg: f64,
    /// MPC_THR_MIN, normalized. Default 0.12.
    pub thr_min: f64,
    /// MPC_THR_MAX, normalized. Default 1.
    pub thr_max: f64,
    /// MPC_THR_XY_MARG, normalized thrust kept for horizontal control. Default 0.3.
    pub thr_xy_margin: f64,
    /// MPC_THR_HOVER, normalized. Default 0.6 (gz x500 airframe).
    pub hover_throttle: f64,
    /// MPC_VELD_LP, Hz: low-pass on the velocity derivative. Default 5.
    pub veld_lp_hz: f64,
}

impl Default for PositionControlParams {
    fn default() -> Self {
        PositionControlParams {
            xy_p: 0.95,
            z_p: 1.0,
            xy_vel_p_acc: 1.8,
            xy_vel_i_acc: 0.4,
            xy_vel_d_acc: 0.2,
            z_vel_p_acc: 4.0,
            z_vel_i_acc: 2.0,
            z_vel_d_acc: 0.0,
            xy_vel_max_m_s: 12.0,
            xy_cruise_m_s: 5.0,
            z_vel_max_up_m_s: 3.0,
            z_vel_max_dn_m_s: 1.5,
            land_speed_m_s: 0.7,
            tilt_max_air_deg: 45.0,
            thr_min: 0.12,
            thr_max: 1.0,
            thr_xy_margin: 0.3,
            hover_throttle: 0.6,
            veld_lp_hz: 5.0,
        }
    }
}

impl PositionControlParams {
    /// Gains >= 0 (P gains > 0), limits positive, thrusts ordered in [0, 1].
    pub fn validate(&self) -> Result<(), ParamsError> {
        check_positive("position.xy_p", self.xy_p)?;
        check_positive("position.z_p", self.z_p)?;
        check_positive("position.xy_vel_p_acc", self.xy_vel_p_acc)?;
        check_positive("position.z_vel_p_acc", self.z_vel_p_acc)?;
        for (k, v) in [
            ("position.xy_vel_i_acc", self.xy_vel_i_acc),
            ("position.xy_vel_d_acc", self.xy_vel_d_acc),
            ("position.z_vel_i_acc", self.z_vel_i_acc),
            ("position.z_vel_d_acc", self.z_vel_d_acc),
            ("position.thr_xy_margin", self.thr_xy_margin),
            ("position.veld_lp_hz", self.veld_lp_hz),
        ] {
            check_non_negative(k, v)?;
        }
        for (k, v) in [
            ("position.xy_vel_max_m_s", self.xy_vel_max_m_s),
            ("position.xy_cruise_m_s", self.xy_cruise_m_s),
            ("position.z_vel_max_up_m_s", self.z_vel_max_up_m_s),
            ("position.z_vel_max_dn_m_s", self.z_vel_max_dn_m_s),
            ("position.land_speed_m_s", self.land_speed_m_s),
        ] {
            check_positive(k, v)?;
        }
        check_range(
            "position.tilt_max_air_deg",
            self.tilt_max_air_deg,
            1.0,
            89.0,
        )?;
        check_range("position.thr_max", self.thr_max, 0.05, 1.0)?;
        check_range("position.thr_min", self.thr_min, 0.0, self.thr_max)?;
        check_range(
            "position.hover_throttle",
            self.hover_throttle,
            0.05,
            self.thr_max,
        )
    }
}

/// PX4's `trajectory_setpoint`, NED. A NaN entry means "this is not controlled"; every axis
/// needs a finite position, velocity or acceleration, and x/y come in pairs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectorySetpoint {
    /// Position setpoint, NED, m.
    pub position_ned_m: Vector3<f64>,
    /// Velocity setpoint (feed-forward when the position is also set), NED, m/s.
    pub velocity_ned_m_s: Vector3<f64>,
    /// Acceleration feed-forward, NED, m/s^2.
    pub acceleration_ned_m_s2: Vector3<f64>,
    /// Heading, rad; NaN holds the current one.
    pub yaw_rad: f64,
    /// Yaw-rate feed-forward, rad/s; NaN is 0.
    pub yaw_rate_rad_s: f64,
}

impl TrajectorySetpoint {
    /// Everything NaN (PX4's `empty_trajectory_setpoint`).
    pub fn empty() -> Self {
        let nan = Vector3::repeat(f64::NAN);
        TrajectorySetpoint {
            position_ned_m: nan,
            velocity_ned_m_s: nan,
            acceleration_ned_m_s2: nan,
            yaw_rad: f64::NAN,
            yaw_rate_rad_s: f64::NAN,
        }
    }

    /// Hold `position_ned_m` with heading `yaw_rad`.
    pub fn position(position_ned_m: Vector3<f64>, yaw_rad: f64) -> Self {
        TrajectorySetpoint {
            position_ned_m,
            yaw_rad,
            ..Self::empty()
        }
    }

    /// Fly `velocity_ned_m_s` (no position control).
    pub fn velocity(velocity_ned_m_s: Vector3<f64>, yaw_rad: f64) -> Self {
        TrajectorySetpoint {
            velocity_ned_m_s,
            yaw_rad,
            ..Self::empty()
        }
    }

    /// PX4's Land: hold the horizontal position `xy_ned_m`, descend at `land_speed_m_s`
    /// (down positive) without a height setpoint.
    pub fn land(xy_ned_m: Vector2<f64>, yaw_rad: f64, land_speed_m_s: f64) -> Self {
        TrajectorySetpoint {
            position_ned_m: Vector3::new(xy_ned_m.x, xy_ned_m.y, f64::NAN),
            velocity_ned_m_s: Vector3::new(f64::NAN, f64::NAN, land_speed_m_s),
            yaw_rad,
            ..Self::empty()
        }
    }
}

/// What the position controller hands to the attitude loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionControlOutput {
    /// Attitude setpoint, body FRD -> NED.
    pub attitude_sp: UnitQuaternion<f64>,
    /// Collective thrust, normalized (PX4's thrust_body z = -thrust).
    pub thrust: f64,
    /// Yaw-rate feed-forward for the attitude loop, rad/s.
    pub yaw_rate_ff_rad_s: f64,
    /// Thrust vector setpoint, normalized, NED.
    pub thrust_ned: Vector3<f64>,
    /// Acceleration setpoint after the velocity loop, NED, m/s^2.
    pub acceleration_sp_ned_m_s2: Vector3<f64>,
    /// Velocity setpoint after the position loop and limits, NED, m/s.
    pub velocity_sp_ned_m_s: Vector3<f64>,
}

#[cfg(test)]
#[path = "position_tests.rs"]
mod tests;

mod control;
pub use control::PositionControl;
