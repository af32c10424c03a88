//! Pure-Rust emulation of PX4 v1.16's multicopter inner loops with PX4's default gains, as
//! the plant's emulated autopilot runs them.
//!
//! Ported from PX4-Autopilot sources read through the code index (each module names its own
//! files): mc_att_control/AttitudeControl/AttitudeControl.cpp, lib/rate_control/
//! rate_control.cpp, mc_pos_control/PositionControl/{PositionControl,ControlMath}.cpp,
//! control_allocator/ControlAllocation/{ControlAllocationPseudoInverse,
//! ControlAllocationSequentialDesaturation,ControlAllocation}.cpp,
//! control_allocator/ActuatorEffectiveness/ActuatorEffectivenessRotors.cpp,
//! lib/mathlib/math/filter/LowPassFilter2p.hpp; the module wrappers (MulticopterRateControl,
//! MulticopterPositionControl, VehicleAngularVelocity) and the parameter defaults
//! (IMU_DGYRO_CUTOFF 20 Hz, MC_YAW_TQ_CUTOFF 2 Hz, MPC_VELD_LP 5 Hz) from excerpts.
//! The index's AttitudeControl.cpp is a later revision with a reference model; the v1.16
//! law is its documented legacy path (reference feed-forward off), which is what is ported.
//!
//! - [`attitude`]: [`AttitudeControl`], quaternion P with tilt priority -> body rates.
//! - [`rate`]: [`RateControl`], PID with D on the filtered angular acceleration -> torque.
//! - [`allocation`]: [`ControlAllocation`], normalized pseudo-inverse with sequential
//!   desaturation (MC_AIRMODE 0 by default) -> motor u in [0, 1] and saturation flags.
//! - [`motor_map`]: [`MotorMap`], the plant-side map u -> commanded rotor speed.
//! - [`position`]: [`PositionControl`], PX4's position/velocity cascade and thrust-to-attitude.
//! - [`chain`]: [`MultirotorInnerLoops`], all of them chained, holding on rejected steps.
//! - [`filters`], [`control_math`]: PX4's filters and ControlMath helpers.
//!
//! Conventions: NED world, FRD body, quaternions body FRD -> NED. Motor order and geometry
//! are PX4 quad X as the plant has it: motor 1 front right CCW, 2 rear left CCW, 3 front left
//! CW, 4 rear right CW; a CCW rotor's reaction torque on the body is +c_m T about body z.
//! Normalized torque and thrust are PX4's `vehicle_torque_setpoint` / `vehicle_thrust_setpoint`
//! units (thrust_body z = -thrust).

pub mod allocation;
pub mod attitude;
pub mod chain;
pub mod control_math;
pub mod errors;
pub mod filters;
pub mod motor_map;
pub mod position;
pub mod rate;

pub use allocation::{
    Airmode, AllocationOutput, AllocationParams, ControlAllocation, RotorGeometry,
};
pub use attitude::{AttitudeControl, AttitudeControlParams};
pub use chain::{InnerLoopParams, InnerLoopStatus, MultirotorInnerLoops, VehicleState};
pub use errors::{ParamsError, StepError};
pub use filters::{AlphaFilter, BlockDerivative, LowPassFilter2p};
pub use motor_map::{MotorMap, MotorMapParams};
pub use position::{
    PositionControl, PositionControlOutput, PositionControlParams, TrajectorySetpoint, PX4_ONE_G,
};
pub use rate::{RateControl, RateControlParams};
