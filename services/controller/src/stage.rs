//! [`ControllerStage`]: one step of the whole cascade from the newest inputs, with the input
//! checks (age, finiteness, armed) around it. See the crate doc for the conventions.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use rt_config::{ControllerConfig, ControllerLaw, VehicleConfig};
use shared_types::{
    given_inputs, mission_flags, setpoint_flags, AttitudeSetpoint, MissionSetpoint, TensionSample,
    VehicleState,
};

use crate::formation::{static_tension, FormationRegime};
use crate::geometric::GeometricGains;
use crate::loops::{ShiftGains, TensionShift, VelocityGains, VelocityPid};
use crate::mapping::{level, yaw_of, MappingParams, ThrustLimit};

/// The step's dt (from consecutive `now_ns`) is clamped to this range, s.
pub const MIN_DT_S: f64 = 1e-4;
pub const MAX_DT_S: f64 = 0.05;

/// Why a [`ControllerStage`] could not be built; messages name the key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControllerParamsError {
    #[error("{0}")]
    Vehicle(String),
    #[error("{0}")]
    Controller(String),
    #[error(
        "key `controller.max_thrust_n` = {max_thrust_n}: below the vehicle's weight \
         vehicle.mass_kg * vehicle.gravity_m_s2 = {weight_n} N"
    )]
    CannotHover { max_thrust_n: f64, weight_n: f64 },
}

/// What the stage has seen, since `new`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ControllerCounters {
    pub steps: u64,
    /// Steps with a non-finite (or zero-norm quaternion) input or result: safe output.
    pub non_finite_inputs: u64,
    /// Steps not armed (IDLE).
    pub idle_steps: u64,
    /// Steps without a tension sample younger than `tension_max_age_s` (POSITION_ONLY).
    pub stale_tension_steps: u64,
    pub stale_mission_steps: u64,
    pub stale_odometry_steps: u64,
    pub tilt_limited_steps: u64,
    pub thrust_limited_steps: u64,
    /// Steps whose formation setpoints were farther apart than the cables reach.
    pub formation_limit_steps: u64,
    /// Steps that used a tension sample carrying flags.
    pub tension_flagged_steps: u64,
}

/// Everything a step changes (`Copy`: a step works on a copy and commits it when finite).
#[derive(Debug, Clone, Copy, PartialEq)]
struct LoopState {
    last_now_ns: Option<u64>,
    shift: TensionShift,
    velocity: VelocityPid,
    /// Position and yaw held while the mission is stale.
    hold: Option<(Vector3<f64>, f64)>,
    tension_desired_ned_n: Vector3<f64>,
    last_yaw_rad: f64,
}

/// The tension-aware cascade (paper IV) for one drone.
#[derive(Debug, Clone)]
pub struct ControllerStage {
    vehicle: VehicleConfig,
    cfg: ControllerConfig,
    k_p: Vector3<f64>,
    shift_gains: ShiftGains,
    velocity_gains: VelocityGains,
    mapping: MappingParams,
    geometric: GeometricGains,
    state: LoopState,
    counters: ControllerCounters,
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The attitude of `s`, if finite and of sane norm (the bridge sends unit quaternions).
fn attitude_of(s: &VehicleState) -> Option<UnitQuaternion<f64>> {
    let [w, x, y, z] = s.attitude_wxyz;
    let q = Quaternion::new(w, x, y, z);
    let n = q.norm();
    (n.is_finite() && (0.5..2.0).contains(&n)).then(|| UnitQuaternion::from_quaternion(q))
}

impl ControllerStage {
    pub fn new(
        vehicle: &VehicleConfig,
        cfg: &ControllerConfig,
    ) -> Result<Self, ControllerParamsError> {
        vehicle.validate().map_err(ControllerParamsError::Vehicle)?;
        cfg.validate().map_err(ControllerParamsError::Controller)?;
        let weight_n = vehicle.mass_kg * vehicle.gravity_m_s2;
        if cfg.max_thrust_n <= weight_n {
            return Err(ControllerParamsError::CannotHover {
                max_thrust_n: cfg.max_thrust_n,
                weight_n,
            });
        }
        Ok(Self {
            vehicle: *vehicle,
            cfg: *cfg,
            k_p: cfg.k_p.into(),
            shift_gains: ShiftGains {
                k_tp: cfg.k_tp.into(),
                k_ti: cfg.k_ti.into(),
                k_td: cfg.k_td.into(),
                max_shift_m: cfg.max_tension_shift_m.into(),
                decay_tau_s: cfg.tension_shift_decay_s,
                slack_ratio: cfg.slack_tension_ratio,
            },
            velocity_gains: VelocityGains {
                k_vp: cfg.k_vp.into(),
                k_vi: cfg.k_vi.into(),
                k_vd: cfg.k_vd.into(),
                max_integral_m_s2: cfg.max_velocity_integral_m_s2.into(),
            },
            mapping: MappingParams {
                mass_kg: vehicle.mass_kg,
                gravity_m_s2: vehicle.gravity_m_s2,
                max_tilt_rad: cfg.max_tilt_deg.to_radians(),
                min_thrust_n: cfg.min_thrust_n,
                max_thrust_n: cfg.max_thrust_n,
            },
            geometric: GeometricGains {
                kp: cfg.geometric.kp.into(),
                kv: cfg.geometric.kv.into(),
            },
            state: Self::fresh_state(cfg, 0.0),
            counters: ControllerCounters::default(),
        })
    }

    fn fresh_state(cfg: &ControllerConfig, yaw_rad: f64) -> LoopState {
        LoopState {
            last_now_ns: None,
            shift: TensionShift::new(cfg.tension_cutoff_hz),
            velocity: VelocityPid::new(cfg.velocity_cutoff_hz),
            hold: None,
            tension_desired_ned_n: Vector3::zeros(),
            last_yaw_rad: yaw_rad,
        }
    }

    pub fn counters(&self) -> ControllerCounters {
        self.counters
    }

    fn dt_s(&self, now_ns: u64) -> f64 {
        let dt = match self.state.last_now_ns {
            Some(last) => now_ns.saturating_sub(last) as f64 * 1e-9,
            None => 1.0 / self.cfg.rate_hz,
        };
        dt.clamp(MIN_DT_S, MAX_DT_S)
    }

    /// One control step at `now_ns` (CLOCK_MONOTONIC or simulated) with the newest of each
    /// input. Never panics, never allocates.
    pub fn step(
        &mut self,
        now_ns: u64,
        state: &VehicleState,
        tension: Option<&TensionSample>,
        mission: Option<&MissionSetpoint>,
    ) -> AttitudeSetpoint {
        let c = &self.cfg;
        let age_s = |t_origin_ns: u64| now_ns.saturating_sub(t_origin_ns) as f64 * 1e-9;
        // What a replay needs to hand the same inputs to the step again.
        let mut given = given_inputs::ODOMETRY;
        let given_tension_sequence = tension.map_or(0, |t| {
            given |= given_inputs::TENSION;
            t.header.sequence
        });
        let given_mission_sequence = mission.map_or(0, |m| {
            given |= given_inputs::MISSION;
            m.header.sequence
        });
        if *state == VehicleState::before_first_odometry() {
            given &= !given_inputs::ODOMETRY;
        }
        let mission = mission.filter(|m| age_s(m.header.t_origin_ns) <= c.mission_max_age_s);
        let tension = tension.filter(|t| age_s(t.header.t_origin_ns) <= c.tension_max_age_s);
        let odometry_stale = age_s(state.header.t_origin_ns) > c.odometry_max_age_s;
        self.counters.steps += 1;
        let mut out = AttitudeSetpoint {
            odometry_origin_ns: state.header.t_origin_ns,
            odometry_sequence: state.header.sequence,
            step_ns: now_ns,
            given_inputs: given,
            given_tension_sequence,
            given_mission_sequence,
            ..Default::default()
        };
        out.header.t_origin_ns = state.header.t_origin_ns;
        if tension.is_none() {
            out.flags |= setpoint_flags::POSITION_ONLY;
            self.counters.stale_tension_steps += 1;
        }
        if odometry_stale {
            out.flags |= setpoint_flags::STALE_ODOMETRY;
            self.counters.stale_odometry_steps += 1;
        }
        match mission {
            Some(m) => {
                out.phase = m.phase;
                out.mission_sequence = m.header.sequence;
                out.nominal_position_ned_m = m.position_ned_m;
                if m.flags & mission_flags::ARM_REQUEST != 0 {
                    out.flags |= setpoint_flags::ARM_REQUEST;
                }
            }
            None => {
                out.flags |= setpoint_flags::STALE_MISSION;
                self.counters.stale_mission_steps += 1;
            }
        }
        let attitude = attitude_of(state);
        let finite = attitude.is_some()
            && finite3(&state.position_ned_m)
            && finite3(&state.velocity_ned_m_s)
            && mission.is_none_or(|m| {
                finite3(&m.position_ned_m)
                    && finite3(&m.peer_position_ned_m)
                    && m.yaw_rad.is_finite()
            })
            && tension.is_none_or(|t| finite3(&t.force_body_n));
        if !finite {
            out.flags |= setpoint_flags::NON_FINITE;
            self.counters.non_finite_inputs += 1;
        }
        if !state.armed() {
            return self.idle(now_ns, attitude.as_ref(), out);
        }
        match (finite, attitude) {
            (true, Some(q)) => self.control(now_ns, state, &q, tension, mission, out),
            _ => self.fallback(out),
        }
    }

    /// Not armed: integrators and filters reset, level at the current yaw, minimum thrust.
    fn idle(
        &mut self,
        now_ns: u64,
        attitude: Option<&UnitQuaternion<f64>>,
        mut out: AttitudeSetpoint,
    ) -> AttitudeSetpoint {
        let yaw = attitude.map_or(self.state.last_yaw_rad, yaw_of);
        self.state = Self::fresh_state(&self.cfg, yaw);
        self.state.last_now_ns = Some(now_ns);
        self.counters.idle_steps += 1;
        out.flags |= setpoint_flags::IDLE;
        out.attitude_wxyz = wxyz(&level(yaw));
        out.thrust_n = self.cfg.min_thrust_n;
        out
    }

    /// Non-finite input or result: level at the last finite yaw, thrust m g; state untouched.
    fn fallback(&mut self, mut out: AttitudeSetpoint) -> AttitudeSetpoint {
        if out.flags & setpoint_flags::NON_FINITE == 0 {
            out.flags |= setpoint_flags::NON_FINITE;
            self.counters.non_finite_inputs += 1;
        }
        out.attitude_wxyz = wxyz(&level(self.state.last_yaw_rad));
        out.thrust_n = self.vehicle.mass_kg * self.vehicle.gravity_m_s2;
        out
    }

    fn control(
        &mut self,
        now_ns: u64,
        state: &VehicleState,
        q: &UnitQuaternion<f64>,
        tension: Option<&TensionSample>,
        mission: Option<&MissionSetpoint>,
        mut out: AttitudeSetpoint,
    ) -> AttitudeSetpoint {
        let dt = self.dt_s(now_ns);
        let mut s = self.state;
        s.last_now_ns = Some(now_ns);
        let position = Vector3::from(state.position_ned_m);
        let mut formation_limited = false;
        let (nominal, yaw_d, enabled) = match mission {
            Some(m) => {
                s.hold = None;
                let f = static_tension(&m.position_ned_m, &m.peer_position_ned_m, &self.vehicle);
                formation_limited = f.regime == FormationRegime::TooFar;
                s.tension_desired_ned_n = f.own_ned_n.into();
                let enabled = m.flags & mission_flags::TENSION_ENABLED != 0;
                (Vector3::from(m.position_ned_m), m.yaw_rad, enabled)
            }
            None => {
                let (p, yaw) = *s.hold.get_or_insert((position, yaw_of(q)));
                (p, yaw, false)
            }
        };
        // T (force the drone exerts on the cable, NED) = −R(q) · (cable's pull, body FRD).
        let measured = tension.map(|t| -(q * Vector3::from(t.force_body_n)));
        s.shift.measure(measured.as_ref(), dt);
        let desired_t = s.tension_desired_ned_n;
        let integrate = out.flags & setpoint_flags::STALE_ODOMETRY == 0;
        let fresh = measured.is_some();
        let law = match self.cfg.law {
            ControllerLaw::Proposed => {
                let inputs = (enabled, fresh, integrate, dt);
                self.proposed(&mut s, inputs, &nominal, state, q, yaw_d)
            }
            ControllerLaw::Geometric => {
                out.flags |= setpoint_flags::GEOMETRIC;
                self.geometric_law(&s, (enabled, fresh), &nominal, mission, state, q, yaw_d)
            }
        };
        let (setpoint, a_d, mapped) = (law.setpoint, law.acceleration, law.mapped);
        let t_f = s.shift.filter.value();
        let results_finite = mapped.thrust_n.is_finite()
            && mapped.attitude.coords.iter().all(|x| x.is_finite())
            && [a_d, setpoint, t_f, desired_t, s.velocity.integral_m_s2]
                .iter()
                .all(|v| v.iter().all(|x| x.is_finite()));
        if !results_finite {
            return self.fallback(out);
        }
        s.last_yaw_rad = yaw_d;
        self.state = s;
        if formation_limited {
            self.counters.formation_limit_steps += 1;
        }
        if mapped.tilt_limited {
            out.flags |= setpoint_flags::TILT_LIMITED;
            self.counters.tilt_limited_steps += 1;
        }
        if mapped.thrust_limit != ThrustLimit::None {
            out.flags |= setpoint_flags::THRUST_LIMITED;
            self.counters.thrust_limited_steps += 1;
        }
        if let (true, Some(t)) = (law.tension_used, tension) {
            out.header.t_origin_ns = t.header.t_origin_ns;
            out.tension_origin_ns = t.header.t_origin_ns;
            out.tension_sequence = t.header.sequence;
            if t.flags != 0 {
                out.flags |= setpoint_flags::TENSION_FLAGGED;
                self.counters.tension_flagged_steps += 1;
            }
        }
        out.attitude_wxyz = wxyz(&mapped.attitude);
        out.thrust_n = mapped.thrust_n;
        out.nominal_position_ned_m = nominal.into();
        out.shifted_position_ned_m = setpoint.into();
        out.tension_desired_ned_n = desired_t.into();
        out.tension_filtered_ned_n = t_f.into();
        out.acceleration_desired_ned_m_s2 = a_d.into();
        out
    }

    /// v_d = K_P (ξ_d − ξ), horizontal norm and vertical magnitude clamped.
    fn velocity_setpoint(&self, error_m: &Vector3<f64>) -> Vector3<f64> {
        let mut v = self.k_p.component_mul(error_m);
        let xy = v.xy().norm();
        if xy > self.cfg.max_velocity_xy_m_s {
            let s = self.cfg.max_velocity_xy_m_s / xy;
            v.x *= s;
            v.y *= s;
        }
        v.z =
            v.z.clamp(-self.cfg.max_velocity_z_m_s, self.cfg.max_velocity_z_m_s);
        v
    }
}

fn wxyz(q: &UnitQuaternion<f64>) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

#[path = "stage_laws.rs"]
mod laws;

#[cfg(test)]
#[path = "stage_tests.rs"]
mod tests;
