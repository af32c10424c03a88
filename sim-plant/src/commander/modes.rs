//! PX4's mode encoding and the MAVLink numbers the commander answers with.
//!
//! `custom_mode` is PX4's `union px4_custom_mode` (src/modules/commander/px4_custom_mode.h):
//! bytes `reserved:16, main_mode:8, sub_mode:8`, so the main mode sits in bits 16..23 and the
//! sub mode in bits 24..31 of the HEARTBEAT's `custom_mode`.

/// PX4 main modes (`PX4_CUSTOM_MAIN_MODE_*`).
pub mod main_mode {
    pub const MANUAL: u8 = 1;
    pub const ALTCTL: u8 = 2;
    pub const POSCTL: u8 = 3;
    pub const AUTO: u8 = 4;
    pub const ACRO: u8 = 5;
    pub const OFFBOARD: u8 = 6;
    pub const STABILIZED: u8 = 7;
}

/// PX4 AUTO sub modes (`PX4_CUSTOM_SUB_MODE_AUTO_*`).
pub mod auto_sub_mode {
    pub const READY: u8 = 1;
    pub const TAKEOFF: u8 = 2;
    pub const LOITER: u8 = 3;
    pub const MISSION: u8 = 4;
    pub const RTL: u8 = 5;
    pub const LAND: u8 = 6;
    pub const FOLLOW_TARGET: u8 = 8;
    pub const PRECLAND: u8 = 9;
    pub const VTOL_TAKEOFF: u8 = 10;
    /// EXTERNAL1..EXTERNAL8 are 11..=18.
    pub const EXTERNAL1: u8 = 11;
    pub const EXTERNAL8: u8 = 18;
}

/// MAV_MODE_FLAG bits of HEARTBEAT `base_mode`.
pub mod mode_flag {
    pub const CUSTOM_MODE_ENABLED: u8 = 1;
    pub const AUTO_ENABLED: u8 = 4;
    pub const GUIDED_ENABLED: u8 = 8;
    pub const STABILIZE_ENABLED: u8 = 16;
    pub const MANUAL_INPUT_ENABLED: u8 = 64;
    pub const SAFETY_ARMED: u8 = 128;
}

/// MAV_STATE values of HEARTBEAT `system_status`.
pub mod mav_state {
    pub const STANDBY: u8 = 3;
    pub const ACTIVE: u8 = 4;
    pub const CRITICAL: u8 = 5;
}

/// MAV_CMD numbers the commander handles.
pub mod mav_cmd {
    pub const DO_SET_MODE: u16 = 176;
    pub const COMPONENT_ARM_DISARM: u16 = 400;
}

/// `param2` of MAV_CMD_COMPONENT_ARM_DISARM that forces the action (PX4: skips the landed
/// check on disarm).
pub const FORCE_MAGIC: i64 = 21196;

/// The flight modes the emulation runs (PX4 `nav_state`s).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NavState {
    /// POSCTL: position hold where it was entered (no sticks). Initial mode.
    Position,
    /// OFFBOARD: follows SET_ATTITUDE_TARGET.
    Offboard,
    /// AUTO.LOITER (Hold): position hold where it was entered.
    Hold,
    /// AUTO.LAND: descend at MPC_LAND_SPEED holding x/y, disarm on the ground.
    Land,
}

impl NavState {
    /// PX4 main mode number.
    pub fn main_mode(self) -> u8 {
        match self {
            NavState::Position => main_mode::POSCTL,
            NavState::Offboard => main_mode::OFFBOARD,
            NavState::Hold | NavState::Land => main_mode::AUTO,
        }
    }

    /// PX4 sub mode number (0 when the main mode has none).
    pub fn sub_mode(self) -> u8 {
        match self {
            NavState::Position | NavState::Offboard => 0,
            NavState::Hold => auto_sub_mode::LOITER,
            NavState::Land => auto_sub_mode::LAND,
        }
    }

    /// HEARTBEAT `custom_mode`: main mode in bits 16..23, sub mode in bits 24..31.
    pub fn custom_mode(self) -> u32 {
        (u32::from(self.main_mode()) << 16) | (u32::from(self.sub_mode()) << 24)
    }

    /// Modes PX4 flies with its position controller (climb rate controlled).
    pub fn position_controlled(self) -> bool {
        !matches!(self, NavState::Offboard)
    }

    /// PX4 `mode_req_prevent_arming`: Land cannot be armed in.
    pub fn prevents_arming(self) -> bool {
        matches!(self, NavState::Land)
    }
}

/// MAV_RESULT of a COMMAND_ACK.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum MavResult {
    Accepted = 0,
    TemporarilyRejected = 1,
    Denied = 2,
    Unsupported = 3,
    Failed = 4,
}

impl MavResult {
    /// The MAV_RESULT number.
    pub fn as_u8(self) -> u8 {
        self as u8
    }
}

/// A COMMAND_LONG as the commander sees it (targets already checked by the link).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandLong {
    /// MAV_CMD number.
    pub command: u16,
    /// param1..param7.
    pub params: [f32; 7],
}

/// What a DO_SET_MODE asks for, decoded the way PX4's Commander decodes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ModeRequest {
    /// A mode the emulation runs.
    Emulated(NavState),
    /// A real PX4 mode the emulation does not run (manual modes, mission, RTL, takeoff, ...).
    NotEmulated,
    /// An AUTO sub mode PX4 rejects ("Unsupported auto mode").
    UnsupportedAutoSubMode,
    /// Nothing PX4 recognises: PX4 accepts the command and changes nothing.
    NoChange,
}

/// PX4 casts each float parameter to `uint8_t`: a truncation toward zero, then the low byte.
fn param_u8(p: f32) -> u8 {
    if p.is_finite() {
        (p as i64) as u8
    } else {
        0
    }
}

/// Decodes DO_SET_MODE as Commander::handle_command does: param1 base mode, param2 custom main
/// mode, param3 custom sub mode, each cast to `uint8_t`.
pub(crate) fn decode_set_mode(params: &[f32; 7]) -> ModeRequest {
    let base_mode = param_u8(params[0]);
    let main = param_u8(params[1]);
    let sub = param_u8(params[2]);
    if base_mode & mode_flag::CUSTOM_MODE_ENABLED != 0 {
        match main {
            // POSCTL sub modes other than SLOW (2) all select POSCTL ("default:" branch).
            main_mode::POSCTL if sub == 2 => ModeRequest::NotEmulated,
            main_mode::POSCTL => ModeRequest::Emulated(NavState::Position),
            main_mode::OFFBOARD => ModeRequest::Emulated(NavState::Offboard),
            main_mode::AUTO => match sub {
                auto_sub_mode::LOITER => ModeRequest::Emulated(NavState::Hold),
                auto_sub_mode::LAND => ModeRequest::Emulated(NavState::Land),
                // Sub mode 0 selects MISSION.
                0 | auto_sub_mode::MISSION | auto_sub_mode::RTL | auto_sub_mode::TAKEOFF => {
                    ModeRequest::NotEmulated
                }
                auto_sub_mode::FOLLOW_TARGET | auto_sub_mode::PRECLAND => ModeRequest::NotEmulated,
                auto_sub_mode::EXTERNAL1..=auto_sub_mode::EXTERNAL8 => ModeRequest::NotEmulated,
                _ => ModeRequest::UnsupportedAutoSubMode,
            },
            main_mode::MANUAL | main_mode::ALTCTL | main_mode::ACRO | main_mode::STABILIZED => {
                ModeRequest::NotEmulated
            }
            _ => ModeRequest::NoChange,
        }
    } else if base_mode & mode_flag::AUTO_ENABLED != 0 {
        ModeRequest::NotEmulated
    } else if base_mode & mode_flag::MANUAL_INPUT_ENABLED != 0 {
        if base_mode & mode_flag::GUIDED_ENABLED != 0 {
            ModeRequest::Emulated(NavState::Position)
        } else {
            ModeRequest::NotEmulated
        }
    } else {
        ModeRequest::NoChange
    }
}
