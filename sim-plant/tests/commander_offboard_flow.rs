//! End-to-end through the commander's public API: an offboard flight at 100 Hz, the stream
//! lost, the Land failsafe, touchdown, land detection and auto-disarm, with exact timings.

use nalgebra::Vector3;
use sim_plant::commander::modes::{mav_cmd, mav_state, mode_flag};
use sim_plant::commander::{
    AttitudeTarget, CommandLong, Commander, CommanderParams, ControlDemand, MavResult, NavState,
    OffboardLossAction, VehicleEstimate,
};

const MS: u64 = 1_000_000;
const S: u64 = 1_000_000_000;

fn attitude_msg(thrust: f32) -> AttitudeTarget {
    AttitudeTarget {
        q: [1.0, 0.0, 0.0, 0.0],
        body_rates: [0.0; 3],
        thrust,
        type_mask: 7,
        thrust_body: [0.0; 3],
    }
}

fn set_mode(main: f32, sub: f32) -> CommandLong {
    CommandLong {
        command: mav_cmd::DO_SET_MODE,
        params: [1.0, main, sub, 0.0, 0.0, 0.0, 0.0],
    }
}

fn arm_cmd(action: f32, param2: f32) -> CommandLong {
    CommandLong {
        command: mav_cmd::COMPONENT_ARM_DISARM,
        params: [action, param2, 0.0, 0.0, 0.0, 0.0, 0.0],
    }
}

const OFFBOARD: (f32, f32) = (6.0, 0.0);

/// A commander, a clock, and what the plant feeds it each 10 ms step.
struct Sim {
    c: Commander,
    t: u64,
    est: VehicleEstimate,
    ground: bool,
    /// Message sent at every step (before the update), if any.
    msg: Option<AttitudeTarget>,
    last: ControlDemand,
}

impl Sim {
    fn new(params: CommanderParams) -> Sim {
        let mut sim = Sim {
            c: Commander::new(params).unwrap(),
            t: 0,
            est: VehicleEstimate::at_rest(0, Vector3::new(0.5, -0.5, 0.0)),
            ground: true,
            msg: None,
            last: ControlDemand::MotorsOff,
        };
        sim.step();
        sim
    }

    fn step(&mut self) {
        if let Some(m) = self.msg {
            self.c.on_attitude_target(self.t, &m);
        }
        self.est.t_ns = self.t;
        self.last = self.c.update(self.t, &self.est, self.ground);
    }

    /// Steps every 10 ms until `t_ns` (inclusive, if on the grid).
    fn run_until(&mut self, t_ns: u64) {
        while self.t + 10 * MS <= t_ns {
            self.t += 10 * MS;
            self.step();
        }
    }

    fn cmd(&mut self, cmd: CommandLong) -> MavResult {
        self.c.on_command(self.t, &cmd)
    }

    fn mode(&mut self, (main, sub): (f32, f32)) -> MavResult {
        self.cmd(set_mode(main, sub))
    }

    /// Streams attitude setpoints at 100 Hz, switches to offboard, arms after 1.2 s of stream,
    /// climbs to 1.5 m (the estimate jumps there) and flies until t = 2 s.
    fn flying_offboard(params: CommanderParams) -> Sim {
        let mut sim = Sim::new(params);
        sim.msg = Some(attitude_msg(0.6));
        sim.step();
        assert_eq!(sim.mode(OFFBOARD), MavResult::Accepted);
        sim.run_until(1200 * MS);
        assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::Accepted);
        sim.ground = false;
        sim.est.position_ned.z = -1.5;
        sim.run_until(2 * S);
        assert!(!sim.c.land_detector().landed(), "took off");
        sim
    }
}

#[test]
fn stream_loss_fires_the_land_failsafe_at_exactly_com_of_loss_t() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    let last_msg = sim.t;
    sim.msg = None;
    sim.run_until(last_msg + 990 * MS);
    sim.t = last_msg + S - 1;
    sim.step();
    assert_eq!(sim.c.nav_state(), NavState::Offboard);
    assert!(!sim.c.failsafe_fired());
    assert_eq!(
        sim.last.thrust(),
        Some(0.6f32 as f64),
        "last setpoint held until the failsafe"
    );
    sim.t = last_msg + S;
    sim.step();
    assert_eq!(sim.c.nav_state(), NavState::Land);
    assert_eq!(sim.c.custom_mode(), (4 << 16) | (6 << 24));
    assert_eq!(sim.c.user_intended_mode(), NavState::Offboard);
    assert!(sim.c.failsafe_active() && sim.c.failsafe_fired());
    assert_eq!(sim.c.system_status(), mav_state::CRITICAL);
    assert_eq!(sim.c.base_mode(), 1 | 128 | 4 | 8 | 16);
    match sim.last {
        ControlDemand::Position {
            position_ned,
            velocity_ned,
            ..
        } => {
            assert_eq!((position_ned.x, position_ned.y), (0.5, -0.5), "holds x/y");
            assert!(position_ned.z.is_nan());
            assert_eq!(velocity_ned, Vector3::new(0.0, 0.0, 0.7));
        }
        other => panic!("expected the land descent, got {other:?}"),
    }
    assert_eq!(sim.c.counters().failsafe_fired, 1);
}

#[test]
fn failsafe_clears_when_the_stream_is_back_for_more_than_1_s() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    sim.msg = None;
    let lost_at = sim.t + S;
    sim.run_until(lost_at + 500 * MS);
    assert_eq!(sim.c.nav_state(), NavState::Land);
    let resume = sim.t + 10 * MS;
    sim.msg = Some(attitude_msg(0.55));
    sim.run_until(resume + S);
    assert_eq!(sim.c.nav_state(), NavState::Land, "run exactly 1 s old");
    sim.run_until(resume + S + 10 * MS);
    assert_eq!(sim.c.nav_state(), NavState::Offboard);
    assert!(!sim.c.failsafe_active() && sim.c.failsafe_fired());
    assert_eq!(sim.c.system_status(), mav_state::ACTIVE);
    // The setpoint in use is one received after the return to offboard.
    assert!(
        matches!(sim.last, ControlDemand::Position { .. }),
        "hold for one period"
    );
    sim.run_until(sim.t + 10 * MS);
    assert_eq!(sim.last.thrust(), Some(0.55f32 as f64));
}

#[test]
fn land_detection_and_auto_disarm_after_2_s_on_the_ground() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    sim.msg = None;
    sim.run_until(sim.t + S);
    assert_eq!(sim.c.nav_state(), NavState::Land);
    sim.run_until(sim.t + S);
    assert!(
        !sim.c.land_detector().landed(),
        "in the air, no ground contact"
    );
    assert_eq!(
        sim.cmd(arm_cmd(0.0, 0.0)),
        MavResult::TemporarilyRejected,
        "not landed"
    );
    // Touchdown: physics reports contact, the vehicle is still.
    sim.ground = true;
    sim.est.position_ned.z = 0.0;
    let touchdown = sim.t + 10 * MS;
    let mut landed_at = None;
    while sim.c.is_armed() {
        sim.run_until(sim.t + 10 * MS);
        if landed_at.is_none() && sim.c.land_detector().landed() {
            landed_at = Some(sim.t);
        }
        assert!(sim.t < touchdown + 10 * S, "never disarmed");
    }
    let landed_at = landed_at.unwrap();
    // Three stages of 1/3 s, each one step late, and the disarm hysteresis of 2 s.
    assert_eq!(landed_at - touchdown, 1040 * MS);
    assert_eq!(sim.t - landed_at, 2 * S);
    assert_eq!(sim.last, ControlDemand::MotorsOff);
    assert_eq!(sim.c.counters().auto_disarms, 1);
    // Back to the user's mode (Offboard) and STANDBY; the failsafe flag stays latched.
    assert_eq!(sim.c.nav_state(), NavState::Offboard);
    assert_eq!(sim.c.system_status(), mav_state::STANDBY);
    assert!(sim.c.failsafe_fired() && !sim.c.failsafe_active());
}

#[test]
fn disarm_in_flight_is_refused_unless_forced() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    assert_eq!(sim.cmd(arm_cmd(0.0, 0.0)), MavResult::TemporarilyRejected);
    assert!(sim.c.is_armed());
    assert_eq!(sim.cmd(arm_cmd(0.0, 21196.0)), MavResult::Accepted);
    assert!(!sim.c.is_armed());
    assert_eq!(
        sim.cmd(arm_cmd(0.0, 0.0)),
        MavResult::Accepted,
        "already disarmed"
    );
    sim.step();
    assert_eq!(sim.last, ControlDemand::MotorsOff);
}

#[test]
fn invalid_setpoints_keep_the_last_valid_one_and_the_stream_alive() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    let mut bad = attitude_msg(0.9);
    bad.q = [f32::NAN, 0.0, 0.0, 0.0];
    sim.msg = Some(bad);
    sim.run_until(sim.t + 3 * S);
    assert_eq!(sim.c.nav_state(), NavState::Offboard, "still proof of life");
    assert_eq!(sim.last.thrust(), Some(0.6f32 as f64));
    assert_eq!(sim.c.counters().invalid_setpoints, 300);
    // Ignoring attitude and the roll/pitch rates publishes nothing: the stream is lost.
    let mut silent = attitude_msg(0.6);
    silent.type_mask = 128 | 3;
    sim.msg = Some(silent);
    sim.run_until(sim.t + S);
    assert_eq!(sim.c.nav_state(), NavState::Land);
    assert_eq!(sim.c.counters().no_proof_of_life, 100);
}

#[test]
fn rate_setpoints_and_rate_injection_reach_the_demand() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    let mut both = attitude_msg(0.6);
    both.type_mask = 0;
    both.body_rates = [0.0, 0.1, 0.0];
    sim.msg = Some(both);
    sim.run_until(sim.t + 10 * MS);
    match sim.last {
        ControlDemand::Attitude {
            rate_injection: Some(inj),
            ..
        } => assert_eq!((inj.rates_frd.y as f32, inj.t_ns), (0.1, sim.t)),
        other => panic!("{other:?}"),
    }
    assert_eq!(sim.c.base_mode() & mode_flag::STABILIZE_ENABLED, 16);
    let mut rates = both;
    rates.type_mask = 128;
    sim.msg = Some(rates);
    sim.run_until(sim.t + 10 * MS);
    assert!(matches!(sim.last, ControlDemand::Rates { .. }));
    assert_eq!(
        sim.c.base_mode(),
        1 | 128,
        "rates only: no attitude control"
    );
}

#[test]
fn preflight_auto_disarm_after_com_disarm_prflt_plus_spoolup() {
    let mut sim = Sim::new(CommanderParams::default());
    sim.msg = Some(attitude_msg(0.0));
    sim.mode(OFFBOARD);
    sim.run_until(1100 * MS);
    let armed_at = sim.t;
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::Accepted);
    sim.run_until(armed_at + 11 * S - 10 * MS);
    assert!(sim.c.is_armed());
    assert!(matches!(sim.last, ControlDemand::Attitude { thrust, .. } if thrust == 0.0));
    sim.run_until(armed_at + 11 * S);
    assert!(!sim.c.is_armed());
    assert_eq!(sim.c.counters().auto_disarms, 1);
}

#[test]
fn other_loss_actions_and_bad_estimates() {
    for (action, mode) in [
        (OffboardLossAction::Hold, NavState::Hold),
        (OffboardLossAction::Position, NavState::Position),
    ] {
        let params = CommanderParams {
            offboard_loss_action: action,
            ..CommanderParams::default()
        };
        let mut sim = Sim::flying_offboard(params);
        sim.msg = None;
        sim.run_until(sim.t + S);
        assert_eq!(sim.c.nav_state(), mode);
        match sim.last {
            ControlDemand::Position { position_ned, .. } => assert_eq!(position_ned.z, -1.5),
            other => panic!("{other:?}"),
        }
    }
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    sim.est.position_ned.x = f64::NAN;
    sim.run_until(sim.t + 50 * MS);
    assert_eq!(sim.c.counters().invalid_estimates, 5);
    assert_eq!(sim.last.thrust(), Some(0.6f32 as f64));
}
