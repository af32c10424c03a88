//! Read-only views of the commander: the HEARTBEAT fields and the state behind them.

use super::{
    mav_state, mode_flag, Commander, CommanderCounters, CommanderParams, LandDetector, NavState,
};

impl Commander {
    /// HEARTBEAT `custom_mode` (PX4 main mode in bits 16..23, sub mode in 24..31).
    pub fn custom_mode(&self) -> u32 {
        self.nav_state.custom_mode()
    }

    /// HEARTBEAT `base_mode` as PX4's HEARTBEAT stream builds it from the control mode.
    pub fn base_mode(&self) -> u8 {
        let mut flags = mode_flag::CUSTOM_MODE_ENABLED;
        if self.armed {
            flags |= mode_flag::SAFETY_ARMED;
        }
        flags |= match self.nav_state {
            NavState::Position => mode_flag::MANUAL_INPUT_ENABLED | mode_flag::STABILIZE_ENABLED,
            NavState::Hold | NavState::Land => {
                mode_flag::AUTO_ENABLED | mode_flag::GUIDED_ENABLED | mode_flag::STABILIZE_ENABLED
            }
            // Attitude offboard runs the attitude controller; rates-only does not.
            NavState::Offboard if self.ocm.is_some_and(|f| f.attitude) => {
                mode_flag::STABILIZE_ENABLED
            }
            NavState::Offboard => 0,
        };
        flags
    }

    /// HEARTBEAT `system_status`: STANDBY disarmed, ACTIVE armed, CRITICAL in failsafe.
    pub fn system_status(&self) -> u8 {
        match (self.armed, self.failsafe) {
            (false, _) => mav_state::STANDBY,
            (true, false) => mav_state::ACTIVE,
            (true, true) => mav_state::CRITICAL,
        }
    }

    /// The mode flown now (after any failsafe).
    pub fn nav_state(&self) -> NavState {
        self.nav_state
    }

    /// The mode last selected by command (PX4's user intention).
    pub fn user_intended_mode(&self) -> NavState {
        self.user_intent
    }

    /// True while armed.
    pub fn is_armed(&self) -> bool {
        self.armed
    }

    /// True while the offboard-loss failsafe is engaged.
    pub fn failsafe_active(&self) -> bool {
        self.failsafe
    }

    /// True once the failsafe has engaged at least once (latched).
    pub fn failsafe_fired(&self) -> bool {
        self.counters.failsafe_fired > 0
    }

    /// Whether offboard may be entered or armed in at `t_ns`.
    pub fn offboard_available(&self, t_ns: u64) -> bool {
        self.stream.available(t_ns)
    }

    /// PX4's `offboard_control_signal_lost` at `t_ns`.
    pub fn offboard_signal_lost(&self, t_ns: u64) -> bool {
        self.stream.signal_lost(t_ns)
    }

    /// Time of the last offboard proof of life, ns.
    pub fn last_proof_of_life_ns(&self) -> Option<u64> {
        self.stream.last_message_ns()
    }

    /// The land detector's state.
    pub fn land_detector(&self) -> &LandDetector {
        &self.land
    }

    /// Counters.
    pub fn counters(&self) -> CommanderCounters {
        self.counters
    }

    /// The configuration in use.
    pub fn params(&self) -> &CommanderParams {
        &self.params
    }
}
