//! Ground truth from the plant, for evaluation only: the companion services never read it.

use iceoryx2::prelude::ZeroCopySend;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::Header;

/// Pose and motion of one rigid body.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct BodyTruth {
    /// Centre of mass, NED, m.
    pub position_ned_m: [f64; 3],
    /// Velocity of the centre of mass, NED, m/s.
    pub velocity_ned_m_s: [f64; 3],
    /// Attitude, body FRD -> NED, (w, x, y, z).
    pub attitude_wxyz: [f64; 4],
    /// Angular rate, body FRD, rad/s.
    pub rate_frd_rad_s: [f64; 3],
}

/// One drone as the plant knows it.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct DroneTruth {
    pub body: BodyTruth,
    /// Rotor speeds, rad/s, PX4 motor order.
    pub rotor_speed_rad_s: [f64; 4],
    /// True cable pull on the drone at its anchor, body FRD, N (what its force sensor measures).
    pub anchor_force_frd_n: [f64; 3],
    /// The emulated PX4's position estimate (what it reports over MAVLink), NED, m.
    pub estimate_position_ned_m: [f64; 3],
    /// The motion-capture position fed to that estimator (truth + perturbation), NED, m.
    pub mocap_position_ned_m: [f64; 3],
    /// PX4 custom_mode as in HEARTBEAT (main mode << 16 | sub mode << 24).
    pub custom_mode: u32,
    /// 1 when armed.
    pub armed: u32,
    /// Times PX4's failsafe fired since start.
    pub failsafe_count: u32,
    /// Bits of [`crash_flags`].
    pub crash_flags: u32,
}

/// Why a drone counts as crashed.
pub mod crash_flags {
    /// Entered an obstacle's volume.
    pub const OBSTACLE: u32 = 1 << 0;
    /// Left the arena.
    pub const ARENA: u32 = 1 << 1;
    /// Hit the ground too fast or tipped over.
    pub const GROUND: u32 = 1 << 2;
    /// Tilted beyond 90 degrees in the air.
    pub const FLIPPED: u32 = 1 << 3;
}

/// What the payload touches.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub enum ContactKind {
    #[default]
    Free = 0,
    Ground = 1,
    Box = 2,
}

/// The whole plant at one instant, published by `sim-plant` on `taut/plant/truth`.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct PlantTruth {
    /// `t_origin_ns` is the CLOCK_MONOTONIC instant the state belongs to.
    pub header: Header,
    /// Simulated time since the plant started, ns.
    pub sim_time_ns: u64,
    pub drones: [DroneTruth; 2],
    pub payload: BodyTruth,
    /// Cable tension, N (0 when slack).
    pub cable_tension_n: [f64; 2],
    /// Cable stretch beyond its rest length, m (negative when slack).
    pub cable_stretch_m: [f64; 2],
    pub payload_contact: ContactKind,
    /// Total normal force of the payload's contact, N.
    pub payload_normal_force_n: f64,
}
