//! `taut svc px4-bridge` against pymavlink playing PX4 (services/px4-bridge/tests/py/
//! px4_peer.py) over UDP on loopback, with this test in the controller's place: it publishes
//! AttitudeSetpoints (ARM_REQUEST) at 100 Hz on iceoryx2 and records what the bridge publishes.
//! Times on both sides are CLOCK_MONOTONIC (Python's time.monotonic). Needs python3 with
//! pymavlink; fails (does not skip) without them.

mod bridge_support;

use bridge_support::{commands, counter, f, fly, secs, start, stop_both, test_setpoint};
use bridge_support::{Q, THRUST_N};
use px4_bridge::normalized_thrust;
use shared_types::vehicle_flags as vf;
use std::time::Duration;

#[test]
fn handshake_with_retries_setpoints_telemetry_garbage_and_link_loss() {
    let (cfg, mut bridge, mut peer, _file) = start("flow");
    let o = fly(
        &cfg,
        test_setpoint(),
        |_| peer.running(),
        Duration::from_secs(16),
    );
    let (rec, log) = stop_both(&mut bridge, &mut peer);
    println!("bridge: {}", log.lines().last().unwrap_or(""));

    // Every frame a MAVLink 2 frame with a good CRC (pymavlink checks it).
    assert_eq!(
        (rec["bad_frames"].as_u64(), rec["non_v2_datagrams"].as_u64()),
        (Some(0), Some(0))
    );
    // SET_ATTITUDE_TARGET: mask 7, PX4's thrust map, the normalised q, addressed to 1/1.
    let v = &cfg.vehicle;
    let thrust = normalized_thrust(THRUST_N, v.mass_kg, v.hover_throttle, v.gravity_m_s2);
    let n = Q.iter().map(|c| c * c).sum::<f64>().sqrt();
    let sps = rec["setpoints"].as_array().unwrap();
    assert!(sps.len() > 500, "only {} setpoints", sps.len());
    for s in sps {
        assert_eq!(
            (s[1].as_u64(), s[4].as_u64(), s[5].as_u64()),
            (Some(7), Some(1), Some(1))
        );
        assert!(
            (f(&s[2]) - f64::from(thrust)).abs() < 1e-7,
            "thrust {} vs {thrust}",
            s[2]
        );
        for k in 0..4 {
            assert!((f(&s[3][k]) - Q[k] / n).abs() < 1e-6, "q {}", s[3]);
        }
        assert!(
            (f(&s[6]) - f(&s[0]) * 1e3).abs() < 50.0,
            "time_boot_ms {} at {}",
            s[6],
            s[0]
        );
    }
    // Our HEARTBEAT: onboard controller, 1/191, at 1 Hz.
    let hb = rec["heartbeats"].as_array().unwrap();
    assert!(
        hb.iter().all(|h| h[1] == 18 && h[3] == 1 && h[4] == 191),
        "{hb:?}"
    );
    let period = (f(&hb[hb.len() - 1][0]) - f(&hb[0][0])) / (hb.len() - 1) as f64;
    println!("heartbeats: {} at {period:.3} s", hb.len());
    let run_s = f(&rec["t_end"]) - f(&rec["t_start"]);
    assert!(
        hb.len() as f64 >= run_s - 2.0 && (period - 1.0).abs() < 0.05,
        "{} heartbeats in {run_s:.1} s, {period} s apart",
        hb.len()
    );
    // Stream rates asked once each (accepted at once), and again after the link loss.
    let got: Vec<(f64, f64)> = commands(&rec, 511)
        .iter()
        .map(|c| (c.1[0], c.1[1]))
        .collect();
    // Intervals (µs, as MAVLink's f32 param) of the embedded config's rates: ODOMETRY,
    // ATTITUDE_QUATERNION, HIGHRES_IMU, ESC_STATUS.
    let px4 = rt_config::Config::embedded_sim().px4;
    let us = |hz: f64| (1e6 / hz) as f32 as f64;
    let rates = [
        (331.0, us(px4.odometry_hz)),
        (31.0, us(px4.attitude_hz)),
        (105.0, us(px4.imu_hz)),
        (291.0, us(px4.esc_hz)),
    ];
    assert_eq!(got, [rates, rates].concat());

    // Handshake: >= 1.2 s of stream, DO_SET_MODE 1/6/0 resent after the ignored first one,
    // then arm, resent after its TEMPORARILY_REJECTED.
    let t_stream = f(&sps[0][0]);
    let (modes, arms) = (commands(&rec, 176), commands(&rec, 400));
    assert_eq!((modes.len(), arms.len()), (2, 2), "{modes:?} {arms:?}");
    let (d_mode, d_retry) = (modes[0].0 - t_stream, modes[1].0 - modes[0].0);
    println!("DO_SET_MODE {d_mode:.3} s into the stream, resent after {d_retry:.3} s");
    assert!(
        (1.15..1.45).contains(&d_mode),
        "DO_SET_MODE {d_mode} s into the stream"
    );
    assert!((0.28..0.40).contains(&d_retry), "resent after {d_retry} s");
    assert!(
        modes.iter().all(|m| m.1[..3] == [1.0, 6.0, 0.0]),
        "{modes:?}"
    );
    assert_eq!((modes[0].2, modes[1].2), (0, 1));
    assert!(
        arms[0].0 > modes[1].0 && arms.iter().all(|a| a.1[0] == 1.0),
        "{arms:?}"
    );
    let d_arm_retry = arms[1].0 - arms[0].0;
    assert!(
        (0.28..0.45).contains(&d_arm_retry),
        "arm resent after {d_arm_retry} s"
    );

    // VehicleState from ODOMETRY with the mode flags; IMU and motor speeds.
    let flying = vf::ARMED | vf::OFFBOARD | vf::HANDSHAKE_DONE;
    let s = o
        .states
        .iter()
        .find(|s| s.flags == flying)
        .expect("a state armed in offboard");
    let t_done = f(&rec["t_done"]);
    assert!(
        (secs(s.header.t_publish_ns) - t_done).abs() < 0.3,
        "done flags late"
    );
    assert_eq!(s.position_ned_m, [1.5, -2.0, -1.25]);
    assert_eq!(s.velocity_ned_m_s, [0.75, -0.5, 0.25]);
    let r = 0.5f64.sqrt();
    assert!(s
        .attitude_wxyz
        .iter()
        .zip([r, 0.0, 0.0, r])
        .all(|(a, b)| (a - b).abs() < 1e-6));
    assert!(s
        .rate_frd_rad_s
        .iter()
        .zip([0.1, -0.2, 0.3])
        .all(|(a, b)| (a - b).abs() < 1e-6));
    assert_eq!(s.custom_mode, 6 << 16);
    let i = o.imu.last().expect("IMU samples");
    assert!(
        (i.specific_force_frd_m_s2[2] + 9.81).abs() < 1e-5
            && (i.gyro_frd_rad_s[0] - 0.01).abs() < 1e-6
    );
    let m = o.motors.last().expect("motor speeds");
    for (k, rpm) in [6000.0, 6100.0, 6200.0, 6300.0].iter().enumerate() {
        assert!((m.rotor_speed_rad_s[k] - rpm * std::f64::consts::PI / 30.0).abs() < 1e-9);
    }

    // Garbage: setpoints keep flowing at ~100 Hz, telemetry keeps coming, drops are counted.
    let (g0, g1) = (f(&rec["t_garbage"][0]), f(&rec["t_garbage"][1]));
    let in_g: Vec<f64> = sps
        .iter()
        .map(|s| f(&s[0]))
        .filter(|t| (g0..g1).contains(t))
        .collect();
    let max_gap = in_g.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let states_in_g = o
        .states
        .iter()
        .filter(|s| (g0..g1).contains(&secs(s.header.t_publish_ns)))
        .count();
    println!(
        "garbage: {} setpoints in 2 s, max gap {max_gap:.3} s, {states_in_g} states; sent {}",
        in_g.len(),
        rec["sent_garbage"]
    );
    assert!(
        in_g.len() >= 180 && max_gap < 0.06,
        "{} setpoints, max gap {max_gap}",
        in_g.len()
    );
    assert!(
        states_in_g >= 80,
        "{states_in_g} states during the garbage (50 Hz odometry)"
    );
    let sent = |k: &str| rec["sent_garbage"][k].as_u64().unwrap();
    assert!(counter(&log, "bad_crc") >= sent("bad_crc"));
    assert!(counter(&log, "unknown_id") >= sent("unknown_id"));
    assert!(counter(&log, "truncated") >= sent("truncated") + sent("bogus_header"));
    assert!(counter(&log, "garbage_bytes") >= 7 * sent("prefixed"));

    // Link loss: LINK_LOST within link_timeout_s (1.0 s) + 0.15 s of the last heartbeat; gone
    // within 0.1 s of the first heartbeat again.
    let hb_sent: Vec<f64> = rec["heartbeats_sent"]
        .as_array()
        .unwrap()
        .iter()
        .map(f)
        .collect();
    let (quiet, again) = (f(&rec["t_no_heartbeat"]), f(&rec["t_heartbeat_again"]));
    let last = hb_sent
        .iter()
        .copied()
        .filter(|t| *t < quiet)
        .fold(0.0, f64::max);
    let first_again = hb_sent
        .iter()
        .copied()
        .find(|t| *t >= again)
        .expect("heartbeats again");
    let lost = o
        .states
        .iter()
        .find(|s| s.flags & vf::LINK_LOST != 0 && secs(s.header.t_publish_ns) > last);
    let d_lost = secs(lost.expect("LINK_LOST published").header.t_publish_ns) - last;
    let back = o
        .states
        .iter()
        .find(|s| s.flags & vf::LINK_LOST == 0 && secs(s.header.t_publish_ns) > first_again);
    let d_back = secs(back.expect("recovery published").header.t_publish_ns) - first_again;
    println!(
        "LINK_LOST {d_lost:.3} s after the last heartbeat, cleared {d_back:.3} s after the next"
    );
    assert!(
        (0.99..1.15).contains(&d_lost) && d_back < 0.1,
        "lost {d_lost} s, back {d_back} s"
    );
    assert_eq!(counter(&log, "link_losses"), 1);
    assert_eq!(counter(&log, "acks_temporarily_rejected"), 1);
    assert!(log.contains("stage=Done"), "{log}");
}

#[test]
fn handshake_gives_up_after_command_attempts() {
    let (cfg, mut bridge, mut peer, _file) = start("fail");
    let o = fly(
        &cfg,
        test_setpoint(),
        |_| peer.running(),
        Duration::from_secs(8),
    );
    let (rec, log) = stop_both(&mut bridge, &mut peer);
    let modes = commands(&rec, 176);
    println!(
        "DO_SET_MODE at {:?}",
        modes.iter().map(|m| m.0 - modes[0].0).collect::<Vec<_>>()
    );
    assert_eq!(modes.len(), cfg.px4.command_attempts as usize);
    assert!(commands(&rec, 400).is_empty(), "armed without offboard");
    assert!(
        o.states.iter().any(|s| s.flags & vf::HANDSHAKE_FAILED != 0),
        "no HANDSHAKE_FAILED state"
    );
    assert!(
        log.contains("handshake FAILED: DO_SET_MODE offboard not accepted after 5 sends (last: MAV_RESULT_TEMPORARILY_REJECTED)"),
        "{log}"
    );
}
