//! What the link reports: the handshake's stage, why it failed, counters.

use mavlink::dialects::common::MavResult;

/// Where the offboard handshake stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandshakeStage {
    /// No ARM_REQUEST in the setpoints, or no setpoint stream.
    Idle,
    /// Streaming setpoints with ARM_REQUEST; DO_SET_MODE once the stream is old enough.
    Streaming,
    /// DO_SET_MODE offboard sent until ACCEPTED.
    SettingOffboard,
    /// COMPONENT_ARM_DISARM(1) sent until ACCEPTED.
    Arming,
    /// Arming accepted; waiting for a HEARTBEAT armed in offboard (within link_timeout_s).
    Confirming,
    /// PX4 is armed in offboard and flies our setpoints.
    Done,
    /// Gave up; see [`LinkStatus::failure`]. Cleared when ARM_REQUEST is cleared.
    Failed,
    /// PX4 left offboard while armed after `Done` (its failsafe, or a pilot). The bridge does
    /// not fight it; cleared when ARM_REQUEST is cleared.
    LeftOffboard,
}

/// Why the handshake gave up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HandshakeFailure {
    SetModeNotAccepted {
        sends: u32,
        last_result: Option<MavResult>,
    },
    ArmNotAccepted {
        sends: u32,
        last_result: Option<MavResult>,
    },
    /// Arming was accepted but no HEARTBEAT showed armed + offboard within link_timeout_s.
    NotConfirmed,
}

impl std::fmt::Display for HandshakeFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let last = |r: &Option<MavResult>| r.map_or("no ack".to_string(), |r| format!("{r:?}"));
        match self {
            Self::SetModeNotAccepted { sends, last_result } => write!(
                f,
                "DO_SET_MODE offboard not accepted after {sends} sends (last: {})",
                last(last_result)
            ),
            Self::ArmNotAccepted { sends, last_result } => write!(
                f,
                "arming not accepted after {sends} sends (last: {})",
                last(last_result)
            ),
            Self::NotConfirmed => write!(
                f,
                "arming accepted but no HEARTBEAT armed in offboard within px4.link_timeout_s"
            ),
        }
    }
}

/// Event counts since `new`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LinkCounters {
    pub setpoints_sent: u64,
    /// Non-finite or non-rotation setpoints not sent.
    pub setpoints_dropped: u64,
    pub heartbeats_sent: u64,
    /// COMMAND_LONG sends, retries included.
    pub commands_sent: u64,
    pub command_retries: u64,
    /// Sends that got no ack within px4.ack_timeout_s.
    pub ack_timeouts: u64,
    pub acks_accepted: u64,
    /// Acks other than ACCEPTED / IN_PROGRESS (TEMPORARILY_REJECTED included).
    pub acks_rejected: u64,
    pub acks_temporarily_rejected: u64,
    pub acks_in_progress: u64,
    /// Acks for a command with nothing of ours waiting (late, duplicate, or not ours).
    pub acks_unexpected: u64,
    /// Handshakes restarted because the setpoint stream stopped.
    pub handshake_restarts: u64,
    pub heartbeats_received: u64,
    pub odometry: u64,
    pub imu: u64,
    pub esc: u64,
    /// Telemetry refused (non-finite, unsupported frame, bad quaternion, ESCs 5+).
    pub telemetry_refused: u64,
    /// Messages from another system or component than the target PX4, ignored.
    pub foreign_messages: u64,
    /// Messages from PX4 the bridge does not use.
    pub other_messages: u64,
    pub intervals_accepted: u64,
    pub intervals_failed: u64,
    pub link_losses: u64,
}

/// A snapshot for logs and tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkStatus {
    pub stage: HandshakeStage,
    pub failure: Option<HandshakeFailure>,
    /// A HEARTBEAT from PX4 within link_timeout_s (as of the last call).
    pub link_up: bool,
    /// [`vehicle_flags`] as of the last call.
    pub flags: u32,
    /// PX4's last HEARTBEAT custom_mode.
    pub custom_mode: u32,
    pub counters: LinkCounters,
}
