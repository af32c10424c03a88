//! What the commander asks of the inner loops at each step.

use nalgebra::{UnitQuaternion, Vector3};

/// A body-rate setpoint that PX4's MAVLink receiver publishes to `vehicle_rates_setpoint` next
/// to an attitude setpoint (a SET_ATTITUDE_TARGET that does not set type_mask bits 1 and 2).
///
/// PX4 runs the attitude controller in that case (attitude wins in the control mode), but the
/// receiver still publishes the message's rates to the topic the rate controller reads, so at
/// each message the rate controller flies these rates until mc_att_control publishes its next
/// output (its next attitude update, a few ms later). The inner loops decide how to apply it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateInjection {
    /// Rates in FRD, rad/s. A NaN axis (ignored yaw rate) means "hold the measured rate of that
    /// axis" (mc_rate_control keeps the current rate for a non-finite setpoint).
    pub rates_frd: Vector3<f64>,
    /// Normalised collective thrust 0..1 that came with it.
    pub thrust: f64,
    /// When the message arrived, ns.
    pub t_ns: u64,
}

/// The inner-loop demand for the current step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ControlDemand {
    /// Disarmed: motors stopped.
    MotorsOff,
    /// Attitude and collective thrust (offboard attitude, or idle on the ground).
    Attitude {
        /// Desired attitude, body FRD -> NED.
        q_sp: UnitQuaternion<f64>,
        /// Normalised collective thrust 0..1 (the throttle PX4's allocator receives).
        thrust: f64,
        /// Yaw-rate feed-forward, rad/s (0 when the message ignores the yaw rate).
        yaw_rate_ff: f64,
        /// Rates from the same message that also reach the rate controller, if any.
        rate_injection: Option<RateInjection>,
    },
    /// Body rates and collective thrust (offboard rates).
    Rates {
        /// Rates in FRD, rad/s; a NaN yaw means "hold the measured yaw rate".
        rates_frd: Vector3<f64>,
        /// Normalised collective thrust 0..1.
        thrust: f64,
    },
    /// PX4's position controller: a finite position component is held with `velocity_ned` as
    /// feed-forward; a NaN position component is flown at `velocity_ned` on that axis.
    Position {
        /// Target position in NED, m (NaN = that axis velocity-controlled).
        position_ned: Vector3<f64>,
        /// Target or feed-forward velocity in NED, m/s.
        velocity_ned: Vector3<f64>,
        /// Heading to hold, rad.
        yaw: f64,
    },
}

impl ControlDemand {
    /// The collective thrust this demand sets directly, if it sets one.
    pub fn thrust(&self) -> Option<f64> {
        match self {
            ControlDemand::Attitude { thrust, .. } | ControlDemand::Rates { thrust, .. } => {
                Some(*thrust)
            }
            ControlDemand::MotorsOff | ControlDemand::Position { .. } => None,
        }
    }

    /// Level attitude at `yaw` with zero thrust: what PX4's position controller outputs on the
    /// ground (not yet taken off, or flying with ground contact).
    pub fn idle(yaw: f64) -> Self {
        ControlDemand::Attitude {
            q_sp: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            thrust: 0.0,
            yaw_rate_ff: 0.0,
            rate_injection: None,
        }
    }
}
