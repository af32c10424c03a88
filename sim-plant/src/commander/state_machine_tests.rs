use super::*;
use crate::commander::stream::OffboardAvailability;

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
const HOLD: (f32, f32) = (4.0, 3.0);
const LAND: (f32, f32) = (4.0, 6.0);

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
fn starts_disarmed_in_position_and_reports_it() {
    let mut sim = Sim::new(CommanderParams::default());
    let c = &sim.c;
    assert_eq!((c.nav_state(), c.is_armed()), (NavState::Position, false));
    assert_eq!(c.custom_mode(), 3 << 16);
    assert_eq!(c.base_mode(), 1 | 64 | 16);
    assert_eq!(c.system_status(), mav_state::STANDBY);
    sim.run_until(S);
    assert_eq!(sim.last, ControlDemand::MotorsOff);
    assert_eq!(NavState::Offboard.custom_mode(), 6 << 16);
    assert_eq!(NavState::Hold.custom_mode(), (4 << 16) | (3 << 24));
    assert_eq!(NavState::Land.custom_mode(), (4 << 16) | (6 << 24));
}

#[test]
fn arming_in_offboard_needs_more_than_1_s_of_stream() {
    let mut sim = Sim::new(CommanderParams::default());
    // PX4 accepts any mode change while disarmed, stream or not; arming is what checks it.
    assert_eq!(sim.mode(OFFBOARD), MavResult::Accepted);
    assert_eq!(sim.c.custom_mode(), 6 << 16);
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::TemporarilyRejected);
    sim.msg = Some(attitude_msg(0.0));
    sim.run_until(S); // stream from 10 ms to 1000 ms
    sim.msg = None;
    sim.t = 1010 * MS; // the run started at 10 ms: exactly 1 s old is not enough
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::TemporarilyRejected);
    sim.t = 1010 * MS + 1;
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::Accepted);
    assert_eq!(
        sim.cmd(arm_cmd(1.0, 0.0)),
        MavResult::Accepted,
        "already armed"
    );
    assert_eq!(sim.c.base_mode(), 1 | 128 | 16);
    assert_eq!(sim.c.system_status(), mav_state::ACTIVE);
}

#[test]
fn switching_to_offboard_in_flight_needs_the_stream() {
    let mut sim = Sim::new(CommanderParams::default());
    assert_eq!(sim.mode(HOLD), MavResult::Accepted);
    assert_eq!(
        sim.cmd(arm_cmd(1.0, 0.0)),
        MavResult::Accepted,
        "Hold arms with a position"
    );
    assert_eq!(
        sim.mode(OFFBOARD),
        MavResult::TemporarilyRejected,
        "no stream"
    );
    // Exactly 2 Hz is not above 2 Hz.
    for k in 1..=10 {
        sim.c.on_attitude_target(k * 500 * MS, &attitude_msg(0.5));
    }
    sim.t = 5 * S + 100 * MS;
    assert_eq!(sim.mode(OFFBOARD), MavResult::TemporarilyRejected);
    // 2.5 Hz from 5.6 s (a 600 ms gap restarts the run): available once it is more than 1 s old.
    for k in 0..=2 {
        sim.c
            .on_attitude_target(5600 * MS + k * 400 * MS, &attitude_msg(0.5));
    }
    sim.t = 6600 * MS;
    assert_eq!(sim.mode(OFFBOARD), MavResult::TemporarilyRejected);
    sim.t = 6800 * MS;
    sim.c.on_attitude_target(sim.t, &attitude_msg(0.5));
    assert_eq!(sim.mode(OFFBOARD), MavResult::Accepted);
    assert_eq!(sim.c.counters().rejected_commands, 3);
}

#[test]
fn px4_code_rule_accepts_a_single_recent_message() {
    let params = CommanderParams {
        offboard_availability: OffboardAvailability::LastMessageAge,
        ..CommanderParams::default()
    };
    let mut sim = Sim::new(params);
    sim.mode(OFFBOARD);
    sim.c.on_attitude_target(sim.t, &attitude_msg(0.0));
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::Accepted);
}

#[test]
fn command_parameters_and_unknown_commands() {
    let mut sim = Sim::new(CommanderParams::default());
    assert_eq!(sim.cmd(arm_cmd(2.0, 0.0)), MavResult::Unsupported);
    assert_eq!(sim.cmd(arm_cmd(f32::NAN, 0.0)), MavResult::Unsupported);
    let interval = CommandLong {
        command: 511,
        params: [0.0; 7],
    };
    assert_eq!(sim.cmd(interval), MavResult::Unsupported);
    // Position cannot be armed in without RC; Land prevents arming.
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::TemporarilyRejected);
    assert_eq!(sim.mode(LAND), MavResult::Accepted);
    assert_eq!(
        sim.cmd(arm_cmd(1.0, 21196.0)),
        MavResult::TemporarilyRejected,
        "forced still checks"
    );
    // The packed custom_mode word in param2 casts to a non-mode: ACCEPTED, nothing changes.
    assert_eq!(sim.mode((393216.0, 0.0)), MavResult::Accepted);
    assert_eq!(sim.c.nav_state(), NavState::Land);
    assert_eq!(
        sim.mode((1.0, 0.0)),
        MavResult::TemporarilyRejected,
        "MANUAL not emulated"
    );
    assert_eq!(
        sim.mode((4.0, 1.0)),
        MavResult::TemporarilyRejected,
        "AUTO.READY unsupported"
    );
    assert_eq!(sim.c.counters().not_emulated_modes, 1);
    let with_rc = CommanderParams {
        rc_present: true,
        ..CommanderParams::default()
    };
    let mut sim = Sim::new(with_rc);
    assert_eq!(sim.cmd(arm_cmd(1.0, 0.0)), MavResult::Accepted);
}

#[test]
fn armed_mode_changes_follow_can_run() {
    let mut sim = Sim::flying_offboard(CommanderParams::default());
    assert_eq!(
        sim.mode((3.0, 0.0)),
        MavResult::TemporarilyRejected,
        "Position needs RC"
    );
    assert_eq!(sim.mode(HOLD), MavResult::Accepted);
    sim.run_until(sim.t + 10 * MS);
    assert_eq!(sim.c.nav_state(), NavState::Hold);
    match sim.last {
        ControlDemand::Position { position_ned, .. } => assert_eq!(position_ned.z, -1.5),
        other => panic!("{other:?}"),
    }
    // Setpoints outside offboard are not used; entering offboard holds until the next one.
    sim.msg = Some(attitude_msg(0.7));
    sim.run_until(sim.t + 100 * MS);
    sim.msg = None;
    assert_eq!(sim.mode(OFFBOARD), MavResult::Accepted);
    sim.step();
    assert!(matches!(sim.last, ControlDemand::Position { .. }));
    sim.c.on_attitude_target(sim.t, &attitude_msg(0.65));
    sim.step();
    assert_eq!(sim.last.thrust(), Some(0.65f32 as f64));
    assert_eq!(
        sim.mode(LAND),
        MavResult::Accepted,
        "Land is always allowed"
    );
}
