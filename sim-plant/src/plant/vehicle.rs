//! One emulated PX4: IMU, motion-capture perturbation, the EKF-like estimator, the commander
//! and the inner loops, run at the rate loop's rate from the physics' truth. Pure: time comes in.

use nalgebra::{UnitQuaternion, Vector3};

use crate::commander::{AttitudeTarget, CommandLong, Commander, ControlDemand, MavResult};
use crate::estimator::{
    ImuModel, ImuSample, MocapPerturbation, PositionEstimator, VehicleEstimate,
};
use crate::inner_loops::{MultirotorInnerLoops, TrajectorySetpoint, VehicleState};
use crate::mavlink_link::{Inbound, Telemetry};
use crate::physics::BodyState;

use super::{PlantConfig, PlantError};

/// What the physics tells the autopilot's sensors at one instant.
#[derive(Debug, Clone, Copy)]
pub struct SensedTruth<'a> {
    pub body: &'a BodyState,
    /// Accelerometer truth, body FRD, m/s².
    pub specific_force_frd: Vector3<f64>,
    pub ground_contact: bool,
    pub rotor_speed: [f64; 4],
}

/// One drone's autopilot.
#[derive(Debug)]
pub struct EmulatedPx4 {
    imu: ImuModel,
    mocap: MocapPerturbation,
    estimator: PositionEstimator,
    commander: Commander,
    inner: MultirotorInnerLoops,
    rotor_cmd: [f64; 4],
    last_imu: ImuSample,
    last_mocap: Vector3<f64>,
    estimate: VehicleEstimate,
    rotor_speed: [f64; 4],
    last_rate_injection_ns: u64,
}

impl EmulatedPx4 {
    /// Drone `k`'s autopilot; its random streams are seeded from `cfg.seed` and `k`.
    pub fn new(cfg: &PlantConfig, k: usize, start: &BodyState) -> Result<Self, PlantError> {
        let seed = |stream: u64| {
            cfg.seed
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(stream * 16 + k as u64)
        };
        let mut pert = cfg.perturbation.clone();
        pert.enabled = cfg.perturbation_enabled;
        let param = |e: String| PlantError::Params(e);
        let mut estimator = PositionEstimator::new(cfg.estimator.clone(), seed(3))
            .map_err(|e| param(e.to_string()))?;
        estimator.correct(0, &start.position_ned);
        let estimate = estimator.estimate();
        Ok(EmulatedPx4 {
            imu: ImuModel::new(cfg.imu.clone(), seed(1)).map_err(|e| param(e.to_string()))?,
            mocap: MocapPerturbation::new(pert, seed(2)).map_err(|e| param(e.to_string()))?,
            estimator,
            commander: Commander::new(cfg.commander.clone()).map_err(|e| param(e.to_string()))?,
            inner: MultirotorInnerLoops::new(&cfg.inner_loops).map_err(|e| param(e.to_string()))?,
            rotor_cmd: [0.0; 4],
            last_imu: ImuSample {
                specific_force_frd: Vector3::new(0.0, 0.0, -9.81),
                angular_rate_frd: Vector3::zeros(),
            },
            last_mocap: start.position_ned,
            estimate,
            rotor_speed: [0.0; 4],
            last_rate_injection_ns: 0,
        })
    }

    pub fn commander(&self) -> &Commander {
        &self.commander
    }

    pub fn commander_mut(&mut self) -> &mut Commander {
        &mut self.commander
    }

    pub fn estimate(&self) -> &VehicleEstimate {
        &self.estimate
    }

    /// The motion-capture position last fed to the estimator (truth + perturbation), NED.
    pub fn mocap_position(&self) -> Vector3<f64> {
        self.last_mocap
    }

    /// Rotor speed commands of the last tick, rad/s.
    pub fn rotor_cmd(&self) -> &[f64; 4] {
        &self.rotor_cmd
    }

    /// A message from the MAVLink link (or an in-process companion).
    pub fn handle(&mut self, t_ns: u64, msg: Inbound) -> Option<MavResult> {
        match msg {
            Inbound::AttitudeTarget {
                q,
                body_rates,
                thrust,
                type_mask,
                thrust_body,
                ..
            } => {
                self.commander.on_attitude_target(
                    t_ns,
                    &AttitudeTarget {
                        q,
                        body_rates,
                        thrust,
                        type_mask,
                        thrust_body,
                    },
                );
                None
            }
            Inbound::Command {
                command, params, ..
            } => Some(
                self.commander
                    .on_command(t_ns, &CommandLong { command, params }),
            ),
            Inbound::Heartbeat { .. } => None,
        }
    }

    /// One rate-loop tick at `t_ns`, `dt_s` after the previous one.
    pub fn tick(&mut self, t_ns: u64, dt_s: f64, truth: &SensedTruth) {
        self.rotor_speed = truth.rotor_speed;
        if let Some(imu) = self
            .imu
            .measure(&truth.specific_force_frd, &truth.body.rate_frd)
        {
            self.last_imu = imu;
            self.estimator
                .predict(t_ns, dt_s, &imu, &truth.body.attitude);
        }
        if let Some(m) = self.mocap.poll(t_ns, &truth.body.position_ned) {
            self.last_mocap = m.position_ned;
            self.estimator.correct(t_ns, &m.position_ned);
        }
        self.estimate = self.estimator.estimate();
        let demand = self
            .commander
            .update(t_ns, &self.estimate, truth.ground_contact);
        self.inner
            .set_landed(self.commander.land_detector().landed());
        let state = VehicleState {
            attitude: self.estimate.attitude,
            rates_frd_rad_s: self.last_imu.angular_rate_frd,
            position_ned_m: self.estimate.position_ned,
            velocity_ned_m_s: self.estimate.velocity_ned,
        };
        self.rotor_cmd = match demand {
            ControlDemand::MotorsOff => {
                self.inner.reset_integrals();
                [0.0; 4]
            }
            ControlDemand::Attitude {
                q_sp,
                thrust,
                yaw_rate_ff,
                rate_injection,
            } => match rate_injection {
                // PX4 also publishes such a message's rates to the rate controller, which flies
                // them until the attitude loop's next output: one tick here.
                Some(r) if r.t_ns > self.last_rate_injection_ns => {
                    self.last_rate_injection_ns = r.t_ns;
                    let mut rates = r.rates_frd;
                    for i in 0..3 {
                        if !rates[i].is_finite() {
                            rates[i] = state.rates_frd_rad_s[i];
                        }
                    }
                    self.inner.update_rates(dt_s, &state, &rates, r.thrust)
                }
                _ => self.inner.update_attitude_with_yaw_rate(
                    dt_s,
                    &state,
                    &q_sp,
                    yaw_rate_ff,
                    thrust,
                ),
            },
            ControlDemand::Rates { rates_frd, thrust } => {
                let mut rates = rates_frd;
                if !rates.z.is_finite() {
                    rates.z = state.rates_frd_rad_s.z;
                }
                self.inner.update_rates(dt_s, &state, &rates, thrust)
            }
            ControlDemand::Position {
                position_ned,
                velocity_ned,
                yaw,
            } => {
                let sp = TrajectorySetpoint {
                    position_ned_m: position_ned,
                    velocity_ned_m_s: velocity_ned,
                    yaw_rad: yaw,
                    ..TrajectorySetpoint::empty()
                };
                self.inner.update_position(dt_s, &state, &sp)
            }
        };
    }

    /// The snapshot the MAVLink link streams.
    pub fn telemetry(&self, t_ns: u64) -> Telemetry {
        let e = &self.estimate;
        let var = |s: f64| [s * s; 3];
        let pos_std = self.estimator.position_std_m();
        Telemetry {
            time_boot_ns: t_ns,
            base_mode: self.commander.base_mode(),
            custom_mode: self.commander.custom_mode(),
            system_status: self.commander.system_status(),
            position_ned_m: e.position_ned,
            velocity_ned_m_s: e.velocity_ned,
            attitude_body_to_ned: e.attitude,
            body_rates_frd_rad_s: self.last_imu.angular_rate_frd,
            specific_force_frd_m_s2: self.last_imu.specific_force_frd,
            gyro_frd_rad_s: self.last_imu.angular_rate_frd,
            rotor_speeds_rad_s: self.rotor_speed,
            position_variance_ned_m2: [pos_std.x.powi(2), pos_std.y.powi(2), pos_std.z.powi(2)],
            velocity_variance_ned_m2_s2: var(f64::NAN),
            attitude_variance_rad2: var(f64::NAN),
            ..Telemetry::default()
        }
    }
}

/// Level attitude with heading `yaw_rad`.
pub fn level(yaw_rad: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(0.0, 0.0, yaw_rad)
}
