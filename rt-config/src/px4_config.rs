//! Config of the PX4 bridge: the MAVLink link and the offboard handshake.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Px4Config {
    /// `serial:/dev/ttyAMA0:921600` (TELEM2 on the Pi), or `udpin:ADDR:PORT` (listen where PX4
    /// SITL or the plant streams to), or `udpout:ADDR:PORT`.
    pub link: String,
    /// Our MAVLink system and component ids (a companion computer: 1 / 191 is PX4's onboard
    /// computer default).
    pub system_id: u8,
    pub component_id: u8,
    /// PX4's system id (MAV_SYS_ID) and autopilot component.
    pub target_system: u8,
    pub target_component: u8,
    /// HEARTBEAT rate, Hz.
    pub heartbeat_hz: f64,
    /// No HEARTBEAT from PX4 for this long means the link is lost, s.
    pub link_timeout_s: f64,
    /// Stream setpoints this long before asking for offboard (PX4 wants > 1 s above 2 Hz), s.
    pub stream_before_offboard_s: f64,
    /// Wait this long for a COMMAND_ACK before resending, s.
    pub ack_timeout_s: f64,
    /// Sends of one command before the handshake gives up.
    pub command_attempts: u32,
    /// Telemetry rates asked with SET_MESSAGE_INTERVAL, Hz.
    pub odometry_hz: f64,
    pub attitude_hz: f64,
    pub imu_hz: f64,
    pub esc_hz: f64,
}

impl Default for Px4Config {
    fn default() -> Self {
        Self {
            link: "udpin:127.0.0.1:14540".to_string(),
            system_id: 1,
            component_id: 191,
            target_system: 1,
            target_component: 1,
            heartbeat_hz: 1.0,
            link_timeout_s: 1.5,
            stream_before_offboard_s: 1.2,
            ack_timeout_s: 0.3,
            command_attempts: 5,
            odometry_hz: 100.0,
            attitude_hz: 100.0,
            imu_hz: 250.0,
            esc_hz: 50.0,
        }
    }
}
