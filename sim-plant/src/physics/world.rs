//! [`World`]: construction, stepping, pinning and external forces. Readings are in
//! `readings.rs`.

use nalgebra::{UnitQuaternion, Vector2, Vector3};

use super::dynamics::{
    point_kinematics, rk4_step, rotation, semi_implicit_euler_step, Drive, Phase,
};
use super::model::{find_surface, Model, PAYLOAD};
use super::params::ParamsError;
use super::state::{BodyId, BodyState, WorldState};
use super::world_params::{Integrator, WorldParams};

/// Most internal sub-steps one `step` call may take (bounds the work of a huge `dt_s`).
pub const MAX_SUBSTEPS_PER_STEP: usize = 10_000;

/// Why a [`World`] could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WorldError {
    #[error(transparent)]
    Params(#[from] ParamsError),
    #[error("initial state `{field}` is not finite")]
    NonFiniteState { field: &'static str },
    #[error("initial quads[{quad}].rotor_speed[{rotor}] = {value} rad/s is outside [0, {max}]")]
    RotorSpeed {
        quad: usize,
        rotor: usize,
        value: f64,
        max: f64,
    },
}

/// Friction anchor of one contact point (see the module doc on stick-slip).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FrictionAnchor {
    /// NED x, y of the anchor, m.
    pub xy: Vector2<f64>,
    /// The point touched a surface at the end of the last step.
    pub active: bool,
}

/// `exp(-h / (2 tau))` for each quad's up and down motor constants, for sub-step length `h`.
#[derive(Debug, Clone, Copy, Default)]
struct MotorDecay {
    h: f64,
    half: [[f64; 2]; 2],
}

/// The plant's rigid-body physics: two quads, the payload, two cables, ground and box contacts.
#[derive(Debug, Clone)]
pub struct World {
    pub(crate) params: WorldParams,
    pub(crate) model: Model,
    pub(crate) state: WorldState,
    pub(crate) pinned: [bool; 2],
    pub(crate) external_force_ned: [Vector3<f64>; 3],
    pub(crate) anchors: [[FrictionAnchor; 4]; 3],
    /// Mean acceleration of each body over the last step, NED, m/s^2.
    pub(crate) last_accel_ned: [Vector3<f64>; 3],
    motor_decay: MotorDecay,
    nan_commands: u64,
    rejected_inputs: u64,
    non_finite_steps: u64,
}

impl World {
    /// Validates `params` and `initial` and builds the world. Contact points that start inside
    /// a surface start sticking where they are.
    pub fn new(params: WorldParams, initial: WorldState) -> Result<World, WorldError> {
        params.validate()?;
        if !initial.time_s.is_finite() {
            return Err(WorldError::NonFiniteState { field: "time_s" });
        }
        let fields = ["quads[0].body", "quads[1].body", "payload"];
        let bodies = [
            &initial.quads[0].body,
            &initial.quads[1].body,
            &initial.payload,
        ];
        for (field, body) in fields.into_iter().zip(bodies) {
            if !body.is_finite() {
                return Err(WorldError::NonFiniteState { field });
            }
        }
        for (i, q) in initial.quads.iter().enumerate() {
            let max = params.quads[i].max_rotor_speed_rad_s;
            for (j, &w) in q.rotor_speed.iter().enumerate() {
                if !(0.0..=max).contains(&w) {
                    return Err(WorldError::RotorSpeed {
                        quad: i,
                        rotor: j,
                        value: w,
                        max,
                    });
                }
            }
        }
        let mut state = initial;
        for q in &mut state.quads {
            q.body.attitude = UnitQuaternion::new_normalize(q.body.attitude.into_inner());
        }
        state.payload.attitude = UnitQuaternion::new_normalize(state.payload.attitude.into_inner());
        let model = Model::new(&params);
        let mut world = World {
            params,
            model,
            state,
            pinned: [false; 2],
            external_force_ned: [Vector3::zeros(); 3],
            anchors: [[FrictionAnchor::default(); 4]; 3],
            last_accel_ned: [Vector3::zeros(); 3],
            motor_decay: MotorDecay::default(),
            nan_commands: 0,
            rejected_inputs: 0,
            non_finite_steps: 0,
        };
        world.update_anchors();
        Ok(world)
    }

    /// Advances by `dt_s` with commanded rotor speeds (rad/s, per quad, PX4 motor order).
    ///
    /// Commands are clamped to [0, max]; NaN counts as 0 and is counted
    /// ([`World::nan_command_count`]). A `dt_s` that is not finite and positive, or that would
    /// need more than [`MAX_SUBSTEPS_PER_STEP`] sub-steps, is ignored and counted
    /// ([`World::rejected_input_count`]). If the state came out non-finite the step is undone
    /// and counted ([`World::non_finite_step_count`]).
    pub fn step(&mut self, dt_s: f64, rotor_cmd: &[[f64; 4]; 2]) {
        let substeps = (dt_s / self.params.max_substep_s).ceil();
        if !(dt_s.is_finite() && dt_s > 0.0) || substeps > MAX_SUBSTEPS_PER_STEP as f64 {
            self.rejected_inputs += 1;
            return;
        }
        let substeps = (substeps as usize).max(1);
        let mut cmd = [[0.0; 4]; 2];
        for i in 0..2 {
            for j in 0..4 {
                let c = rotor_cmd[i][j];
                cmd[i][j] = if c.is_nan() {
                    self.nan_commands += 1;
                    0.0
                } else {
                    c.clamp(0.0, self.model.rotors[i].max_speed)
                };
            }
        }
        let before = self.state;
        let before_anchors = self.anchors;
        let h = dt_s / substeps as f64;
        for _ in 0..substeps {
            self.substep(h, &cmd);
        }
        self.state.time_s = before.time_s + dt_s;
        let bodies = [
            &self.state.quads[0].body,
            &self.state.quads[1].body,
            &self.state.payload,
        ];
        if !bodies.iter().all(|b| b.is_finite()) {
            self.state = before;
            self.anchors = before_anchors;
            self.non_finite_steps += 1;
            return;
        }
        let v0 = [
            before.quads[0].body.velocity_ned,
            before.quads[1].body.velocity_ned,
            before.payload.velocity_ned,
        ];
        let v1 = [
            bodies[0].velocity_ned,
            bodies[1].velocity_ned,
            bodies[2].velocity_ned,
        ];
        for b in 0..3 {
            self.last_accel_ned[b] = (v1[b] - v0[b]) / dt_s;
        }
    }

    fn motor_decay_half(&mut self, h: f64) -> [[f64; 2]; 2] {
        if self.motor_decay.h != h {
            let r = &self.model.rotors;
            self.motor_decay = MotorDecay {
                h,
                half: [0, 1].map(|i| {
                    [
                        (-0.5 * h / r[i].tau_up).exp(),
                        (-0.5 * h / r[i].tau_down).exp(),
                    ]
                }),
            };
        }
        self.motor_decay.half
    }

    fn substep(&mut self, h: f64, cmd: &[[f64; 4]; 2]) {
        // Rotor speeds in closed form: w(t) = c + (w0 - c) exp(-t / tau), tau by direction.
        let decay = self.motor_decay_half(h);
        let mut rotor = [[[0.0; 4]; 2]; 3];
        for i in 0..2 {
            for j in 0..4 {
                let w0 = self.state.quads[i].rotor_speed[j];
                let c = cmd[i][j];
                let e = decay[i][if c >= w0 { 0 } else { 1 }];
                rotor[0][i][j] = w0;
                rotor[1][i][j] = c + (w0 - c) * e;
                rotor[2][i][j] = c + (w0 - c) * e * e;
            }
        }
        let anchors_xy = self.anchors.map(|a| a.map(|p| p.xy));
        let drive = Drive {
            external_force_ned: &self.external_force_ned,
            pinned: self.pinned,
            anchors_xy: &anchors_xy,
        };
        let y = self.phase();
        let y = match self.params.integrator {
            Integrator::Rk4 => rk4_step(&self.model, &y, h, &rotor, &drive),
            Integrator::SemiImplicitEuler => {
                semi_implicit_euler_step(&self.model, &y, h, &rotor[0], &drive)
            }
        };
        for (i, quad) in self.state.quads.iter_mut().enumerate() {
            if !self.pinned[i] {
                write_body(&mut quad.body, &y, i);
                quad.rotor_speed = rotor[2][i];
            }
        }
        write_body(&mut self.state.payload, &y, PAYLOAD);
        self.update_anchors();
    }

    fn phase(&self) -> Phase {
        let b = [
            &self.state.quads[0].body,
            &self.state.quads[1].body,
            &self.state.payload,
        ];
        Phase {
            pos: b.map(|b| b.position_ned),
            vel: b.map(|b| b.velocity_ned),
            quat: b.map(|b| b.attitude.into_inner()),
            rate: b.map(|b| b.rate_frd),
        }
    }

    /// Stick-slip bookkeeping after a (sub-)step: a point in contact keeps its anchor unless
    /// the anchor spring alone exceeds mu N, in which case the anchor is dragged to where the
    /// spring gives exactly mu N; a point out of contact has its anchor where it is.
    fn update_anchors(&mut self) {
        let c = self.model.contact;
        let b = [
            &self.state.quads[0].body,
            &self.state.quads[1].body,
            &self.state.payload,
        ];
        for (k, body) in b.into_iter().enumerate() {
            if k < 2 && self.pinned[k] {
                continue;
            }
            let rot = rotation(&body.attitude.into_inner());
            for j in 0..4 {
                let r = &self.model.points_frd[k][j];
                let (p, v) = point_kinematics(
                    &body.position_ned,
                    &body.velocity_ned,
                    &rot,
                    &body.rate_frd,
                    r,
                );
                let anchor = &mut self.anchors[k][j];
                match find_surface(&p, &self.model.boxes, c.depth) {
                    Some((_, pen)) => {
                        let normal = (c.k_n * pen + c.c_n * v.z).max(0.0);
                        let d = p.xy() - anchor.xy;
                        let spring = c.k_t * d.norm();
                        let limit = c.mu * normal;
                        if !anchor.active {
                            anchor.xy = p.xy();
                        } else if spring > limit {
                            anchor.xy = p.xy() - d * (limit / spring);
                        }
                        anchor.active = true;
                    }
                    None => {
                        *anchor = FrictionAnchor {
                            xy: p.xy(),
                            active: false,
                        }
                    }
                }
            }
        }
    }

    /// Makes quad `i` kinematic (or dynamic again). Pinning zeroes its velocity and body
    /// rate; while pinned its state (pose, rotor speeds) does not change, it feels no forces,
    /// and its cable still pulls on the payload from its fixed anchor. Panics if `i > 1`.
    pub fn pin_quad(&mut self, i: usize, pinned: bool) {
        if pinned && !self.pinned[i] {
            self.state.quads[i].body.velocity_ned = Vector3::zeros();
            self.state.quads[i].body.rate_frd = Vector3::zeros();
            self.last_accel_ned[i] = Vector3::zeros();
        }
        self.pinned[i] = pinned;
    }

    /// True if quad `i` is pinned. Panics if `i > 1`.
    pub fn is_quad_pinned(&self, i: usize) -> bool {
        self.pinned[i]
    }

    /// Applies a constant force (NED, N) at `body`'s centre of mass until changed (for tests).
    /// A non-finite force is ignored and counted as a rejected input.
    pub fn set_external_force(&mut self, body: BodyId, force_ned: Vector3<f64>) {
        if force_ned.iter().all(|v| v.is_finite()) {
            self.external_force_ned[body.index()] = force_ned;
        } else {
            self.rejected_inputs += 1;
        }
    }

    /// The external force on `body`, NED, N.
    pub fn external_force(&self, body: BodyId) -> Vector3<f64> {
        self.external_force_ned[body.index()]
    }

    /// Current state.
    pub fn state(&self) -> &WorldState {
        &self.state
    }

    /// Parameters the world was built with.
    pub fn params(&self) -> &WorldParams {
        &self.params
    }

    /// Rotor commands that were NaN (each counted once per rotor per step).
    pub fn nan_command_count(&self) -> u64 {
        self.nan_commands
    }

    /// Ignored calls: bad `dt_s` in `step`, non-finite force in `set_external_force`.
    pub fn rejected_input_count(&self) -> u64 {
        self.rejected_inputs
    }

    /// Steps undone because the state came out non-finite.
    pub fn non_finite_step_count(&self) -> u64 {
        self.non_finite_steps
    }
}

fn write_body(body: &mut BodyState, y: &Phase, b: usize) {
    body.position_ned = y.pos[b];
    body.velocity_ned = y.vel[b];
    body.attitude = UnitQuaternion::new_normalize(y.quat[b]);
    body.rate_frd = y.rate[b];
}
