//! The MAVLink v2 endpoint of each emulated PX4 v1.16 drone, over UDP on loopback.
//!
//! It behaves like PX4 SITL's onboard link (`mavlink start -m onboard`) towards the companion
//! software, pymavlink or MAVSDK:
//!
//! - [`config`]: [`LinkConfig`] (PX4 SITL ports: bind 127.0.0.1:14580+i, stream to
//!   127.0.0.1:14540+i, system id 1+i, component 1) and [`StreamRates`] (PX4's onboard
//!   defaults: HEARTBEAT 1 Hz, ATTITUDE_QUATERNION 50, HIGHRES_IMU 50, LOCAL_POSITION_NED 30,
//!   ODOMETRY 30, ESC_STATUS 10).
//! - [`telemetry`]: [`Telemetry`], the vehicle snapshot the streams are built from.
//! - [`outbound`]: each message filled the way PX4's stream classes fill it.
//! - [`schedule`]: [`StreamSchedule`], per-stream intervals; MAV_CMD_SET_MESSAGE_INTERVAL.
//! - [`codec`]: datagram framing with rejects counted by kind, and a reusable frame writer.
//! - [`inbound`]: [`Inbound`], what reaches the vehicle (attitude setpoints, commands,
//!   heartbeats).
//! - [`endpoint`]: [`MavlinkEndpoint`], the socket, `send_due` and `poll`.
//!
//! Where PX4's behaviour decides a detail, the endpoint follows PX4 v1.16:
//! - Addressing: streams go to `remote` until the first datagram arrives, then (once) to its
//!   source, like PX4's UDP link; COMMAND_ACK and TIMESYNC replies go to the requester.
//! - COMMAND_LONG is accepted only for our exact system id and component ours or 0
//!   (`evaluate_target_ok`; system 0 only for REQUEST_AUTOPILOT_CAPABILITIES/PROTOCOL_VERSION);
//!   SET_ATTITUDE_TARGET for system and component each ours or 0.
//! - ODOMETRY carries EKF2's odometry as PX4's stream does: frame_id and child_frame_id both
//!   MAV_FRAME_LOCAL_NED (velocity in NED), estimator_type AUTOPILOT.
//! - Frames out are MAVLink 2, one per datagram; frames in may be MAVLink 1 or 2 (signed frames
//!   are accepted, signatures not checked: PX4 v1.16 does not sign).

pub mod codec;
pub mod config;
pub mod endpoint;
pub mod inbound;
pub mod outbound;
pub mod schedule;
pub mod telemetry;

pub use config::{
    LinkConfig, LinkConfigError, LinkOpenError, Stream, StreamRates, MAV_COMP_ID_AUTOPILOT1,
    PX4_SITL_LOCAL_PORT_BASE, PX4_SITL_REMOTE_PORT_BASE,
};
pub use endpoint::{LinkCounters, MavlinkEndpoint};
pub use inbound::Inbound;
pub use mavlink::dialects::common::MavResult;
pub use schedule::{IntervalRequest, StreamSchedule};
pub use telemetry::{
    px4_custom_mode, Telemetry, MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MAV_MODE_FLAG_SAFETY_ARMED,
    PX4_MAIN_MODE_OFFBOARD, PX4_MAIN_MODE_POSCTL,
};
