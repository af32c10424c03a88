//! The whole plant: the physics of two drones, payload and cables, an emulated PX4 per drone,
//! and the ground truth, stepped in simulated time. Pure (no I/O, no clock): the real-time
//! process (`taut plant`) and the fast mode drive the same `Plant`.
//!
//! Timing: physics every `physics_dt_s` (0.5 ms); each PX4 at `rate_loop_hz` (400 Hz, PX4's
//! rate loop) with its estimator prediction, motion-capture fusion at the perturbation's rate
//! (100 Hz), commander and inner loops. Rotor commands are held between ticks.

mod config;
mod vehicle;

use nalgebra::Vector3;
use shared_types::{crash_flags, BodyTruth, ContactKind, DroneTruth, PlantTruth};

use crate::commander::MavResult as CommanderResult;
use crate::mavlink_link::{Inbound, MavResult, Telemetry};
use crate::physics::{
    hanging_formation, BodyState, BoxObstacle, ContactSurface, QuadState, World, WorldState,
};
use crate::pilot::Vehicles;
use crate::scenario::{BoxSpec, DroneStart, PayloadStart, Scenario};

pub use config::PlantConfig;
pub use vehicle::{level, EmulatedPx4, SensedTruth};

/// Why a plant could not be built.
#[derive(Debug, thiserror::Error)]
pub enum PlantError {
    #[error("plant parameter: {0}")]
    Params(String),
    #[error("scenario {scenario}: {message}")]
    Scenario { scenario: String, message: String },
    #[error("physics: {0}")]
    World(String),
}

/// Two drones, payload, cables, boxes and two emulated PX4s.
#[derive(Debug)]
pub struct Plant {
    world: World,
    px4: [EmulatedPx4; 2],
    t_ns: u64,
    dt_ns: u64,
    dt_s: f64,
    steps_per_tick: u64,
    steps: u64,
    obstacles: Vec<BoxSpec>,
    arena: [[f64; 3]; 2],
    drone_radius_m: f64,
    crash_speed_m_s: f64,
    crash_flags: [u32; 2],
}

impl Plant {
    pub fn new(scenario: &Scenario, cfg: &PlantConfig) -> Result<Self, PlantError> {
        let steps_per_tick = cfg.steps_per_tick().map_err(PlantError::Params)?;
        let mut params = cfg.physics.clone();
        params.boxes = scenario
            .boxes
            .iter()
            .map(|b| BoxObstacle {
                center_ned: b.center_ned_m,
                half_extents: b.half_extents_m,
            })
            .collect();
        let initial = initial_state(scenario, &params)?;
        let world = World::new(params, initial).map_err(|e| PlantError::World(e.to_string()))?;
        let s = *world.state();
        let mut px4 = [
            EmulatedPx4::new(cfg, 0, &s.quads[0].body)?,
            EmulatedPx4::new(cfg, 1, &s.quads[1].body)?,
        ];
        for (k, d) in scenario.drones.iter().enumerate() {
            if d.start == DroneStart::Hover {
                px4[k].commander_mut().start_airborne(0);
            }
        }
        let dt_ns = (cfg.physics_dt_s * 1e9).round() as u64;
        Ok(Plant {
            world,
            px4,
            t_ns: 0,
            dt_ns,
            dt_s: dt_ns as f64 * 1e-9,
            steps_per_tick,
            steps: 0,
            obstacles: scenario.obstacles.clone(),
            arena: [scenario.arena.min_ned_m, scenario.arena.max_ned_m],
            drone_radius_m: cfg.drone_radius_m,
            crash_speed_m_s: cfg.crash_speed_m_s,
            crash_flags: [0; 2],
        })
    }

    /// Simulated time since start, ns.
    pub fn time_ns(&self) -> u64 {
        self.t_ns
    }

    /// Physics step, ns.
    pub fn dt_ns(&self) -> u64 {
        self.dt_ns
    }

    pub fn world(&self) -> &World {
        &self.world
    }

    pub fn px4(&self, k: usize) -> &EmulatedPx4 {
        &self.px4[k]
    }

    /// Advances one physics step; the autopilots tick first when their tick is due.
    pub fn step(&mut self) {
        if self.steps.is_multiple_of(self.steps_per_tick) {
            let tick_dt = self.dt_s * self.steps_per_tick as f64;
            for k in 0..2 {
                let q = &self.world.state().quads[k];
                let truth = SensedTruth {
                    body: &q.body,
                    specific_force_frd: self.world.specific_force_frd(k),
                    ground_contact: self.world.quad_on_ground(k),
                    rotor_speed: q.rotor_speed,
                };
                self.px4[k].tick(self.t_ns, tick_dt, &truth);
                self.check_crash(k);
            }
        }
        let cmd = [*self.px4[0].rotor_cmd(), *self.px4[1].rotor_cmd()];
        self.world.step(self.dt_s, &cmd);
        self.t_ns += self.dt_ns;
        self.steps += 1;
    }

    fn check_crash(&mut self, k: usize) {
        let b = &self.world.state().quads[k].body;
        let p = b.position_ned;
        let mut flags = 0;
        if self
            .obstacles
            .iter()
            .any(|o| o.contains(&p, self.drone_radius_m))
        {
            flags |= crash_flags::OBSTACLE;
        }
        if (0..3).any(|i| p[i] < self.arena[0][i] - 0.01 || p[i] > self.arena[1][i] + 0.01) {
            flags |= crash_flags::ARENA;
        }
        // Body z axis pointing up: upside down.
        if (b.attitude * Vector3::z()).z < 0.0 {
            flags |= crash_flags::FLIPPED;
        }
        if self.world.quad_on_ground(k) && b.velocity_ned.z > self.crash_speed_m_s {
            flags |= crash_flags::GROUND;
        }
        self.crash_flags[k] |= flags;
    }

    /// A message for drone `k`'s autopilot (from its MAVLink link or an in-process companion).
    pub fn handle(&mut self, k: usize, msg: Inbound) -> Option<MavResult> {
        self.px4[k].handle(self.t_ns, msg).map(|r| match r {
            CommanderResult::Accepted => MavResult::MAV_RESULT_ACCEPTED,
            CommanderResult::TemporarilyRejected => MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
            CommanderResult::Denied => MavResult::MAV_RESULT_DENIED,
            CommanderResult::Unsupported => MavResult::MAV_RESULT_UNSUPPORTED,
            CommanderResult::Failed => MavResult::MAV_RESULT_FAILED,
        })
    }

    /// What drone `k`'s PX4 streams.
    pub fn telemetry(&self, k: usize) -> Telemetry {
        self.px4[k].telemetry(self.t_ns)
    }

    /// True cable pull on drone `k` at its anchor, body FRD, N: its force sensor's input.
    pub fn anchor_force_frd(&self, k: usize) -> [f64; 3] {
        let f = self.world.anchor_force_frd(k);
        [f.x, f.y, f.z]
    }

    /// Times each drone's failsafe fired.
    pub fn failsafe_count(&self) -> [u32; 2] {
        [0, 1].map(|k| self.drone_failsafes(k))
    }

    fn drone_failsafes(&self, k: usize) -> u32 {
        self.px4[k].commander().counters().failsafe_fired as u32
    }

    /// Bits of `shared_types::crash_flags` per drone, latched.
    pub fn crash_flags(&self) -> [u32; 2] {
        self.crash_flags
    }

    /// The ground truth at this instant (the header is the publisher's to fill).
    pub fn truth(&self) -> PlantTruth {
        let s = self.world.state();
        let drone = |k: usize| {
            let c = self.px4[k].commander();
            DroneTruth {
                body: body_truth(&s.quads[k].body),
                rotor_speed_rad_s: s.quads[k].rotor_speed,
                anchor_force_frd_n: self.anchor_force_frd(k),
                estimate_position_ned_m: arr(&self.px4[k].estimate().position_ned),
                mocap_position_ned_m: arr(&self.px4[k].mocap_position()),
                custom_mode: c.custom_mode(),
                armed: c.is_armed() as u32,
                failsafe_count: self.drone_failsafes(k),
                crash_flags: self.crash_flags[k],
            }
        };
        let contact = self.world.payload_contact();
        let cable = |i: usize| self.world.cable(i);
        PlantTruth {
            header: Default::default(),
            sim_time_ns: self.t_ns,
            drones: [drone(0), drone(1)],
            payload: body_truth(&s.payload),
            cable_tension_n: [cable(0).tension_n, cable(1).tension_n],
            cable_stretch_m: [cable(0).stretch_m, cable(1).stretch_m],
            payload_contact: match contact.surface {
                _ if !contact.in_contact => ContactKind::Free,
                Some(ContactSurface::Box(_)) => ContactKind::Box,
                _ => ContactKind::Ground,
            },
            payload_normal_force_n: contact.normal_force_n,
        }
    }
}

impl Vehicles for Plant {
    fn time_ns(&self) -> u64 {
        self.t_ns
    }
    fn telemetry(&self, drone: usize) -> Telemetry {
        Plant::telemetry(self, drone)
    }
    fn handle(&mut self, drone: usize, msg: Inbound) -> Option<MavResult> {
        Plant::handle(self, drone, msg)
    }
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn body_truth(b: &BodyState) -> BodyTruth {
    let q = b.attitude.quaternion();
    BodyTruth {
        position_ned_m: arr(&b.position_ned),
        velocity_ned_m_s: arr(&b.velocity_ned),
        attitude_wxyz: [q.w, q.i, q.j, q.k],
        rate_frd_rad_s: arr(&b.rate_frd),
    }
}

/// The physics' initial state from the scenario: drones standing or hovering, the payload
/// resting where the file says or hanging in equilibrium below the drones.
fn initial_state(
    scenario: &Scenario,
    params: &crate::physics::WorldParams,
) -> Result<WorldState, PlantError> {
    let err = |message: String| PlantError::Scenario {
        scenario: scenario.name.clone(),
        message,
    };
    let pos = |k: usize| Vector3::from(scenario.drones[k].position_ned_m);
    let mut state = match scenario.payload.start {
        PayloadStart::Hanging => {
            let (a, b) = (pos(0), pos(1));
            if (a.x - b.x).abs() > 1e-9 || (a.z - b.z).abs() > 1e-9 || a.y >= b.y {
                return Err(err(
                    "a hanging payload needs the drones side by side along y (drone 0 west), \
                     at one height"
                        .into(),
                ));
            }
            hanging_formation(params, (a + b) / 2.0, b.y - a.y).state
        }
        PayloadStart::Resting => {
            let p = scenario
                .payload
                .position_ned_m
                .ok_or_else(|| err("payload.position_ned_m missing".into()))?;
            let mut payload = BodyState::at_rest(Vector3::from(p));
            payload.attitude = level(scenario.payload.yaw_deg.to_radians());
            WorldState {
                time_s: 0.0,
                quads: [0, 1].map(|k| QuadState {
                    body: BodyState::at_rest(pos(k)),
                    rotor_speed: [0.0; 4],
                }),
                payload,
            }
        }
    };
    let g = params.gravity_m_s2;
    for k in 0..2 {
        let q = &mut state.quads[k];
        q.body.position_ned = pos(k);
        q.body.attitude = level(scenario.yaw_rad(k));
        q.body.velocity_ned = Vector3::zeros();
        q.body.rate_frd = Vector3::zeros();
        q.rotor_speed = match scenario.drones[k].start {
            DroneStart::Ground => [0.0; 4],
            DroneStart::Hover => {
                let share = match scenario.payload.start {
                    PayloadStart::Hanging => params.payload.mass_kg / 2.0,
                    PayloadStart::Resting => 0.0,
                };
                let w = params.quads[k].hover_rotor_speed(params.quads[k].mass_kg + share, g);
                [w; 4]
            }
        };
    }
    Ok(state)
}
