//! PX4 v1.16's mode, arming and offboard logic as a companion computer sees it over MAVLink,
//! as a pure state machine driven by timestamps (u64 ns, CLOCK_MONOTONIC-like).
//!
//! Followed from the PX4-Autopilot sources (src/modules/...):
//!
//! - mavlink/mavlink_receiver.cpp `handle_message_set_attitude_target`: the type_mask, which
//!   `offboard_control_mode` flags each message publishes, setpoints published only in
//!   OFFBOARD ([`setpoint`]).
//! - commander/ModeUtil/control_mode.cpp: in OFFBOARD `attitude` is checked before
//!   `body_rate`, so attitude wins when a message sets both.
//! - commander/HealthAndArmingChecks/checks/offboardCheck.cpp: the signal is lost COM_OF_LOSS_T
//!   after the last `offboard_control_mode` ([`stream`], which also models the documented
//!   "2 Hz for more than 1 s" rule and says where it differs).
//! - commander/Commander.cpp `handle_command`: DO_SET_MODE decodes param1/2/3 as `uint8_t`
//!   base mode / main mode / sub mode; an unknown main mode is ACCEPTED and changes nothing;
//!   a refused change is TEMPORARILY_REJECTED; Land is always allowed. ARM_DISARM: `param1`
//!   rounded, anything but 0/1 is UNSUPPORTED; `param2 = 21196` forces; external commands
//!   always run the arming checks; a refused (dis)arm is TEMPORARILY_REJECTED; disarm needs
//!   landed or maybe-landed unless forced.
//! - commander/UserModeIntention.cpp: mode changes are always allowed while disarmed, else
//!   only into modes that can run; after disarm the mode returns to the last selected mode
//!   that does not prevent arming.
//! - commander/HealthAndArmingChecks/checks/modeCheck.cpp: without manual control (no RC)
//!   Position can neither run nor be armed in; Land prevents arming; offboard needs the signal.
//! - commander/failsafe/failsafe.cpp `checkModeFallback` and framework.cpp: offboard loss is a
//!   mode fallback (COM_OBL_RC_ACT) applied immediately (no COM_FAIL_ACT_T hold), cleared when
//!   the signal returns; the action without RC indoors is Land ([`OffboardLossAction`]).
//! - mavlink/streams/HEARTBEAT.hpp: `base_mode` from the control mode, `system_status`
//!   STANDBY / ACTIVE / CRITICAL (armed and in failsafe).
//! - land_detector/MulticopterLandDetector.cpp and Commander `checkForAutoDisarm`: the land
//!   detector ([`land_detector`]), COM_DISARM_LAND and COM_DISARM_PRFLT.
//!
//! Modes emulated: Position (initial; holds where entered), Offboard, Hold (AUTO.LOITER) and
//! Land (AUTO.LAND). Other real PX4 modes are answered TEMPORARILY_REJECTED and counted (PX4
//! would accept some of them while disarmed). Before the first offboard setpoint in Offboard the
//! demand is a position hold where Offboard was entered (PX4 would fly the last attitude
//! setpoint of the previous controller for that one stream period), or idle on the ground.

pub mod demand;
pub mod land_detector;
pub mod modes;
pub mod params;
pub mod setpoint;
mod state_machine;
pub mod stream;

pub use demand::{ControlDemand, RateInjection};
pub use land_detector::{LandDetector, LandDetectorParams};
pub use modes::{CommandLong, MavResult, NavState};
pub use params::{CommanderParams, CommanderParamsError, OffboardLossAction};
pub use setpoint::{AttitudeTarget, OffboardControlFlags};
pub use state_machine::{Commander, CommanderCounters};
pub use stream::OffboardAvailability;

pub use crate::estimator::VehicleEstimate;
