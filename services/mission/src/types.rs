//! What the mission stage hands out: its output, events, counters and setup errors.

use shared_types::{MissionPhase, MissionSetpoint};

use crate::signal::PeerSignal;

/// Most phases a scenario may have (fixed tables, no allocation per step).
pub const MAX_PHASES: usize = 32;

/// Why a mission could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum MissionError {
    #[error("{0}")]
    Config(String),
    #[error("drone index {0}: a scenario has drones 0 and 1")]
    DroneIndex(usize),
    #[error("key `mission.peer` = {peer:?}: the scenario's other drone is {expected:?}")]
    PeerMismatch { peer: String, expected: String },
    #[error("scenario {name}: {n} phases, at most {MAX_PHASES}")]
    TooManyPhases { name: String, n: usize },
    #[error("drone id: {0}")]
    Id(#[from] crate::signal::SignalError),
}

/// Something the shell logs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MissionEvent {
    /// Both drones idle-ready: ARM_REQUEST is now set.
    ArmRequested,
    /// The handshake did not complete on both drones within `arm_timeout_s`: staying in Idle.
    ArmTimedOut,
    /// Phase `index` started (`ended`: the phase that ended for it, none when leaving Idle).
    PhaseStarted {
        index: u32,
        phase: MissionPhase,
        ended: Option<u32>,
    },
    /// The last phase (`last`) ended.
    Done { last: u32 },
    /// No valid peer signal for `peer_timeout_s`.
    PeerLost,
    /// A valid peer signal again (also the first one heard).
    PeerRegained,
    /// The peer holds for its own reason (it lost us, or its phase timed out): we hold too.
    PeerHolding,
    /// The peer's reason to hold is gone.
    PeerResumed,
    /// Phase `index` did not end within its `timeout_s` (path time): frozen for good.
    TimedOut { index: u32 },
}

/// What one [`crate::MissionStage::step`] produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionOutput {
    /// For the controller (header: `t_origin_ns` = the tick's time; the publisher stamps the rest).
    pub setpoint: MissionSetpoint,
    /// For the peer.
    pub signal: PeerSignal,
    pub event: Option<MissionEvent>,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MissionCounters {
    pub ticks: u64,
    /// Distinct signals handed to `step` from an id other than the configured peer.
    pub unexpected_sender: u64,
}
