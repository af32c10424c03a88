//! taut's MAVLink v2 bridge to PX4 v1.16: attitude setpoints out (SET_ATTITUDE_TARGET), the
//! offboard handshake (stream, DO_SET_MODE offboard, arm), telemetry in (ODOMETRY, HIGHRES_IMU,
//! ESC_STATUS, HEARTBEAT).
//!
//! [`OffboardLink`] is the pure core: messages and setpoints in, messages and samples out, time
//! as an argument. [`frame`] frames bytes with every drop counted. [`shell`] runs it on a UDP or
//! serial link with iceoryx2 topics.

mod command;
pub mod frame;
mod link;
pub mod shell;
mod status;
mod telemetry;
mod transport;

pub use link::{HandshakeFailure, HandshakeStage, LinkCounters, LinkStatus, OffboardLink};
/// The mavlink crate the bridge speaks (0.21, common dialect), for callers naming its types.
pub use mavlink;
pub use mavlink::dialects::common::MavMessage;
pub use mavlink::MavHeader;
use shared_types::{ImuSample, MotorSpeeds, VehicleState};

/// MAV_CMD_DO_SET_MODE.
pub const CMD_DO_SET_MODE: u16 = 176;
/// MAV_CMD_COMPONENT_ARM_DISARM.
pub const CMD_ARM_DISARM: u16 = 400;
/// MAV_CMD_SET_MESSAGE_INTERVAL.
pub const CMD_SET_MESSAGE_INTERVAL: u16 = 511;
/// SET_ATTITUDE_TARGET type_mask: the three body rates ignored (attitude + thrust).
pub const TYPE_MASK_ATTITUDE_THRUST: u8 = 7;
/// PX4's main mode offboard in HEARTBEAT custom_mode (main mode << 16).
pub const PX4_CUSTOM_MODE_OFFBOARD: u32 = 6 << 16;
/// A gap in the setpoint stream longer than this restarts an unfinished handshake, s.
pub const STREAM_GAP_S: f64 = 0.5;

/// A sample decoded from PX4's telemetry, ready to publish.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Telemetry {
    State(VehicleState),
    Imu(ImuSample),
    Motors(MotorSpeeds),
}

/// The config cannot drive the bridge; the message names the key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BridgeConfigError {
    #[error("px4 config: {0}")]
    Px4(String),
    #[error("key `{key}` = {value}: {why}")]
    Vehicle {
        key: &'static str,
        value: f64,
        why: &'static str,
    },
}

/// PX4's thrust map (as its position controller uses it): throttle = hover_throttle · a / g
/// with a = thrust / mass the specific thrust, clamped to [0, 1]. Non-finite input gives 0.
pub fn normalized_thrust(
    thrust_n: f64,
    mass_kg: f64,
    hover_throttle: f64,
    gravity_m_s2: f64,
) -> f32 {
    let t = hover_throttle * (thrust_n / mass_kg) / gravity_m_s2;
    if t.is_finite() {
        t.clamp(0.0, 1.0) as f32
    } else {
        0.0
    }
}

#[cfg(test)]
#[path = "test_harness.rs"]
mod test_harness;

#[cfg(test)]
#[path = "link_tests.rs"]
mod link_tests;

#[cfg(test)]
#[path = "handshake_tests.rs"]
mod handshake_tests;
