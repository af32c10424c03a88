//! Core tests: setpoint encoding, telemetry decoding, addressing, link loss, stream requests.

use crate::test_harness::{accept_all, Harness};
use crate::*;
use mavlink::dialects::common::{
    MavCmd, MavFrame, MavModeFlag, ESC_STATUS_DATA, HEARTBEAT_DATA, HIGHRES_IMU_DATA, ODOMETRY_DATA,
};
use rt_config::{Px4Config, VehicleConfig};
use shared_types::{vehicle_flags, AttitudeSetpoint};

#[test]
fn thrust_map_is_pxs_hover_map_and_clamps() {
    let v = VehicleConfig::default();
    let hover = v.mass_kg * v.gravity_m_s2;
    assert_eq!(
        normalized_thrust(hover, v.mass_kg, 0.6, v.gravity_m_s2),
        0.6f32
    );
    assert_eq!(
        normalized_thrust(0.5 * hover, v.mass_kg, 0.6, v.gravity_m_s2),
        0.3f32
    );
    assert_eq!(
        normalized_thrust(3.0 * hover, v.mass_kg, 0.6, v.gravity_m_s2),
        1.0
    );
    assert_eq!(normalized_thrust(-5.0, v.mass_kg, 0.6, v.gravity_m_s2), 0.0);
    assert_eq!(
        normalized_thrust(f64::NAN, v.mass_kg, 0.6, v.gravity_m_s2),
        0.0
    );
}

#[test]
fn setpoint_becomes_set_attitude_target_mask_7() {
    let mut h = Harness::new();
    let v = VehicleConfig::default();
    let s = 0.5f64.sqrt();
    let sp = AttitudeSetpoint {
        // Not normalised on purpose: 2 x (yaw 90 deg).
        attitude_wxyz: [2.0 * s, 0.0, 0.0, 2.0 * s],
        thrust_n: v.mass_kg * v.gravity_m_s2,
        ..AttitudeSetpoint::default()
    };
    h.now = 12_345_678_901;
    let Some(MavMessage::SET_ATTITUDE_TARGET(m)) = h.link.on_setpoint(h.now, &sp) else {
        panic!("no SET_ATTITUDE_TARGET");
    };
    assert_eq!(m.type_mask.bits(), 7);
    assert_eq!(m.thrust, 0.6f32);
    assert_eq!((m.target_system, m.target_component), (1, 1));
    assert_eq!(m.time_boot_ms, 12_345);
    let expect = [s as f32, 0.0, 0.0, s as f32];
    for (got, want) in m.q.iter().zip(expect) {
        assert!((got - want).abs() < 1e-7, "q {:?}", m.q);
    }
    assert_eq!(m.thrust_body, [0.0; 3]);
    let bad = AttitudeSetpoint {
        attitude_wxyz: [f64::NAN, 0.0, 0.0, 0.0],
        ..sp
    };
    assert!(h.link.on_setpoint(h.now, &bad).is_none());
    let zero_q = AttitudeSetpoint {
        attitude_wxyz: [0.0; 4],
        ..sp
    };
    assert!(h.link.on_setpoint(h.now, &zero_q).is_none());
    let c = h.link.status().counters;
    assert_eq!((c.setpoints_sent, c.setpoints_dropped), (1, 2));
}

fn odometry() -> ODOMETRY_DATA {
    ODOMETRY_DATA {
        time_usec: 4_200_000,
        x: 1.5,
        y: -2.0,
        z: -1.25,
        // 90 deg yaw: body x points east.
        q: [0.5f32.sqrt(), 0.0, 0.0, 0.5f32.sqrt()],
        vx: 0.75,
        vy: -0.5,
        vz: 0.25,
        rollspeed: 0.1,
        pitchspeed: -0.2,
        yawspeed: 0.3,
        frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        child_frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        ..ODOMETRY_DATA::default()
    }
}

#[test]
fn odometry_becomes_vehicle_state_with_heartbeat_flags() {
    let mut h = Harness::new();
    h.px4_armed = true;
    h.px4_mode = 6 << 16;
    h.heartbeat();
    h.now += 5_000_000;
    let Some(Telemetry::State(s)) = h.px4_sends(MavMessage::ODOMETRY(odometry())) else {
        panic!("no state");
    };
    assert_eq!(s.header.t_origin_ns, h.now);
    assert_eq!(s.px4_time_us, 4_200_000);
    assert_eq!(s.position_ned_m, [1.5, -2.0, -1.25]);
    assert_eq!(s.velocity_ned_m_s, [0.75, -0.5, 0.25]);
    let r = 0.5f64.sqrt();
    for (got, want) in s.attitude_wxyz.iter().zip([r, 0.0, 0.0, r]) {
        assert!((got - want).abs() < 1e-7, "{:?}", s.attitude_wxyz);
    }
    for (got, want) in s.rate_frd_rad_s.iter().zip([0.1, -0.2, 0.3]) {
        assert!((got - want).abs() < 1e-7);
    }
    assert_eq!(s.custom_mode, 6 << 16);
    assert_eq!(s.flags, vehicle_flags::ARMED | vehicle_flags::OFFBOARD);

    // Velocity in body FRD (child_frame_id BODY_FRD) is rotated into NED: forward = east.
    let body = ODOMETRY_DATA {
        vx: 1.0,
        vy: 0.0,
        vz: 0.0,
        child_frame_id: MavFrame::MAV_FRAME_BODY_FRD,
        ..odometry()
    };
    let Some(Telemetry::State(s)) = h.px4_sends(MavMessage::ODOMETRY(body)) else {
        panic!("no state");
    };
    let v = s.velocity_ned_m_s;
    assert!(
        v[0].abs() < 1e-6 && (v[1] - 1.0).abs() < 1e-6 && v[2].abs() < 1e-6,
        "{v:?}"
    );

    // NaN position (EKF2 without a position) and other frames are refused.
    let nan = ODOMETRY_DATA {
        x: f32::NAN,
        ..odometry()
    };
    assert!(h.px4_sends(MavMessage::ODOMETRY(nan)).is_none());
    let frd = ODOMETRY_DATA {
        frame_id: MavFrame::MAV_FRAME_LOCAL_FRD,
        ..odometry()
    };
    assert!(h.px4_sends(MavMessage::ODOMETRY(frd)).is_none());
    assert_eq!(h.link.status().counters.telemetry_refused, 2);
}

#[test]
fn imu_and_esc_status_become_samples() {
    let mut h = Harness::new();
    let imu = HIGHRES_IMU_DATA {
        time_usec: 77,
        xacc: 0.1,
        yacc: -0.2,
        zacc: -9.81,
        xgyro: 0.01,
        ygyro: 0.02,
        zgyro: -0.03,
        ..HIGHRES_IMU_DATA::default()
    };
    let Some(Telemetry::Imu(s)) = h.px4_sends(MavMessage::HIGHRES_IMU(imu)) else {
        panic!("no imu");
    };
    assert_eq!(s.px4_time_us, 77);
    assert!((s.specific_force_frd_m_s2[2] + 9.81).abs() < 1e-6);
    assert!((s.gyro_frd_rad_s[2] + 0.03).abs() < 1e-8);
    let esc = ESC_STATUS_DATA {
        time_usec: 88,
        rpm: [6000, 7000, -60, 0],
        ..ESC_STATUS_DATA::default()
    };
    let Some(Telemetry::Motors(m)) = h.px4_sends(MavMessage::ESC_STATUS(esc)) else {
        panic!("no motors");
    };
    // rpm * 2 pi / 60: 628.3185, 733.0383, -6.2832, 0 rad/s.
    let want = [6000.0, 7000.0, -60.0, 0.0].map(|rpm: f64| rpm * std::f64::consts::PI / 30.0);
    assert!((m.rotor_speed_rad_s[0] - 628.318_530_7).abs() < 1e-6);
    for (got, want) in m.rotor_speed_rad_s.iter().zip(want) {
        assert!((got - want).abs() < 1e-12, "{:?}", m.rotor_speed_rad_s);
    }
}

#[test]
fn messages_from_other_systems_and_components_are_ignored() {
    let mut h = Harness::new();
    let armed = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 6 << 16,
        base_mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
        ..HEARTBEAT_DATA::default()
    });
    for (system_id, component_id) in [(2, 1), (1, 191), (255, 190)] {
        let other = MavHeader {
            system_id,
            component_id,
            sequence: 0,
        };
        assert!(h.link.on_message(h.now, &other, &armed).is_none());
        let odo = MavMessage::ODOMETRY(odometry());
        assert!(h.link.on_message(h.now, &other, &odo).is_none());
    }
    let s = h.link.status();
    assert_eq!(s.counters.foreign_messages, 6);
    assert_eq!(s.counters.heartbeats_received, 0);
    assert!(!s.link_up);
    assert_eq!(s.flags, vehicle_flags::LINK_LOST);
}

#[test]
fn link_loss_after_timeout_and_recovery_with_new_stream_requests() {
    let mut h = Harness::new(); // link_timeout_s 1.5
    h.heartbeat();
    h.px4_sends(MavMessage::ODOMETRY(odometry()));
    assert_eq!(h.link.flags_update(h.now), None);
    h.poll();
    assert_eq!(h.commands(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL).len(), 1);
    let t_hb = h.now;
    h.now = t_hb + 1_500_000_000;
    assert_eq!(
        h.link.flags_update(h.now),
        None,
        "still up at exactly 1.5 s"
    );
    h.now = t_hb + 1_510_000_000;
    let s = h.link.flags_update(h.now).expect("LINK_LOST published");
    assert_eq!(s.flags, vehicle_flags::LINK_LOST);
    assert_eq!(
        s.position_ned_m,
        [1.5, -2.0, -1.25],
        "the last state, re-flagged"
    );
    assert_eq!(h.link.flags_update(h.now), None, "published once");
    assert_eq!(h.link.status().counters.link_losses, 1);
    h.heartbeat();
    let s = h.link.flags_update(h.now).expect("recovery published");
    assert_eq!(s.flags, 0);
    // Intervals asked again from the first stream (PX4 may have rebooted).
    h.poll();
    let requests = h.commands(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL);
    assert_eq!(requests.len(), 2);
    assert_eq!(requests[1].1.param1, 331.0);
}

#[test]
fn stream_rates_requested_one_by_one_with_acks() {
    let mut h = Harness::new();
    h.run(1.0, false, true, &mut accept_all);
    let r = h.commands(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL);
    let got: Vec<(f32, f32)> = r.iter().map(|(_, c)| (c.param1, c.param2)).collect();
    // 100 Hz odometry and attitude, 250 Hz IMU, 50 Hz ESC (defaults), intervals in µs.
    assert_eq!(
        got,
        [
            (331.0, 10_000.0),
            (31.0, 10_000.0),
            (105.0, 4_000.0),
            (291.0, 20_000.0)
        ]
    );
    assert_eq!(h.link.status().counters.intervals_accepted, 4);
    assert!(r
        .iter()
        .all(|(_, c)| c.target_system == 1 && c.target_component == 1));
}

#[test]
fn heartbeat_at_configured_rate() {
    let mut h = Harness::with(Px4Config {
        heartbeat_hz: 2.0,
        ..Px4Config::default()
    });
    h.run(10.0, false, false, &mut accept_all);
    let beats: Vec<u64> = h
        .sent
        .iter()
        .filter(|(_, m)| matches!(m, MavMessage::HEARTBEAT(_)))
        .map(|(t, _)| *t)
        .collect();
    assert_eq!(beats.len(), 20, "2 Hz over 10 s");
    for w in beats.windows(2) {
        assert_eq!(w[1] - w[0], 500_000_000);
    }
    let MavMessage::HEARTBEAT(hb) = &h.sent[0].1 else {
        panic!()
    };
    assert_eq!(
        hb.mavtype,
        mavlink::dialects::common::MavType::MAV_TYPE_ONBOARD_CONTROLLER
    );
}

#[test]
fn config_errors_name_the_key() {
    let bad = Px4Config {
        command_attempts: 0,
        ..Px4Config::default()
    };
    let e = OffboardLink::new(&bad, &VehicleConfig::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("px4.command_attempts"), "{e}");
    let heavy = VehicleConfig {
        hover_throttle: 1.5,
        ..VehicleConfig::default()
    };
    let e = OffboardLink::new(&Px4Config::default(), &heavy)
        .err()
        .unwrap();
    assert!(e.to_string().contains("vehicle.hover_throttle"), "{e}");
}
