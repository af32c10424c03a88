//! The offboard handshake against a scripted PX4: order, timing, retries, give-up, restarts.
//! Defaults: stream_before_offboard_s 1.2, ack_timeout_s 0.3, command_attempts 5; 10 ms steps.

use crate::test_harness::{accept_all, Harness, STEP_NS};
use crate::*;
use mavlink::dialects::common::{MavCmd, MavResult, COMMAND_LONG_DATA};
use shared_types::vehicle_flags;

const MS: u64 = 1_000_000;
const MODE: MavCmd = MavCmd::MAV_CMD_DO_SET_MODE;
const ARM: MavCmd = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;

#[test]
fn streams_then_sets_offboard_then_arms() {
    let mut h = Harness::new();
    h.run(0.5, false, true, &mut accept_all);
    // Setpoints without ARM_REQUEST: streamed, but no handshake.
    for k in 0..200 {
        h.now += STEP_NS;
        if k % 10 == 0 {
            h.heartbeat();
        }
        assert!(h.setpoint(false).is_some());
        h.poll();
    }
    assert!(h.commands(MODE).is_empty() && h.commands(ARM).is_empty());
    assert_eq!(h.link.status().stage, HandshakeStage::Idle);
    // ARM_REQUEST on a stream that already ran 2 s: no further wait.
    let t_request = h.now + STEP_NS;
    h.run(0.05, true, true, &mut accept_all);
    assert!(h.commands(MODE)[0].0 - t_request <= 20 * MS);

    let mut h = Harness::new();
    h.run(0.5, false, true, &mut accept_all);
    let t_stream = h.now + STEP_NS;
    h.run(3.0, true, true, &mut accept_all);
    let (modes, arms) = (h.commands(MODE), h.commands(ARM));
    assert_eq!((modes.len(), arms.len()), (1, 1));
    let (t_mode, m) = modes[0].clone();
    assert_eq!(
        t_mode - t_stream,
        1200 * MS,
        "DO_SET_MODE after 1.2 s of stream"
    );
    assert_eq!((m.param1, m.param2, m.param3), (1.0, 6.0, 0.0));
    assert_eq!(
        (m.target_system, m.target_component, m.confirmation),
        (1, 1, 0)
    );
    let (t_arm, a) = arms[0].clone();
    // The ACCEPTED ack arrives one step later and the arm goes out in that step.
    assert_eq!(t_arm - t_mode, 10 * MS);
    assert_eq!((a.param1, a.param2), (1.0, 0.0));
    let s = h.link.status();
    assert_eq!(s.stage, HandshakeStage::Done);
    assert_eq!(
        s.flags,
        vehicle_flags::ARMED | vehicle_flags::OFFBOARD | vehicle_flags::HANDSHAKE_DONE
    );
}

#[test]
fn resends_after_missing_ack_and_after_temporary_rejection() {
    let mut h = Harness::new();
    let (mut n_mode, mut n_arm) = (0, 0);
    let mut px4 = |c: &COMMAND_LONG_DATA| match c.command {
        MODE => {
            n_mode += 1;
            (n_mode > 1).then_some(MavResult::MAV_RESULT_ACCEPTED)
        }
        ARM => {
            n_arm += 1;
            Some(if n_arm == 1 {
                MavResult::MAV_RESULT_TEMPORARILY_REJECTED
            } else {
                MavResult::MAV_RESULT_ACCEPTED
            })
        }
        _ => Some(MavResult::MAV_RESULT_ACCEPTED),
    };
    h.run(4.0, true, true, &mut px4);
    let (modes, arms) = (h.commands(MODE), h.commands(ARM));
    assert_eq!((modes.len(), arms.len()), (2, 2));
    assert_eq!(
        modes[1].0 - modes[0].0,
        300 * MS,
        "resent after ack_timeout_s"
    );
    assert_eq!((modes[0].1.confirmation, modes[1].1.confirmation), (0, 1));
    assert!(
        arms[0].0 > modes[1].0,
        "arm only after DO_SET_MODE was accepted"
    );
    // Rejection ack one step after the send, resend ack_timeout_s after the rejection.
    assert_eq!(arms[1].0 - arms[0].0, 310 * MS);
    let s = h.link.status();
    assert_eq!(s.stage, HandshakeStage::Done);
    let c = s.counters;
    assert_eq!(c.ack_timeouts, 1);
    assert_eq!(c.command_retries, 2);
    assert_eq!((c.acks_rejected, c.acks_temporarily_rejected), (1, 1));
}

#[test]
fn gives_up_after_command_attempts_and_restarts_on_a_new_request() {
    let mut h = Harness::new();
    let mut px4 = |c: &COMMAND_LONG_DATA| match c.command {
        MODE => Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED),
        _ => Some(MavResult::MAV_RESULT_ACCEPTED),
    };
    h.run(5.0, true, true, &mut px4);
    let modes = h.commands(MODE);
    assert_eq!(modes.len(), 5, "px4.command_attempts sends");
    for w in modes.windows(2) {
        assert_eq!(w[1].0 - w[0].0, 310 * MS);
    }
    assert!(h.commands(ARM).is_empty());
    let s = h.link.status();
    assert_eq!(s.stage, HandshakeStage::Failed);
    assert_eq!(
        s.failure,
        Some(HandshakeFailure::SetModeNotAccepted {
            sends: 5,
            last_result: Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED)
        })
    );
    assert!(s.flags & vehicle_flags::HANDSHAKE_FAILED != 0);
    h.run(2.0, true, true, &mut px4);
    assert_eq!(h.commands(MODE).len(), 5, "no more sends once failed");

    // The mission clears ARM_REQUEST, then asks again: a fresh handshake.
    h.now += STEP_NS;
    h.setpoint(false);
    assert_eq!(h.link.status().stage, HandshakeStage::Idle);
    assert_eq!(h.link.status().failure, None);
    h.run(3.0, true, true, &mut accept_all);
    assert_eq!(h.link.status().stage, HandshakeStage::Done);
    assert_eq!(h.commands(MODE).len(), 6);
}

#[test]
fn gives_up_on_arming_without_acks() {
    let mut h = Harness::new();
    let mut px4 = |c: &COMMAND_LONG_DATA| match c.command {
        ARM => None,
        _ => Some(MavResult::MAV_RESULT_ACCEPTED),
    };
    h.run(5.0, true, true, &mut px4);
    let arms = h.commands(ARM);
    assert_eq!(arms.len(), 5);
    for w in arms.windows(2) {
        assert_eq!(w[1].0 - w[0].0, 300 * MS);
    }
    let s = h.link.status();
    assert_eq!(
        s.failure,
        Some(HandshakeFailure::ArmNotAccepted {
            sends: 5,
            last_result: None
        })
    );
    assert_eq!(s.counters.ack_timeouts, 5);
    let shown = s.failure.unwrap().to_string();
    assert!(shown.contains("after 5 sends"), "{shown}");
}

#[test]
fn a_stream_gap_restarts_the_handshake() {
    let mut h = Harness::new();
    let mut ignore_mode = |c: &COMMAND_LONG_DATA| match c.command {
        MODE => None,
        _ => Some(MavResult::MAV_RESULT_ACCEPTED),
    };
    h.run(1.5, true, true, &mut ignore_mode);
    assert_eq!(h.link.status().stage, HandshakeStage::SettingOffboard);
    // 0.6 s without setpoints: after 0.5 s, back to waiting for the stream.
    h.run(0.6, false, true, &mut ignore_mode);
    let s = h.link.status();
    assert_eq!(s.stage, HandshakeStage::Idle);
    assert_eq!(s.counters.handshake_restarts, 1);
    let sent_before = h.commands(MODE).len();
    assert_eq!(
        sent_before, 3,
        "resends at 1.2, 1.5, 1.8 s; none after the gap is seen"
    );
    let t_stream = h.now + STEP_NS;
    h.run(3.0, true, true, &mut accept_all);
    let modes = h.commands(MODE);
    assert_eq!(
        modes[sent_before].0 - t_stream,
        1200 * MS,
        "a full stream again first"
    );
    assert_eq!(h.link.status().stage, HandshakeStage::Done);
}

#[test]
fn leaving_offboard_after_done_is_flagged_and_not_fought() {
    let mut h = Harness::new();
    h.run(3.0, true, true, &mut accept_all);
    assert_eq!(h.link.status().stage, HandshakeStage::Done);
    let commands = h.commands(MODE).len() + h.commands(ARM).len();
    h.px4_mode = (4 << 16) | (6 << 24); // AUTO.LAND, still armed
    h.run(2.0, true, true, &mut accept_all);
    let s = h.link.status();
    assert_eq!(s.stage, HandshakeStage::LeftOffboard);
    assert_eq!(s.flags, vehicle_flags::ARMED | vehicle_flags::LEFT_OFFBOARD);
    assert_eq!(h.commands(MODE).len() + h.commands(ARM).len(), commands);
}

#[test]
fn the_stream_counts_from_when_px4_is_heard() {
    let mut h = Harness::new();
    // 1 s of setpoints before PX4 is heard (on udpin they cannot even be sent).
    h.run(1.0, true, false, &mut accept_all);
    assert_eq!(h.link.status().stage, HandshakeStage::Streaming);
    h.now += STEP_NS;
    h.heartbeat();
    let t_link = h.now;
    h.run(2.0, true, true, &mut accept_all);
    assert_eq!(h.commands(MODE)[0].0 - t_link, 1200 * MS);
}
