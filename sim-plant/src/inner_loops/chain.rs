//! The emulated PX4's multicopter control chain: position -> attitude -> rate -> allocation ->
//! motor map, one step of each per call (call at 400 Hz to run the attitude and rate loops
//! at PX4's rate; the position loop then runs at the same rate, where PX4 runs it at the
//! estimator's rate, which changes little at these bandwidths).

use nalgebra::{UnitQuaternion, Vector3};
use serde::Deserialize;

use super::allocation::{AllocationOutput, AllocationParams, ControlAllocation};
use super::attitude::{AttitudeControl, AttitudeControlParams};
use super::errors::{check_finite3, check_finite_quat, ParamsError, StepError};
use super::motor_map::{MotorMap, MotorMapParams};
use super::position::{PositionControl, PositionControlParams, TrajectorySetpoint};
use super::rate::{RateControl, RateControlParams};

/// The estimate the emulated PX4 controls with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleState {
    /// Attitude, body FRD -> NED.
    pub attitude: UnitQuaternion<f64>,
    /// Body rates, body FRD, rad/s (unfiltered: the rate loop filters them).
    pub rates_frd_rad_s: Vector3<f64>,
    /// Position, NED, m (NaN where invalid; only the position loop reads it).
    pub position_ned_m: Vector3<f64>,
    /// Velocity, NED, m/s (NaN where invalid; only the position loop reads it).
    pub velocity_ned_m_s: Vector3<f64>,
}

/// All inner-loop parameters; each section defaults to PX4 v1.16 / the plant's X500.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InnerLoopParams {
    pub attitude: AttitudeControlParams,
    pub rate: RateControlParams,
    pub allocation: AllocationParams,
    pub motor_map: MotorMapParams,
    pub position: PositionControlParams,
}

/// What the chain computed in its last accepted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InnerLoopStatus {
    /// Attitude setpoint, body FRD -> NED (the current attitude in rate-only steps).
    pub attitude_sp: UnitQuaternion<f64>,
    /// Body-rate setpoint, body FRD, rad/s.
    pub rate_sp_frd_rad_s: Vector3<f64>,
    /// Normalized torque setpoint, body FRD.
    pub torque_sp_frd: Vector3<f64>,
    /// Collective thrust setpoint, normalized.
    pub thrust: f64,
    /// Allocation result (motor u and saturation).
    pub allocation: AllocationOutput,
    /// Commanded rotor speeds, rad/s, PX4 motor order.
    pub rotor_speed_cmd_rad_s: [f64; 4],
}

/// Position, attitude and rate controllers, allocation and motor map of one drone.
#[derive(Debug, Clone, PartialEq)]
pub struct MultirotorInnerLoops {
    attitude: AttitudeControl,
    rate: RateControl,
    allocation: ControlAllocation,
    motor_map: MotorMap,
    position: PositionControl,
    landed: bool,
    status: InnerLoopStatus,
    rejected_steps: u64,
    last_error: Option<StepError>,
}

impl MultirotorInnerLoops {
    pub fn new(params: &InnerLoopParams) -> Result<Self, ParamsError> {
        Ok(MultirotorInnerLoops {
            attitude: AttitudeControl::new(&params.attitude)?,
            rate: RateControl::new(&params.rate)?,
            allocation: ControlAllocation::new(&params.allocation)?,
            motor_map: MotorMap::new(&params.motor_map)?,
            position: PositionControl::new(&params.position)?,
            landed: false,
            status: InnerLoopStatus {
                attitude_sp: UnitQuaternion::identity(),
                rate_sp_frd_rad_s: Vector3::zeros(),
                torque_sp_frd: Vector3::zeros(),
                thrust: 0.0,
                allocation: AllocationOutput::default(),
                rotor_speed_cmd_rad_s: [0.0; 4],
            },
            rejected_steps: 0,
            last_error: None,
        })
    }

    /// Landed (PX4's land detector): rate integrators frozen, position loop at zero thrust
    /// with its integrators cleared. The commander clears it for takeoff.
    pub fn set_landed(&mut self, landed: bool) {
        self.landed = landed;
        self.position.set_landed(landed);
    }

    /// Clears the rate and velocity integrators (PX4 does on arming / while disarmed).
    pub fn reset_integrals(&mut self) {
        self.rate.reset_integral();
        self.position.reset_integral();
    }

    /// Rate mode: body-rate setpoint (FRD, rad/s) and collective thrust (0..1) to rotor speeds.
    pub fn update_rates(
        &mut self,
        dt: f64,
        state: &VehicleState,
        rate_sp_frd_rad_s: &Vector3<f64>,
        thrust: f64,
    ) -> [f64; 4] {
        let r = self.step_rates(dt, state, rate_sp_frd_rad_s, thrust);
        if r.is_ok() {
            self.status.attitude_sp = state.attitude;
        }
        self.hold_on_error(r)
    }

    /// Attitude mode (offboard SET_ATTITUDE_TARGET): attitude setpoint (body FRD -> NED) and
    /// collective thrust (0..1) to rotor speeds.
    pub fn update_attitude(
        &mut self,
        dt: f64,
        state: &VehicleState,
        attitude_sp: &UnitQuaternion<f64>,
        thrust: f64,
    ) -> [f64; 4] {
        self.update_attitude_with_yaw_rate(dt, state, attitude_sp, f64::NAN, thrust)
    }

    /// As [`Self::update_attitude`] with a yaw-rate feed-forward about NED z, rad/s (NaN: none).
    pub fn update_attitude_with_yaw_rate(
        &mut self,
        dt: f64,
        state: &VehicleState,
        attitude_sp: &UnitQuaternion<f64>,
        yaw_rate_ff_rad_s: f64,
        thrust: f64,
    ) -> [f64; 4] {
        let r = self.step_attitude(dt, state, attitude_sp, yaw_rate_ff_rad_s, thrust);
        self.hold_on_error(r)
    }

    /// Position mode (PX4's own hold / Land, or scenario setpoints without a companion).
    pub fn update_position(
        &mut self,
        dt: f64,
        state: &VehicleState,
        setpoint: &TrajectorySetpoint,
    ) -> [f64; 4] {
        let r = self.step_position(dt, state, setpoint);
        self.hold_on_error(r)
    }

    /// Last accepted step.
    pub fn status(&self) -> &InnerLoopStatus {
        &self.status
    }

    /// Steps rejected (bad dt, non-finite input, invalid setpoint); each held the previous
    /// rotor speeds.
    pub fn rejected_steps(&self) -> u64 {
        self.rejected_steps
    }

    /// Why the last rejected step was rejected.
    pub fn last_error(&self) -> Option<&StepError> {
        self.last_error.as_ref()
    }

    /// Rate-loop integrator, normalized torque, body FRD.
    pub fn rate_integral(&self) -> Vector3<f64> {
        self.rate.integral()
    }

    /// Velocity-loop integrator, NED, m/s^2.
    pub fn velocity_integral(&self) -> Vector3<f64> {
        self.position.integral()
    }

    fn hold_on_error(&mut self, r: Result<[f64; 4], StepError>) -> [f64; 4] {
        match r {
            Ok(w) => w,
            Err(e) => {
                self.rejected_steps += 1;
                self.last_error = Some(e);
                self.status.rotor_speed_cmd_rad_s
            }
        }
    }

    fn check_attitude_state(state: &VehicleState) -> Result<(), StepError> {
        check_finite_quat("state.attitude", &state.attitude)?;
        check_finite3("state.rates_frd_rad_s", &state.rates_frd_rad_s)
    }

    fn step_position(
        &mut self,
        dt: f64,
        state: &VehicleState,
        setpoint: &TrajectorySetpoint,
    ) -> Result<[f64; 4], StepError> {
        Self::check_attitude_state(state)?;
        super::errors::check_dt(dt)?;
        let (_, _, yaw) = state.attitude.euler_angles();
        let out = self.position.update(
            dt,
            &state.position_ned_m,
            &state.velocity_ned_m_s,
            yaw,
            setpoint,
        )?;
        self.step_attitude(
            dt,
            state,
            &out.attitude_sp,
            out.yaw_rate_ff_rad_s,
            out.thrust,
        )
    }

    fn step_attitude(
        &mut self,
        dt: f64,
        state: &VehicleState,
        attitude_sp: &UnitQuaternion<f64>,
        yaw_rate_ff_rad_s: f64,
        thrust: f64,
    ) -> Result<[f64; 4], StepError> {
        Self::check_attitude_state(state)?;
        let rate_sp = self
            .attitude
            .update(&state.attitude, attitude_sp, yaw_rate_ff_rad_s)?;
        let w = self.step_rates(dt, state, &rate_sp, thrust)?;
        self.status.attitude_sp = *attitude_sp;
        Ok(w)
    }

    fn step_rates(
        &mut self,
        dt: f64,
        state: &VehicleState,
        rate_sp: &Vector3<f64>,
        thrust: f64,
    ) -> Result<[f64; 4], StepError> {
        Self::check_attitude_state(state)?;
        if !thrust.is_finite() {
            return Err(StepError::NonFinite { name: "thrust" });
        }
        let thrust = thrust.clamp(0.0, 1.0);
        let torque = self
            .rate
            .update(dt, &state.rates_frd_rad_s, rate_sp, self.landed)?;
        let alloc = self.allocation.update(&torque, thrust)?;
        self.rate
            .set_saturation(alloc.saturation_positive, alloc.saturation_negative);
        let w = self.motor_map.rotor_speeds(&alloc.motor_thrust);
        self.status.rate_sp_frd_rad_s = *rate_sp;
        self.status.torque_sp_frd = torque;
        self.status.thrust = thrust;
        self.status.allocation = alloc;
        self.status.rotor_speed_cmd_rad_s = w;
        Ok(w)
    }
}
