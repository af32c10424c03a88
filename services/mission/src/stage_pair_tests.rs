//! Both drones' stages run against each other in lockstep (signals one tick late).

use super::tests::{cfg, has, scenario, state, HS, TICK_NS};
use super::*;
use crate::signal::signal_flags as sf;
use shared_types::mission_flags as mf;

/// Both drones' stages in lockstep at 100 Hz, signals delivered one tick late; each drone sits
/// at its last setpoint plus `offset`.
struct Pair {
    stages: [MissionStage; 2],
    last: [Option<MissionOutput>; 2],
    inbox: [Option<(PeerSignal, u64)>; 2],
    now: u64,
    t0: u64,
    link_up: bool,
    offset: [[f64; 3]; 2],
    flags: [u32; 2],
    events: Vec<(f64, usize, MissionEvent)>,
}

impl Pair {
    fn new(name: &str) -> Pair {
        let s = scenario(name);
        Pair {
            stages: [
                MissionStage::new(&s, 0, &cfg("uav2")).unwrap(),
                MissionStage::new(&s, 1, &cfg("uav1")).unwrap(),
            ],
            last: [None, None],
            inbox: [None, None],
            now: 1_000_000_000,
            t0: 1_000_000_000,
            link_up: true,
            offset: [[0.0; 3]; 2],
            flags: [HS; 2],
            events: Vec::new(),
        }
    }

    fn t(&self) -> f64 {
        (self.now - self.t0) as f64 * 1e-9
    }

    fn tick(&mut self) -> [MissionOutput; 2] {
        self.now += TICK_NS;
        let outs = [0, 1].map(|i| {
            let mut pos = self.last[i].map_or_else(
                || self.stages[i].idle_own.into(),
                |o| o.setpoint.position_ned_m,
            );
            (0..3).for_each(|j| pos[j] += self.offset[i][j]);
            let st = state(self.now, pos, self.flags[i]);
            let peer = self.inbox[i].as_ref().map(|(s, t)| (s, *t));
            let o = self.stages[i].step(self.now, Some(&st), peer);
            if let Some(e) = o.event {
                self.events.push((self.t(), i, e));
            }
            o
        });
        if self.link_up {
            self.inbox[0] = Some((outs[1].signal, self.now));
            self.inbox[1] = Some((outs[0].signal, self.now));
        }
        self.last = outs.map(Some);
        outs
    }

    /// Ticks until `pred` holds (returns the time) or `max_s` passes (None).
    fn run_until(
        &mut self,
        max_s: f64,
        mut pred: impl FnMut(&[MissionOutput; 2]) -> bool,
    ) -> Option<f64> {
        let end = self.t() + max_s;
        while self.t() < end {
            let o = self.tick();
            if pred(&o) {
                return Some(self.t());
            }
        }
        None
    }

    fn run_for(&mut self, s: f64) -> [MissionOutput; 2] {
        let end = self.t() + s;
        let mut o = self.tick();
        while self.t() < end {
            o = self.tick();
        }
        o
    }
}

#[test]
fn arm_times_out_without_handshake() {
    let mut p = Pair::new("test-a");
    p.flags = [0, HS];
    let t = p.run_until(16.0, |o| has(&o[0], mf::TIMED_OUT)).unwrap();
    // Arm requested at 0.02 s; arm_timeout_s = 15 s.
    assert!((15.02..15.05).contains(&t), "t = {t}");
    let o = p.tick();
    assert!(!has(&o[0], mf::ARM_REQUEST) && o[0].setpoint.phase == MissionPhase::Idle);
    assert!(p.events.contains(&(t, 0, MissionEvent::ArmTimedOut)));
}

#[test]
fn phase_needs_both_ready_and_one_second_within_0_3_m() {
    let mut p = Pair::new("test-a");
    let started = p
        .run_until(1.0, |o| o[0].setpoint.phase == MissionPhase::Takeoff)
        .unwrap();
    // Both on their setpoints: 4 s path + 1 s settle (+ one tick of signal latency).
    if let Some(t) = p.run_until(4.99, |o| o[0].setpoint.phase_index > 0) {
        panic!("ended at {t}");
    }
    let ended = p
        .run_until(0.1, |o| o.iter().all(|o| o.setpoint.phase_index == 1))
        .unwrap();
    let d = ended - started;
    eprintln!("takeoff ended {d:.3} s after it started");
    assert!(
        (5.0..=5.03).contains(&d),
        "takeoff ended {d} s after it started"
    );

    // The move (a step): B stays 0.31 m off (outside 0.3 m): A ready, nobody advances.
    p.offset[1] = [0.0, 0.0, 0.31];
    let o = p.run_for(8.0);
    assert_eq!(
        [o[0].setpoint.phase_index, o[1].setpoint.phase_index],
        [1, 1]
    );
    assert!(has(&o[0], mf::READY) && !has(&o[0], mf::PEER_READY));
    assert!(!has(&o[1], mf::READY) && has(&o[1], mf::PEER_READY));
    // 0.29 m is within: both advance 1 s later (+ at most 3 ticks: the drone moves in on the
    // next tick, the settle ends on a tick, the peer hears it one tick later).
    p.offset[1] = [0.0, 0.0, 0.29];
    let inside = p.t();
    let ended = p
        .run_until(2.0, |o| o.iter().all(|o| o.setpoint.phase_index == 2))
        .unwrap();
    eprintln!("move ended {:.3} s after B came within", ended - inside);
    assert!(
        (1.0..=1.035).contains(&(ended - inside)),
        "{}",
        ended - inside
    );
}

#[test]
fn peer_silence_holds_the_path_frozen_and_resumes_where_it_was() {
    let mut p = Pair::new("test-a");
    let started = p
        .run_until(1.0, |o| o[0].setpoint.phase == MissionPhase::Takeoff)
        .unwrap();
    p.run_for(2.0);
    p.link_up = false;
    let cut = p.t();
    let lost = p.run_until(1.0, |o| has(&o[0], mf::PEER_LOST)).unwrap();
    eprintln!("peer lost {:.3} s after the cut", lost - cut);
    assert!(
        (lost - cut - 0.5).abs() <= 0.015,
        "lost {} s after the cut",
        lost - cut
    );
    let o = p.tick();
    assert_eq!(o[0].setpoint.phase, MissionPhase::Hold);
    assert!(has(&o[0], mf::HOLDING) && has(&o[1], mf::PEER_LOST));
    let frozen = o[0].setpoint.position_ned_m;
    let o = p.run_for(3.0);
    assert_eq!(
        o[0].setpoint.position_ned_m, frozen,
        "setpoint moved while holding"
    );
    assert!(!has(&o[0], mf::TIMED_OUT));
    p.link_up = true;
    let o = p
        .run_until(0.1, |o| !has(&o[0], mf::HOLDING))
        .map(|_| p.last[0].unwrap());
    let o = o.unwrap();
    assert_eq!(o.setpoint.phase, MissionPhase::Takeoff);
    let step = (o.setpoint.position_ned_m[2] - frozen[2]).abs();
    eprintln!("resumed {step:.4} m from the frozen setpoint");
    assert!(
        step < 0.01,
        "resumed {step} m away from the frozen setpoint"
    );
    // Path time lost = the frozen time (3 s + a few ticks; the 0.5 s before noticing still ran).
    let ended = p
        .run_until(6.0, |o| o[0].setpoint.phase_index == 1)
        .unwrap();
    let pause = ended - started - 5.0;
    eprintln!("takeoff took {pause:.3} s longer");
    assert!(
        (3.0..3.1).contains(&pause),
        "takeoff took {pause} s more than 5 s"
    );
}

#[test]
fn tension_off_only_in_test_a_takeoff_and_done_holds_last_setpoint() {
    let mut p = Pair::new("test-a");
    let mut seen = Vec::new();
    p.run_until(60.0, |o| {
        let key = (o[0].setpoint.phase, has(&o[0], mf::TENSION_ENABLED));
        if seen.last() != Some(&key) {
            seen.push(key);
        }
        o[0].setpoint.phase == MissionPhase::Done
    })
    .unwrap();
    use MissionPhase::*;
    assert_eq!(
        seen,
        [
            (Idle, false),
            (Takeoff, false),
            (Move, true),
            (Hold, true),
            (Done, true)
        ]
    );
    let o = p.run_for(2.0);
    assert_eq!(o[0].setpoint.phase_index, 3);
    assert_eq!(o[0].setpoint.position_ned_m, [-1.0, -0.8, -2.1]);
    assert_eq!(o[0].setpoint.peer_position_ned_m, [-1.0, 0.8, -2.1]);
    assert!(o[0].signal.has(sf::DONE) && !has(&o[0], mf::HOLDING));
}

#[test]
fn test_b_tension_is_on_in_every_phase() {
    let mut p = Pair::new("test-b");
    let mut seen = Vec::new();
    p.run_until(60.0, |o| {
        let key = (o[1].setpoint.phase, has(&o[1], mf::TENSION_ENABLED));
        if seen.last() != Some(&key) {
            seen.push(key);
        }
        o[1].setpoint.phase == MissionPhase::Done
    })
    .unwrap();
    use MissionPhase::*;
    let expected = [
        (Idle, false),
        (Hold, true),
        (Move, true),
        (Hold, true),
        (Move, true),
        (Done, true),
    ];
    assert_eq!(seen, expected);
}

#[test]
fn phase_timeout_freezes_for_good() {
    let mut p = Pair::new("test-a");
    let started = p
        .run_until(1.0, |o| o[0].setpoint.phase == MissionPhase::Takeoff)
        .unwrap();
    p.offset[1] = [0.0, 0.0, 1.0];
    let t = p.run_until(25.0, |o| has(&o[0], mf::TIMED_OUT)).unwrap();
    eprintln!("timed out {:.3} s into the takeoff", t - started);
    assert!(
        (t - started - 20.0).abs() < 0.02,
        "timed out {} s in",
        t - started
    );
    p.offset[1] = [0.0; 3];
    let o = p.run_for(5.0);
    assert_eq!(o[0].setpoint.phase, MissionPhase::Hold);
    assert_eq!(o[0].setpoint.phase_index, 0);
    assert!(has(&o[0], mf::HOLDING) && has(&o[1], mf::TIMED_OUT));
}
