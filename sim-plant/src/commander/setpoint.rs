//! SET_ATTITUDE_TARGET as PX4 v1.16 reads it (MavlinkReceiver::handle_message_set_attitude_target
//! in src/modules/mavlink/mavlink_receiver.cpp):
//!
//! - `attitude = !(mask & 128)`, `body_rates = !(mask & 1) && !(mask & 2)` (the yaw bit 4 does
//!   not matter), `thrust_body = mask & 32`.
//! - If `attitude || body_rates` an `offboard_control_mode` is published with
//!   `{attitude, body_rate}` set accordingly: that is the proof of life. A message with neither
//!   publishes nothing and keeps nothing alive.
//! - Attitude: `q_d = q`; yaw feed-forward = body yaw rate unless bit 4 (NaN, which the attitude
//!   controller treats as 0); thrust = `thrust` unless bit 32 (then `thrust_body`) or bit 64
//!   (then zero: the struct is zero-initialised). Published only in OFFBOARD.
//! - Body rates: roll, pitch, yaw (NaN where ignored), thrust = `thrust` unless bit 64 (zero;
//!   bit 32 is not honoured here). Published only in OFFBOARD, to the same topic the attitude
//!   controller writes.
//! - In OFFBOARD the control mode (ModeUtil/control_mode.cpp) checks `attitude` before
//!   `body_rate`: with both set the attitude controller runs, and the message's rates still
//!   reach the rate controller between attitude-controller outputs ([`RateInjection`]).
//!   That is why MODEL.md says to set bits 1 and 2 (mask 7) for attitude + thrust.
//!
//! Deviations, to stay robust: PX4 does not validate the message. We reject a message whose
//! used fields are not finite or whose quaternion has (near) zero norm, count it, and keep the
//! last valid setpoint; it still counts as proof of life (PX4 publishes the control mode
//! before anything else). A non-unit quaternion is normalised, as PX4's attitude controller
//! does. Thrust is clamped to 0..1 (a quadrotor cannot push down); with bit 32 the collective
//! thrust is `-thrust_body[2]` and the x/y components are ignored.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::demand::{ControlDemand, RateInjection};

/// SET_ATTITUDE_TARGET `type_mask` bits (ATTITUDE_TARGET_TYPEMASK).
pub mod type_mask {
    pub const BODY_ROLL_RATE_IGNORE: u8 = 1;
    pub const BODY_PITCH_RATE_IGNORE: u8 = 2;
    pub const BODY_YAW_RATE_IGNORE: u8 = 4;
    pub const THRUST_BODY_SET: u8 = 32;
    pub const THROTTLE_IGNORE: u8 = 64;
    pub const ATTITUDE_IGNORE: u8 = 128;
}

/// The fields of SET_ATTITUDE_TARGET (#82) the autopilot uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttitudeTarget {
    /// Attitude (w, x, y, z), body FRD relative to NED.
    pub q: [f32; 4],
    /// Body roll, pitch, yaw rates (FRD), rad/s.
    pub body_rates: [f32; 3],
    /// Collective thrust, normalised 0..1.
    pub thrust: f32,
    /// Which fields to ignore (see [`type_mask`]).
    pub type_mask: u8,
    /// Thrust vector in FRD, normalised (extension field; used with bit 32).
    pub thrust_body: [f32; 3],
}

/// The `offboard_control_mode` flags a message publishes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OffboardControlFlags {
    pub attitude: bool,
    pub body_rate: bool,
}

/// What one message means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Interpretation {
    /// Neither attitude nor roll+pitch rates: PX4 publishes nothing.
    NoProofOfLife,
    /// Proof of life, but the setpoint is unusable (non-finite or zero quaternion).
    Invalid(OffboardControlFlags),
    /// Proof of life and a setpoint.
    Setpoint(OffboardControlFlags, ControlDemand),
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

fn clamp_thrust(t: f32) -> f64 {
    f64::from(t).clamp(0.0, 1.0)
}

/// Interprets a message received at `t_ns`.
pub(crate) fn interpret(msg: &AttitudeTarget, t_ns: u64) -> Interpretation {
    use type_mask::*;
    let mask = msg.type_mask;
    let flags = OffboardControlFlags {
        attitude: mask & ATTITUDE_IGNORE == 0,
        body_rate: mask & BODY_ROLL_RATE_IGNORE == 0 && mask & BODY_PITCH_RATE_IGNORE == 0,
    };
    if !flags.attitude && !flags.body_rate {
        return Interpretation::NoProofOfLife;
    }
    let ignore_yaw_rate = mask & BODY_YAW_RATE_IGNORE != 0;
    let ignore_throttle = mask & THROTTLE_IGNORE != 0;
    let use_thrust_body = mask & THRUST_BODY_SET != 0;

    // Rates branch (also used as the injection next to an attitude setpoint).
    let rates = if flags.body_rate {
        let [roll, pitch, yaw] = msg.body_rates;
        let rates_ok = finite(&[roll, pitch]) && (ignore_yaw_rate || yaw.is_finite());
        let thrust_ok = ignore_throttle || msg.thrust.is_finite();
        if !(rates_ok && thrust_ok) {
            return Interpretation::Invalid(flags);
        }
        let yaw = if ignore_yaw_rate {
            f64::NAN
        } else {
            f64::from(yaw)
        };
        let thrust = if ignore_throttle {
            0.0
        } else {
            clamp_thrust(msg.thrust)
        };
        Some((Vector3::new(f64::from(roll), f64::from(pitch), yaw), thrust))
    } else {
        None
    };

    if !flags.attitude {
        let (rates_frd, thrust) = rates.unwrap_or((Vector3::zeros(), 0.0));
        return Interpretation::Setpoint(flags, ControlDemand::Rates { rates_frd, thrust });
    }

    let [w, x, y, z] = msg.q;
    let q = Quaternion::new(f64::from(w), f64::from(x), f64::from(y), f64::from(z));
    if !finite(&msg.q) || q.norm() < 1e-6 {
        return Interpretation::Invalid(flags);
    }
    let yaw_rate_ff = if ignore_yaw_rate {
        0.0
    } else if msg.body_rates[2].is_finite() {
        f64::from(msg.body_rates[2])
    } else {
        return Interpretation::Invalid(flags);
    };
    let thrust = if use_thrust_body {
        if !finite(&msg.thrust_body) {
            return Interpretation::Invalid(flags);
        }
        clamp_thrust(-msg.thrust_body[2])
    } else if ignore_throttle {
        0.0
    } else if msg.thrust.is_finite() {
        clamp_thrust(msg.thrust)
    } else {
        return Interpretation::Invalid(flags);
    };
    let demand = ControlDemand::Attitude {
        q_sp: UnitQuaternion::from_quaternion(q),
        thrust,
        yaw_rate_ff,
        rate_injection: rates.map(|(rates_frd, thrust)| RateInjection {
            rates_frd,
            thrust,
            t_ns,
        }),
    };
    Interpretation::Setpoint(flags, demand)
}

#[cfg(test)]
#[path = "setpoint_tests.rs"]
mod tests;
