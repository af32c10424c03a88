//! What the endpoint hands to the vehicle, and COMMAND_LONG decoding that survives command ids
//! the dialect's `MavCmd` enum does not list.

use mavlink::dialects::common::{MavCmd, COMMAND_LONG_DATA, SET_ATTITUDE_TARGET_DATA};

/// A message for the emulated autopilot, already filtered by target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Inbound {
    /// SET_ATTITUDE_TARGET (#82) addressed to this system (or system 0) and this component (or 0).
    /// Values are passed on untouched: the commander applies type_mask and validity checks.
    AttitudeTarget {
        /// Sender's timestamp, ms.
        time_boot_ms: u32,
        /// Attitude setpoint (w, x, y, z), body FRD -> NED.
        q: [f32; 4],
        /// Body rate setpoint (roll, pitch, yaw), FRD, rad/s.
        body_rates: [f32; 3],
        /// Collective thrust, normalised 0..1.
        thrust: f32,
        /// ATTITUDE_TARGET_TYPEMASK bits (1/2/4 ignore rates, 32 thrust_body, 64 no thrust,
        /// 128 no attitude).
        type_mask: u8,
        /// 3D thrust setpoint, body FRD, normalised -1..1 (used with type_mask bit 32).
        thrust_body: [f32; 3],
    },
    /// COMMAND_LONG (#76) addressed to this system/component (PX4's target rule). The handler's
    /// result goes back in a COMMAND_ACK; `None` means unsupported.
    Command {
        /// MAV_CMD id.
        command: u16,
        /// param1..param7.
        params: [f32; 7],
        /// Sender (system id, component id).
        from: (u8, u8),
    },
    /// HEARTBEAT from a peer (companion / GCS): proof of life of the link.
    Heartbeat {
        /// Peer system id.
        sysid: u8,
        /// Peer component id.
        compid: u8,
    },
}

/// A decoded COMMAND_LONG with its raw command id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandLong {
    /// MAV_CMD id as sent.
    pub command: u16,
    /// The id as the dialect's enum, when the dialect knows it.
    pub known: Option<MavCmd>,
    /// param1..param7.
    pub params: [f32; 7],
    /// Addressed system.
    pub target_system: u8,
    /// Addressed component.
    pub target_component: u8,
}

/// COMMAND_LONG payload length (MAVLink 2 may trim trailing zeros from it).
const COMMAND_LONG_LEN: usize = 33;

impl CommandLong {
    /// From the crate's parsed message.
    pub fn from_parsed(d: &COMMAND_LONG_DATA) -> CommandLong {
        CommandLong {
            command: d.command as u16,
            known: Some(d.command),
            params: [
                d.param1, d.param2, d.param3, d.param4, d.param5, d.param6, d.param7,
            ],
            target_system: d.target_system,
            target_component: d.target_component,
        }
    }

    /// From the payload bytes, for command ids the crate rejects as an invalid enum value
    /// (PX4 answers those with MAV_RESULT_UNSUPPORTED, so they must still be read).
    pub fn from_payload(payload: &[u8]) -> CommandLong {
        let mut p = [0u8; COMMAND_LONG_LEN];
        let n = payload.len().min(COMMAND_LONG_LEN);
        p[..n].copy_from_slice(&payload[..n]);
        let f = |k: usize| f32::from_le_bytes([p[4 * k], p[4 * k + 1], p[4 * k + 2], p[4 * k + 3]]);
        CommandLong {
            command: u16::from_le_bytes([p[28], p[29]]),
            known: None,
            params: [f(0), f(1), f(2), f(3), f(4), f(5), f(6)],
            target_system: p[30],
            target_component: p[31],
        }
    }

    /// PX4's `evaluate_target_ok`: exact system id (0 allowed only for
    /// REQUEST_AUTOPILOT_CAPABILITIES and REQUEST_PROTOCOL_VERSION, which ignore the
    /// component), component ours or 0.
    pub fn is_for(&self, system_id: u8, component_id: u8) -> bool {
        const REQUEST_AUTOPILOT_CAPABILITIES: u16 = 520;
        const REQUEST_PROTOCOL_VERSION: u16 = 519;
        match self.command {
            REQUEST_AUTOPILOT_CAPABILITIES | REQUEST_PROTOCOL_VERSION => {
                self.target_system == 0 || self.target_system == system_id
            }
            _ => {
                self.target_system == system_id
                    && (self.target_component == component_id || self.target_component == 0)
            }
        }
    }
}

/// SET_ATTITUDE_TARGET as an [`Inbound`], if addressed to us (PX4: system and component each
/// ours or 0).
pub fn attitude_target(
    d: &SET_ATTITUDE_TARGET_DATA,
    system_id: u8,
    component_id: u8,
) -> Option<Inbound> {
    let system_ok = d.target_system == system_id || d.target_system == 0;
    let component_ok = d.target_component == component_id || d.target_component == 0;
    (system_ok && component_ok).then_some(Inbound::AttitudeTarget {
        time_boot_ms: d.time_boot_ms,
        q: d.q,
        body_rates: [d.body_roll_rate, d.body_pitch_rate, d.body_yaw_rate],
        thrust: d.thrust,
        type_mask: d.type_mask.bits(),
        thrust_body: d.thrust_body,
    })
}
