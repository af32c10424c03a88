//! The commander: modes, arming, offboard proof of life, the offboard-loss failsafe, land
//! detection and auto-disarm. See the module doc of [`crate::commander`] for the PX4 sources.

use nalgebra::Vector3;

use super::demand::ControlDemand;
use super::land_detector::{LandDetector, LandInputs};
use super::modes::{
    decode_set_mode, mav_cmd, mav_state, mode_flag, CommandLong, MavResult, ModeRequest, NavState,
    FORCE_MAGIC,
};
use super::params::{CommanderParams, CommanderParamsError, OffboardLossAction};
use super::setpoint::{interpret, AttitudeTarget, Interpretation, OffboardControlFlags};
use super::stream::{secs_to_ns, OffboardStream};
use crate::estimator::VehicleEstimate;

/// Counts of what the commander has seen and done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CommanderCounters {
    /// SET_ATTITUDE_TARGET messages received.
    pub setpoint_messages: u64,
    /// Messages that counted as offboard proof of life.
    pub proof_of_life: u64,
    /// Messages ignoring both the attitude and the roll/pitch rates (no proof of life).
    pub no_proof_of_life: u64,
    /// Messages rejected as invalid (NaN, zero quaternion); the last valid setpoint is kept.
    pub invalid_setpoints: u64,
    /// Times the offboard-loss failsafe engaged.
    pub failsafe_fired: u64,
    /// Commands answered TEMPORARILY_REJECTED.
    pub rejected_commands: u64,
    /// DO_SET_MODE requests for real PX4 modes the emulation does not run.
    pub not_emulated_modes: u64,
    /// `update` calls with a non-finite estimate (the last finite one was used).
    pub invalid_estimates: u64,
    /// Automatic disarms (landed, or no take-off after arming).
    pub auto_disarms: u64,
}

/// Where a hold mode holds.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HoldTarget {
    position_ned: Vector3<f64>,
    yaw: f64,
}

/// PX4 v1.16's commander as seen over MAVLink.
#[derive(Debug, Clone)]
pub struct Commander {
    params: CommanderParams,
    disarm_land_ns: Option<u64>,
    disarm_preflight_ns: Option<u64>,
    stream: OffboardStream,
    /// Flags of the last `offboard_control_mode` (decides the offboard control mode).
    ocm: Option<OffboardControlFlags>,
    /// Last valid setpoint received while in offboard.
    offboard_demand: Option<ControlDemand>,
    armed: bool,
    armed_at_ns: u64,
    have_taken_off: bool,
    landed_since_ns: Option<u64>,
    user_intent: NavState,
    nav_after_disarm: NavState,
    nav_state: NavState,
    failsafe: bool,
    hold: Option<HoldTarget>,
    land: LandDetector,
    last_estimate: Option<VehicleEstimate>,
    counters: CommanderCounters,
}

fn positive_ns(s: f64) -> Option<u64> {
    (s > 0.0).then(|| secs_to_ns(s))
}

impl Commander {
    /// A disarmed commander in Position mode.
    pub fn new(params: CommanderParams) -> Result<Self, CommanderParamsError> {
        params.validate()?;
        Ok(Commander {
            disarm_land_ns: positive_ns(params.disarm_land_s),
            disarm_preflight_ns: positive_ns(params.disarm_preflight_s)
                .map(|ns| ns + secs_to_ns(params.spoolup_time_s.max(0.0))),
            stream: OffboardStream::new(
                params.offboard_availability,
                params.offboard_loss_timeout_s,
            ),
            land: LandDetector::new(params.land_detector.clone()),
            params,
            ocm: None,
            offboard_demand: None,
            armed: false,
            armed_at_ns: 0,
            have_taken_off: false,
            landed_since_ns: None,
            user_intent: NavState::Position,
            nav_after_disarm: NavState::Position,
            nav_state: NavState::Position,
            failsafe: false,
            hold: None,
            last_estimate: None,
            counters: CommanderCounters::default(),
        })
    }

    /// Puts the commander in the state of a vehicle flown up by its pilot: armed at `t_ns`,
    /// taken off, holding position in Position mode (a scenario that starts in hover).
    pub fn start_airborne(&mut self, t_ns: u64) {
        self.armed = true;
        self.armed_at_ns = t_ns;
        self.have_taken_off = true;
        self.landed_since_ns = None;
        self.land = LandDetector::airborne(self.params.land_detector.clone());
        self.nav_state = NavState::Position;
        self.user_intent = NavState::Position;
        self.hold = None;
    }

    /// A SET_ATTITUDE_TARGET received at `t_ns`.
    pub fn on_attitude_target(&mut self, t_ns: u64, msg: &AttitudeTarget) {
        self.counters.setpoint_messages += 1;
        let (flags, demand) = match interpret(msg, t_ns) {
            Interpretation::NoProofOfLife => {
                self.counters.no_proof_of_life += 1;
                return;
            }
            Interpretation::Invalid(flags) => {
                self.counters.invalid_setpoints += 1;
                (flags, None)
            }
            Interpretation::Setpoint(flags, demand) => (flags, Some(demand)),
        };
        self.counters.proof_of_life += 1;
        self.stream.on_message(t_ns);
        self.ocm = Some(flags);
        // PX4 publishes the setpoint only while the vehicle is in OFFBOARD.
        if self.nav_state == NavState::Offboard && demand.is_some() {
            self.offboard_demand = demand;
        }
    }

    /// A COMMAND_LONG received at `t_ns`: DO_SET_MODE and COMPONENT_ARM_DISARM; anything else
    /// is UNSUPPORTED.
    pub fn on_command(&mut self, t_ns: u64, cmd: &CommandLong) -> MavResult {
        let result = match cmd.command {
            mav_cmd::DO_SET_MODE => self.set_mode(t_ns, &cmd.params),
            mav_cmd::COMPONENT_ARM_DISARM => self.arm_disarm(t_ns, &cmd.params),
            _ => MavResult::Unsupported,
        };
        if result == MavResult::TemporarilyRejected {
            self.counters.rejected_commands += 1;
        }
        result
    }

    fn set_mode(&mut self, t_ns: u64, params: &[f32; 7]) -> MavResult {
        let mode = match decode_set_mode(params) {
            ModeRequest::NoChange => return MavResult::Accepted,
            ModeRequest::UnsupportedAutoSubMode => return MavResult::TemporarilyRejected,
            ModeRequest::NotEmulated => {
                self.counters.not_emulated_modes += 1;
                return MavResult::TemporarilyRejected;
            }
            ModeRequest::Emulated(mode) => mode,
        };
        // UserModeIntention::change: always allowed while disarmed; Land is forced.
        if self.armed && mode != NavState::Land && !self.can_run(mode, t_ns) {
            return MavResult::TemporarilyRejected;
        }
        self.user_intent = mode;
        if !mode.prevents_arming() {
            self.nav_after_disarm = mode;
        }
        self.evaluate_modes(t_ns);
        MavResult::Accepted
    }

    fn arm_disarm(&mut self, t_ns: u64, params: &[f32; 7]) -> MavResult {
        if !params[0].is_finite() {
            return MavResult::Unsupported;
        }
        let forced = params[1].is_finite() && params[1].round() as i64 == FORCE_MAGIC;
        match params[0].round() as i64 {
            1 => self.arm(t_ns),
            0 => self.disarm(forced),
            _ => MavResult::Unsupported,
        }
    }

    /// PX4's mode requirements (HealthAndArmingChecks): Position needs manual control and a
    /// position estimate, Hold a position estimate, Offboard the offboard signal.
    fn can_run(&self, mode: NavState, t_ns: u64) -> bool {
        let position_valid = self.last_estimate.is_some_and(|e| e.position_valid);
        match mode {
            NavState::Position => self.params.rc_present && position_valid,
            NavState::Hold => position_valid,
            NavState::Land => true,
            NavState::Offboard => self.stream.available(t_ns),
        }
    }

    /// Commands from outside always run the arming checks, forced or not (Commander::arm is
    /// called with `run_preflight_checks = from_external || !forced`).
    fn arm(&mut self, t_ns: u64) -> MavResult {
        if self.armed {
            return MavResult::Accepted;
        }
        if self.nav_state.prevents_arming() || !self.can_run(self.nav_state, t_ns) {
            return MavResult::TemporarilyRejected;
        }
        self.armed = true;
        self.armed_at_ns = t_ns;
        self.have_taken_off = false;
        self.landed_since_ns = None;
        self.hold = None;
        self.evaluate_modes(t_ns);
        MavResult::Accepted
    }

    /// Disarming needs landed or maybe-landed unless forced (Commander::disarm).
    fn disarm(&mut self, forced: bool) -> MavResult {
        if !self.armed {
            return MavResult::Accepted;
        }
        if !(forced || self.land.landed() || self.land.maybe_landed()) {
            return MavResult::TemporarilyRejected;
        }
        self.do_disarm();
        MavResult::Accepted
    }

    fn do_disarm(&mut self) {
        self.armed = false;
        self.failsafe = false;
        self.landed_since_ns = None;
        self.user_intent = self.nav_after_disarm;
        self.set_nav(self.user_intent);
    }

    fn set_nav(&mut self, nav: NavState) {
        if nav != self.nav_state {
            self.nav_state = nav;
            self.hold = None;
            if nav == NavState::Offboard {
                self.offboard_demand = None;
            }
        }
    }

    /// The failsafe state machine, reduced to the offboard-loss mode fallback: it engages when
    /// the signal is lost (COM_OF_LOSS_T) and clears when offboard is available again
    /// (ClearCondition::WhenConditionClears), returning to offboard.
    fn evaluate_modes(&mut self, t_ns: u64) {
        if !self.armed || self.user_intent != NavState::Offboard {
            self.failsafe = false;
            self.set_nav(self.user_intent);
            return;
        }
        if self.failsafe {
            self.failsafe = !self.stream.available(t_ns);
        } else if self.stream.signal_lost(t_ns) {
            self.failsafe = true;
            self.counters.failsafe_fired += 1;
        }
        let nav = if self.failsafe {
            match self.params.offboard_loss_action {
                OffboardLossAction::Land => NavState::Land,
                OffboardLossAction::Hold => NavState::Hold,
                OffboardLossAction::Position => NavState::Position,
            }
        } else {
            NavState::Offboard
        };
        self.set_nav(nav);
    }

    /// One commander step at `t_ns` with the current estimate and the physics' ground-contact
    /// hint; returns what the inner loops should fly.
    pub fn update(
        &mut self,
        t_ns: u64,
        estimate: &VehicleEstimate,
        ground_contact: bool,
    ) -> ControlDemand {
        let est = if estimate.is_finite() {
            self.last_estimate = Some(*estimate);
            *estimate
        } else {
            self.counters.invalid_estimates += 1;
            let mut fallback = VehicleEstimate::at_rest(t_ns, Vector3::zeros());
            fallback.position_valid = false;
            self.last_estimate.unwrap_or(fallback)
        };
        self.evaluate_modes(t_ns);
        let was_landed = self.land.landed();
        let throttle = match (self.nav_state, self.offboard_demand) {
            (NavState::Offboard, Some(d)) if self.armed => d.thrust(),
            _ => None,
        };
        let inputs = LandInputs {
            armed: self.armed,
            climb_rate_controlled: self.nav_state.position_controlled(),
            in_descend: self.nav_state == NavState::Land,
            throttle,
            ground_contact_hint: ground_contact,
            velocity_ned: est.velocity_ned,
            rate_frd: est.rate_frd,
            specific_force_frd: est.specific_force_frd,
        };
        self.land.update(t_ns, &inputs);
        if self.armed && was_landed && !self.land.landed() {
            self.have_taken_off = true;
        }
        if self.armed && self.auto_disarm_due(t_ns) {
            self.counters.auto_disarms += 1;
            self.do_disarm();
        }
        self.demand(&est)
    }

    /// COM_DISARM_LAND after take-off, COM_DISARM_PRFLT + COM_SPOOLUP_TIME before it.
    fn auto_disarm_due(&mut self, t_ns: u64) -> bool {
        if self.have_taken_off {
            let Some(limit) = self.disarm_land_ns else {
                return false;
            };
            if !self.land.landed() {
                self.landed_since_ns = None;
                return false;
            }
            let since = *self.landed_since_ns.get_or_insert(t_ns);
            t_ns.saturating_sub(since) >= limit
        } else {
            self.disarm_preflight_ns
                .is_some_and(|limit| t_ns.saturating_sub(self.armed_at_ns) >= limit)
        }
    }

    fn demand(&mut self, est: &VehicleEstimate) -> ControlDemand {
        if !self.armed {
            return ControlDemand::MotorsOff;
        }
        let hold = *self.hold.get_or_insert(HoldTarget {
            position_ned: est.position_ned,
            yaw: est.yaw(),
        });
        let on_ground = self.land.ground_contact() || self.land.landed();
        let hold_demand = ControlDemand::Position {
            position_ned: hold.position_ned,
            velocity_ned: Vector3::zeros(),
            yaw: hold.yaw,
        };
        match self.nav_state {
            NavState::Offboard => match self.offboard_demand {
                Some(d) => d,
                None if self.land.landed() => ControlDemand::idle(est.yaw()),
                None => hold_demand,
            },
            // PX4's position controller idles on the ground (not taken off, or ground contact).
            _ if on_ground => ControlDemand::idle(est.yaw()),
            NavState::Position | NavState::Hold => hold_demand,
            NavState::Land => ControlDemand::Position {
                position_ned: Vector3::new(hold.position_ned.x, hold.position_ned.y, f64::NAN),
                velocity_ned: Vector3::new(0.0, 0.0, self.params.land_speed_mps),
                yaw: hold.yaw,
            },
        }
    }
}

#[path = "status.rs"]
mod status;

#[cfg(test)]
#[path = "state_machine_tests.rs"]
mod tests;
