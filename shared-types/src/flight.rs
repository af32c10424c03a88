//! Samples of the flight stack: what the PX4 bridge publishes from telemetry, what the mission
//! hands the controller, and what the controller hands the bridge. Frames: NED (inertial) and
//! FRD (body), quaternions (w, x, y, z) rotating body FRD into NED, as PX4 uses them.

use iceoryx2::prelude::ZeroCopySend;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::Header;

/// Bits of [`VehicleState::flags`].
pub mod vehicle_flags {
    /// PX4 reports itself armed (HEARTBEAT base_mode bit 128).
    pub const ARMED: u32 = 1 << 0;
    /// PX4's custom_mode is offboard (6 << 16).
    pub const OFFBOARD: u32 = 1 << 1;
    /// No HEARTBEAT from PX4 within the link timeout: the state is the last one received.
    pub const LINK_LOST: u32 = 1 << 2;
    /// The offboard handshake (stream, DO_SET_MODE, arm) finished and PX4 flies our setpoints.
    pub const HANDSHAKE_DONE: u32 = 1 << 3;
    /// The handshake gave up after its retries; see the bridge's log.
    pub const HANDSHAKE_FAILED: u32 = 1 << 4;
    /// PX4 left offboard while armed after the handshake (its failsafe, or a pilot).
    pub const LEFT_OFFBOARD: u32 = 1 << 5;
}

/// PX4's estimate of one drone, published by `px4-bridge` from ODOMETRY (and HEARTBEAT for the
/// mode bits). The controller acts on it.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct VehicleState {
    /// `t_origin_ns`: when the bridge received the ODOMETRY message (CLOCK_MONOTONIC).
    pub header: Header,
    /// PX4's own sample time (ODOMETRY time_usec), µs since PX4 boot.
    pub px4_time_us: u64,
    /// NED, m.
    pub position_ned_m: [f64; 3],
    /// NED, m/s.
    pub velocity_ned_m_s: [f64; 3],
    /// Body FRD -> NED, (w, x, y, z).
    pub attitude_wxyz: [f64; 4],
    /// Body FRD, rad/s.
    pub rate_frd_rad_s: [f64; 3],
    /// HEARTBEAT custom_mode (PX4: main mode << 16 | sub mode << 24).
    pub custom_mode: u32,
    /// Bits of [`vehicle_flags`].
    pub flags: u32,
}

impl VehicleState {
    /// What the controller acts on until the bridge's first state: disarmed, level, never
    /// measured (stale).
    pub fn before_first_odometry() -> Self {
        Self {
            attitude_wxyz: [1.0, 0.0, 0.0, 0.0],
            ..Default::default()
        }
    }

    pub fn armed(&self) -> bool {
        self.flags & vehicle_flags::ARMED != 0
    }
}

/// One IMU reading from PX4 (HIGHRES_IMU), published by `px4-bridge`.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct ImuSample {
    /// `t_origin_ns`: when the bridge received it.
    pub header: Header,
    /// HIGHRES_IMU time_usec, µs since PX4 boot.
    pub px4_time_us: u64,
    /// Specific force, body FRD, m/s² (about (0, 0, -9.81) in hover).
    pub specific_force_frd_m_s2: [f64; 3],
    /// Angular rate, body FRD, rad/s.
    pub gyro_frd_rad_s: [f64; 3],
}

/// Rotor speeds from PX4 (ESC_STATUS), published by `px4-bridge`.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct MotorSpeeds {
    /// `t_origin_ns`: when the bridge received it.
    pub header: Header,
    /// ESC_STATUS time_usec, µs since PX4 boot.
    pub px4_time_us: u64,
    /// PX4 motor order, rad/s (ESC_STATUS rpm * 2 pi / 60).
    pub rotor_speed_rad_s: [f64; 4],
}

/// The mission's phase, as the controller and the peer see it.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub enum MissionPhase {
    /// On the ground, waiting for both drones' services and the handshake.
    #[default]
    Idle = 0,
    Takeoff = 1,
    Move = 2,
    Hold = 3,
    Land = 4,
    /// Every phase of the scenario ended; holding the last setpoint.
    Done = 5,
}

/// Bits of [`MissionSetpoint::flags`].
pub mod mission_flags {
    /// The drones should be armed and flown in offboard (the bridge starts its handshake).
    pub const ARM_REQUEST: u32 = 1 << 0;
    /// The tension loop is on: the payload is meant to hang from the cables.
    pub const TENSION_ENABLED: u32 = 1 << 1;
    /// The peer has not been heard within the configured time: holding.
    pub const PEER_LOST: u32 = 1 << 2;
    /// The path is frozen (peer lost or phase timed out): the setpoint does not advance.
    pub const HOLDING: u32 = 1 << 3;
    /// The running phase did not end within its timeout.
    pub const TIMED_OUT: u32 = 1 << 4;
    /// This drone is ready (path done, within tolerance for the settle time).
    pub const READY: u32 = 1 << 5;
    /// The peer reported itself ready in the running phase.
    pub const PEER_READY: u32 = 1 << 6;
}

/// The nominal setpoint of one drone at one instant, published by `mission` at 100 Hz.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct MissionSetpoint {
    /// `t_origin_ns`: the mission tick's time.
    pub header: Header,
    pub phase: MissionPhase,
    /// Index of the running phase in the scenario (its number of phases once done).
    pub phase_index: u32,
    /// CLOCK_MONOTONIC time the running phase started.
    pub phase_start_ns: u64,
    /// Bits of [`mission_flags`].
    pub flags: u32,
    /// Nominal position setpoint (the paper's ξ̄_d), NED, m.
    pub position_ned_m: [f64; 3],
    /// Its time derivative along the path, NED, m/s (feed-forward; zero in a step).
    pub velocity_ned_m_s: [f64; 3],
    /// Its second derivative, NED, m/s².
    pub acceleration_ned_m_s2: [f64; 3],
    /// Yaw setpoint, rad (NED, from north towards east).
    pub yaw_rad: f64,
    /// The peer's nominal position setpoint at the same instant (same plan), NED, m: with it the
    /// controller computes the static tension T_d of the formation.
    pub peer_position_ned_m: [f64; 3],
}

/// Bits of [`AttitudeSetpoint::flags`].
pub mod setpoint_flags {
    /// No tension sample younger than the configured age: position-only control.
    pub const POSITION_ONLY: u32 = 1 << 0;
    /// The odometry used is older than the configured age.
    pub const STALE_ODOMETRY: u32 = 1 << 1;
    /// No mission setpoint younger than the configured age: holding the last one.
    pub const STALE_MISSION: u32 = 1 << 2;
    /// A non-finite input or result: the output is the safe fallback (level, hover thrust).
    pub const NON_FINITE: u32 = 1 << 3;
    /// The desired tilt was limited.
    pub const TILT_LIMITED: u32 = 1 << 4;
    /// The thrust was limited.
    pub const THRUST_LIMITED: u32 = 1 << 5;
    /// Not armed: integrators held at zero; the output only keeps the offboard stream alive.
    pub const IDLE: u32 = 1 << 6;
    /// Copied from the mission: the bridge should perform the offboard handshake.
    pub const ARM_REQUEST: u32 = 1 << 7;
    /// The tension sample used was flagged by the tension stage.
    pub const TENSION_FLAGGED: u32 = 1 << 8;
    /// The geometric baseline law computed this setpoint (`controller.law = "geometric"`).
    pub const GEOMETRIC: u32 = 1 << 9;
}

/// Bits of [`AttitudeSetpoint::given_inputs`]: which inputs the step was handed (fresh or not).
pub mod given_inputs {
    /// A vehicle state from the bridge (without it the step saw
    /// `VehicleState::before_first_odometry()`).
    pub const ODOMETRY: u32 = 1 << 0;
    /// A tension sample, whose sequence is `given_tension_sequence`.
    pub const TENSION: u32 = 1 << 1;
    /// A mission setpoint, whose sequence is `given_mission_sequence`.
    pub const MISSION: u32 = 1 << 2;
}

/// What the controller hands the PX4 bridge, at 100 Hz, with what it was computed from.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct AttitudeSetpoint {
    /// `t_origin_ns`: that of the tension sample used (its physical measurement), or of the
    /// odometry when no tension was used.
    pub header: Header,
    /// `t_origin_ns` of the tension sample used (0 if none).
    pub tension_origin_ns: u64,
    /// `t_origin_ns` of the vehicle state used.
    pub odometry_origin_ns: u64,
    /// Sequence numbers of the inputs used (tension, odometry, mission), for replay.
    pub tension_sequence: u64,
    pub odometry_sequence: u64,
    pub mission_sequence: u64,
    /// Desired attitude, body FRD -> NED, (w, x, y, z).
    pub attitude_wxyz: [f64; 4],
    /// Collective thrust, N (the bridge normalises it with the hover-throttle map).
    pub thrust_n: f64,
    /// Bits of [`setpoint_flags`].
    pub flags: u32,
    pub phase: MissionPhase,
    /// Nominal setpoint ξ̄_d, NED, m.
    pub nominal_position_ned_m: [f64; 3],
    /// Setpoint after the tension shift ξ_d, NED, m.
    pub shifted_position_ned_m: [f64; 3],
    /// Static tension expected T_d (force the drone exerts on the cable), NED, N.
    pub tension_desired_ned_n: [f64; 3],
    /// Low-pass filtered measured tension T_f (same convention), NED, N.
    pub tension_filtered_ned_n: [f64; 3],
    /// Desired acceleration from the velocity PID, NED, m/s².
    pub acceleration_desired_ned_m_s2: [f64; 3],
    /// The time the step ran at (its `now_ns`), so that a replay can run it again.
    pub step_ns: u64,
    /// Bits of [`given_inputs`]: the inputs handed to the step, stale ones included.
    pub given_inputs: u32,
    /// Sequence of the tension sample handed to the step (used or too old to use).
    pub given_tension_sequence: u64,
    /// Sequence of the mission setpoint handed to the step (used or too old to use).
    pub given_mission_sequence: u64,
}
