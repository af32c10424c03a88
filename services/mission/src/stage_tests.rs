use super::*;
use crate::signal::{encode_drone_id, signal_flags as sf};
use shared_types::mission_flags as mf;

pub(super) const TICK_NS: u64 = 10_000_000;
pub(super) const HS: u32 = vehicle_flags::HANDSHAKE_DONE;

pub(super) fn cfg(peer: &str) -> rt_config::MissionConfig {
    rt_config::MissionConfig {
        peer: peer.into(),
        ..Default::default()
    }
}

pub(super) fn scenario(name: &str) -> Scenario {
    Scenario::load(name).unwrap()
}

pub(super) fn state(now: u64, pos: [f64; 3], flags: u32) -> VehicleState {
    VehicleState {
        header: Header {
            t_origin_ns: now,
            ..Default::default()
        },
        position_ned_m: pos,
        flags,
        ..Default::default()
    }
}

pub(super) fn peer_signal(id: &str, phase_index: u32, flags: u32) -> PeerSignal {
    PeerSignal {
        drone_id: encode_drone_id(id).unwrap(),
        phase_index,
        flags,
        ..Default::default()
    }
}

pub(super) fn has(o: &MissionOutput, bit: u32) -> bool {
    o.setpoint.flags & bit != 0
}

#[test]
fn arm_request_only_when_both_idle_ready() {
    let s = scenario("test-a");
    let mut a = MissionStage::new(&s, 0, &cfg("uav2")).unwrap();
    let at = [1.0, -0.8, -0.12];
    let idle_peer = peer_signal("uav2", 0, sf::IDLE | sf::IDLE_READY);
    let mut now = 1_000_000_000;
    // Own ready, peer never heard.
    let o = a.step(now, Some(&state(now, at, 0)), None);
    assert!(!has(&o, mf::ARM_REQUEST) && has(&o, mf::PEER_LOST));
    assert_eq!(o.setpoint.phase, MissionPhase::Idle);
    assert_eq!(o.setpoint.position_ned_m, at);
    assert_eq!(o.setpoint.peer_position_ned_m, [1.0, 0.8, -0.12]);
    assert!((o.setpoint.yaw_rad - 30f64.to_radians()).abs() < 1e-12);
    assert!(!has(&o, mf::TENSION_ENABLED));
    assert!(o.signal.has(sf::IDLE) && o.signal.has(sf::IDLE_READY));
    // Peer heard but not idle-ready.
    now += TICK_NS;
    let not_ready = peer_signal("uav2", 0, sf::IDLE);
    let o = a.step(now, Some(&state(now, at, 0)), Some((&not_ready, now)));
    assert!(!has(&o, mf::ARM_REQUEST));
    assert_eq!(o.event, Some(MissionEvent::PeerRegained));
    // Peer idle-ready, own state stale (0.51 s old > 0.5 s), then own PX4 link lost, then none.
    now += TICK_NS;
    let stale = state(now - 510_000_000, at, 0);
    for own in [
        Some(stale),
        Some(state(now, at, vehicle_flags::LINK_LOST)),
        None,
    ] {
        let o = a.step(now, own.as_ref(), Some((&idle_peer, now)));
        assert!(!has(&o, mf::ARM_REQUEST) && !o.signal.has(sf::IDLE_READY));
    }
    // Both idle-ready.
    let o = a.step(now, Some(&state(now, at, 0)), Some((&idle_peer, now)));
    assert!(has(&o, mf::ARM_REQUEST));
    assert_eq!(o.event, Some(MissionEvent::ArmRequested));
}

#[test]
fn first_phase_starts_when_both_report_handshake_done() {
    let s = scenario("test-a");
    let mut a = MissionStage::new(&s, 0, &cfg("uav2")).unwrap();
    let at = [1.0, -0.8, -0.12];
    let mut now = 1_000_000_000;
    let idle = peer_signal("uav2", 0, sf::IDLE | sf::IDLE_READY);
    let idle_hs = peer_signal("uav2", 0, sf::IDLE | sf::IDLE_READY | sf::HANDSHAKE_DONE);
    a.step(now, Some(&state(now, at, 0)), Some((&idle, now)));
    for (own_flags, peer) in [(HS, &idle), (0, &idle_hs)] {
        now += TICK_NS;
        let o = a.step(now, Some(&state(now, at, own_flags)), Some((peer, now)));
        assert_eq!(o.setpoint.phase, MissionPhase::Idle);
        assert!(has(&o, mf::ARM_REQUEST), "ARM_REQUEST stays latched");
    }
    now += TICK_NS;
    let o = a.step(now, Some(&state(now, at, HS)), Some((&idle_hs, now)));
    assert_eq!(o.setpoint.phase, MissionPhase::Takeoff);
    assert_eq!(o.setpoint.phase_start_ns, now);
    assert!(has(&o, mf::ARM_REQUEST) && !has(&o, mf::TENSION_ENABLED));
    assert_eq!(
        o.event,
        Some(MissionEvent::PhaseStarted {
            index: 0,
            phase: MissionPhase::Takeoff,
            ended: None
        })
    );
}

/// A single stage fed crafted peer signals, flown to the end of the takeoff path + 1.5 s.
fn stage_in_takeoff() -> (MissionStage, u64) {
    let s = scenario("test-a");
    let mut a = MissionStage::new(&s, 0, &cfg("uav2")).unwrap();
    let idle_hs = peer_signal("uav2", 0, sf::IDLE | sf::IDLE_READY | sf::HANDSHAKE_DONE);
    let flying = peer_signal("uav2", 0, 0);
    let mut now = 1_000_000_000;
    let mut pos = [1.0, -0.8, -0.12];
    for i in 0..600 {
        now += TICK_NS;
        let peer = if a.started() && i > 5 {
            &flying
        } else {
            &idle_hs
        };
        let o = a.step(now, Some(&state(now, pos, HS)), Some((peer, now)));
        assert_eq!(
            o.setpoint.phase_index, 0,
            "no end while the peer is not ready"
        );
        pos = o.setpoint.position_ned_m;
    }
    (a, now)
}

#[test]
fn phase_ends_on_peer_ready_in_same_phase_or_peer_past_it() {
    let pos = [1.0, -0.8, -1.5];
    for (peer, ends) in [
        (peer_signal("uav2", 0, 0), false),
        (peer_signal("uav2", 0, sf::READY), true),
        (peer_signal("uav2", 1, 0), true),
        (peer_signal("uav2", 0, sf::IDLE | sf::READY), false),
    ] {
        let (mut a, now) = stage_in_takeoff();
        let now = now + TICK_NS;
        let o = a.step(now, Some(&state(now, pos, HS)), Some((&peer, now)));
        assert_eq!(o.setpoint.phase_index == 1, ends, "peer {peer:?}");
    }
    // Peer ready but we are not (1 m off our setpoint): no end.
    let (mut a, now) = stage_in_takeoff();
    let ready = peer_signal("uav2", 0, sf::READY);
    let o = a.step(
        now + TICK_NS,
        Some(&state(now, [1.0, -0.8, -0.5], HS)),
        Some((&ready, now)),
    );
    assert_eq!(o.setpoint.phase_index, 0);
    assert!(has(&o, mf::PEER_READY) && !has(&o, mf::READY));
}

#[test]
fn peer_holding_for_its_own_reason_holds_us_too() {
    let (mut a, mut now) = stage_in_takeoff();
    let pos = [1.0, -0.8, -1.5];
    let lost_us = peer_signal("uav2", 0, sf::HOLDING | sf::PEER_LOST);
    now += TICK_NS;
    let o = a.step(now, Some(&state(now, pos, HS)), Some((&lost_us, now)));
    assert_eq!(o.event, Some(MissionEvent::PeerHolding));
    assert!(has(&o, mf::HOLDING) && !has(&o, mf::PEER_LOST) && !o.signal.has(sf::PEER_LOST));
    // An echo of our own hold is not a reason: HOLDING alone does not hold us.
    now += TICK_NS;
    let echo = peer_signal("uav2", 0, sf::HOLDING | sf::READY);
    let o = a.step(now, Some(&state(now, pos, HS)), Some((&echo, now)));
    assert_eq!(o.event, Some(MissionEvent::PeerResumed));
    assert!(!has(&o, mf::HOLDING));
}

#[test]
fn unexpected_sender_is_ignored_and_counted_once() {
    let s = scenario("test-a");
    let mut a = MissionStage::new(&s, 0, &cfg("uav2")).unwrap();
    let at = [1.0, -0.8, -0.12];
    let intruder = peer_signal(
        "intruder",
        0,
        sf::IDLE | sf::IDLE_READY | sf::HANDSHAKE_DONE,
    );
    let now = 1_000_000_000;
    for k in 0..3 {
        let o = a.step(
            now + k * TICK_NS,
            Some(&state(now, at, HS)),
            Some((&intruder, now)),
        );
        assert!(!has(&o, mf::ARM_REQUEST) && has(&o, mf::PEER_LOST));
    }
    assert_eq!(a.counters().unexpected_sender, 1);
    assert!(matches!(
        MissionStage::new(&s, 0, &cfg("uav3")),
        Err(MissionError::PeerMismatch { .. })
    ));
}
