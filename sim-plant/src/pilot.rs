//! The plant's own pilot: flies a scenario through the emulated PX4's offboard interface with
//! PX4's position controller, the way a companion would (setpoint stream first, then
//! DO_SET_MODE offboard, then arm), without any taut service. It makes the plant usable alone
//! (`taut plant --pilot`, the fast-mode benchmark) and exercises the same inbound path that the
//! MAVLink endpoint feeds.

use crate::inner_loops::{ParamsError, PositionControl, PositionControlParams, TrajectorySetpoint};
use crate::mavlink_link::{
    px4_custom_mode, Inbound, MavResult, Telemetry, MAV_MODE_FLAG_SAFETY_ARMED,
    PX4_MAIN_MODE_OFFBOARD,
};
use crate::scenario::{PhaseEvent, PhaseTracker, Scenario};

/// MAV_CMD_DO_SET_MODE.
pub const MAV_CMD_DO_SET_MODE: u16 = 176;
/// MAV_CMD_COMPONENT_ARM_DISARM.
pub const MAV_CMD_COMPONENT_ARM_DISARM: u16 = 400;
/// SET_ATTITUDE_TARGET type_mask: ignore the three body rates (attitude + thrust).
pub const ATTITUDE_AND_THRUST: u8 = 7;

/// Where a drone's offboard handshake stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Handshake {
    /// Streaming setpoints since this time, ns.
    Streaming { since_ns: u64 },
    /// Offboard accepted; arming.
    Arming,
    /// Armed in offboard.
    Flying,
}

/// Anything that can take the pilot's messages and give telemetry: the in-process plant, or
/// a test double.
pub trait Vehicles {
    fn time_ns(&self) -> u64;
    fn telemetry(&self, drone: usize) -> Telemetry;
    fn handle(&mut self, drone: usize, msg: Inbound) -> Option<MavResult>;
}

/// Flies both drones through the scenario's phases at 100 Hz.
#[derive(Debug)]
pub struct ScenarioPilot {
    scenario: Scenario,
    tracker: PhaseTracker,
    /// The phases start once both drones fly in offboard.
    phases_started: bool,
    position: [PositionControl; 2],
    yaw_rad: [f64; 2],
    handshake: [Handshake; 2],
    period_ns: u64,
    next_ns: u64,
    last_ns: Option<u64>,
    started: bool,
    /// Phases that have ended.
    phases_completed: usize,
    timed_out: bool,
}

impl ScenarioPilot {
    /// `params.hover_throttle` is what the pilot believes (PX4's MPC_THR_HOVER).
    pub fn new(scenario: &Scenario, params: &PositionControlParams) -> Result<Self, ParamsError> {
        let pc = || PositionControl::new(params);
        Ok(ScenarioPilot {
            scenario: scenario.clone(),
            tracker: PhaseTracker::new(scenario, 0.0),
            phases_started: false,
            position: [pc()?, pc()?],
            yaw_rad: [scenario.yaw_rad(0), scenario.yaw_rad(1)],
            handshake: [Handshake::Streaming { since_ns: 0 }; 2],
            period_ns: 10_000_000,
            next_ns: 0,
            last_ns: None,
            started: false,
            phases_completed: 0,
            timed_out: false,
        })
    }

    pub fn phases_completed(&self) -> usize {
        self.phases_completed
    }

    /// Every phase ended.
    pub fn completed(&self) -> bool {
        self.tracker.done()
    }

    /// Completed, or a phase timed out.
    pub fn finished(&self) -> bool {
        self.tracker.done() || self.timed_out
    }

    pub fn tracker(&self) -> &PhaseTracker {
        &self.tracker
    }

    /// Call after every plant step; acts at 100 Hz of plant time.
    pub fn on_step<V: Vehicles>(&mut self, v: &mut V) {
        let now = v.time_ns();
        if now < self.next_ns {
            return;
        }
        self.next_ns = now + self.period_ns;
        if !self.started {
            self.started = true;
            self.handshake = [Handshake::Streaming { since_ns: now }; 2];
        }
        let dt = self
            .last_ns
            .map_or(self.period_ns as f64 * 1e-9, |l| (now - l) as f64 * 1e-9);
        self.last_ns = Some(now);
        let t_s = now as f64 * 1e-9;
        let tel = [v.telemetry(0), v.telemetry(1)];
        let flying = self.handshake.iter().all(|h| *h == Handshake::Flying);
        if flying && !self.phases_started {
            // Paths are timed from the moment both drones fly.
            self.phases_started = true;
            self.tracker = PhaseTracker::new(&self.scenario, t_s);
        }
        if flying && !self.finished() {
            let pos = [tel[0].position_ned_m, tel[1].position_ned_m];
            match self.tracker.update(t_s, &pos) {
                PhaseEvent::Ended { .. } => self.phases_completed += 1,
                PhaseEvent::TimedOut { .. } => self.timed_out = true,
                PhaseEvent::Running => {}
            }
        }
        for (k, tel) in tel.iter().enumerate() {
            self.fly(v, k, tel, now, t_s, dt);
        }
    }

    fn fly<V: Vehicles>(
        &mut self,
        v: &mut V,
        k: usize,
        tel: &Telemetry,
        now: u64,
        t_s: f64,
        dt: f64,
    ) {
        // Before the phases run (handshake), hold the start point.
        let sp = if self.phases_started {
            let s = self.tracker.setpoint(k, t_s);
            TrajectorySetpoint {
                position_ned_m: s.position_ned_m,
                velocity_ned_m_s: s.velocity_ned_m_s,
                acceleration_ned_m_s2: s.acceleration_ned_m_s2,
                yaw_rad: self.yaw_rad[k],
                yaw_rate_rad_s: 0.0,
            }
        } else {
            TrajectorySetpoint::position(
                self.tracker.setpoint(k, 0.0).position_ned_m,
                self.yaw_rad[k],
            )
        };
        let armed = tel.base_mode & MAV_MODE_FLAG_SAFETY_ARMED != 0;
        self.position[k].set_landed(!armed);
        let out = self.position[k].update(
            dt.clamp(0.002, 0.04),
            &tel.position_ned_m,
            &tel.velocity_ned_m_s,
            self.yaw_rad[k],
            &sp,
        );
        let (q, thrust) = match out {
            Ok(o) => (o.attitude_sp, o.thrust),
            Err(_) => (tel.attitude_body_to_ned, 0.0),
        };
        let q = q.into_inner();
        v.handle(
            k,
            Inbound::AttitudeTarget {
                time_boot_ms: (now / 1_000_000) as u32,
                q: [q.w as f32, q.i as f32, q.j as f32, q.k as f32],
                body_rates: [0.0; 3],
                thrust: thrust as f32,
                type_mask: ATTITUDE_AND_THRUST,
                thrust_body: [0.0; 3],
            },
        );
        let offboard = tel.custom_mode == px4_custom_mode(PX4_MAIN_MODE_OFFBOARD, 0);
        self.handshake[k] = match self.handshake[k] {
            // PX4 wants the stream for more than 1 s before the switch.
            Handshake::Streaming { since_ns } if now >= since_ns + 1_200_000_000 => {
                let r = v.handle(k, command(MAV_CMD_DO_SET_MODE, [1.0, 6.0]));
                if r == Some(MavResult::MAV_RESULT_ACCEPTED) {
                    Handshake::Arming
                } else {
                    Handshake::Streaming { since_ns }
                }
            }
            Handshake::Arming if offboard => {
                if armed {
                    Handshake::Flying
                } else {
                    v.handle(k, command(MAV_CMD_COMPONENT_ARM_DISARM, [1.0, 0.0]));
                    Handshake::Arming
                }
            }
            h => h,
        };
    }
}

fn command(command: u16, p: [f32; 2]) -> Inbound {
    Inbound::Command {
        command,
        params: [p[0], p[1], 0.0, 0.0, 0.0, 0.0, 0.0],
        from: (255, 190),
    }
}
