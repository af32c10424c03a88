//! Each outbound message serialised by the endpoint's writer and read back by the crate's own
//! reader (`MavlinkReader`), fields checked against the snapshot.

use super::*;
use crate::mavlink_link::codec::FrameWriter;
use crate::mavlink_link::telemetry::px4_custom_mode;
use mavlink::{MavHeader, MavlinkReader, MavlinkVersion};
use nalgebra::{UnitQuaternion, Vector3};

fn snapshot() -> Telemetry {
    Telemetry {
        time_boot_ns: 12_345_678_901,
        base_mode: 129,
        custom_mode: px4_custom_mode(6, 0),
        system_status: 4,
        position_ned_m: Vector3::new(0.3, -1.2, -1.5),
        velocity_ned_m_s: Vector3::new(0.4, 0.1, -0.2),
        attitude_body_to_ned: UnitQuaternion::from_euler_angles(0.1, -0.05, 0.7),
        body_rates_frd_rad_s: Vector3::new(0.01, -0.02, 0.3),
        specific_force_frd_m_s2: Vector3::new(0.2, -0.1, -9.9),
        gyro_frd_rad_s: Vector3::new(0.011, -0.019, 0.301),
        rotor_speeds_rad_s: [760.0, 770.0, 780.0, 790.0],
        position_variance_ned_m2: [1e-4, 2e-4, 3e-4],
        velocity_variance_ned_m2_s2: [4e-4, 5e-4, 6e-4],
        attitude_variance_rad2: [f64::NAN; 3],
        reset_counter: 2,
    }
}

/// Serialises and parses back through the crate's reader.
fn round_trip(stream: Stream, t: &Telemetry) -> (MavHeader, MavMessage) {
    let mut writer = FrameWriter::new(7, 1);
    let bytes = writer.encode(&stream_message(stream, t)).to_vec();
    let mut reader = MavlinkReader::new(&bytes[..]);
    let (header, msg) = reader
        .read_message::<MavMessage>(MavlinkVersion::V2)
        .expect("crate parses our frame");
    assert_eq!((header.system_id, header.component_id), (7, 1));
    (header, msg)
}

fn close(a: f32, b: f64) -> bool {
    (f64::from(a) - b).abs() <= 1e-6 * b.abs().max(1.0)
}

#[test]
fn heartbeat_round_trip() {
    let t = snapshot();
    let MavMessage::HEARTBEAT(h) = round_trip(Stream::Heartbeat, &t).1 else {
        panic!("not a heartbeat")
    };
    assert_eq!(h.mavtype, MavType::MAV_TYPE_QUADROTOR);
    assert_eq!(h.autopilot, MavAutopilot::MAV_AUTOPILOT_PX4);
    assert_eq!(h.base_mode.bits(), 129);
    assert_eq!(h.custom_mode, 6 << 16);
    assert_eq!(h.system_status, MavState::MAV_STATE_ACTIVE);
    assert_eq!(h.mavlink_version, 3);
}

#[test]
fn attitude_quaternion_round_trip() {
    let t = snapshot();
    let MavMessage::ATTITUDE_QUATERNION(a) = round_trip(Stream::AttitudeQuaternion, &t).1 else {
        panic!("wrong message")
    };
    let q = t.attitude_body_to_ned.quaternion();
    assert_eq!(a.time_boot_ms, 12_345);
    assert!(close(a.q1, q.w) && close(a.q2, q.i) && close(a.q3, q.j) && close(a.q4, q.k));
    assert!(close(a.rollspeed, 0.01) && close(a.pitchspeed, -0.02) && close(a.yawspeed, 0.3));
    assert_eq!(a.repr_offset_q, [0.0; 4]);
}

#[test]
fn highres_imu_round_trip() {
    let t = snapshot();
    let MavMessage::HIGHRES_IMU(m) = round_trip(Stream::HighresImu, &t).1 else {
        panic!("wrong message")
    };
    assert_eq!(m.time_usec, 12_345_678);
    assert!(close(m.xacc, 0.2) && close(m.yacc, -0.1) && close(m.zacc, -9.9));
    assert!(close(m.xgyro, 0.011) && close(m.ygyro, -0.019) && close(m.zgyro, 0.301));
    assert_eq!(m.fields_updated.bits(), 0x3F);
}

#[test]
fn local_position_ned_round_trip() {
    let t = snapshot();
    let MavMessage::LOCAL_POSITION_NED(m) = round_trip(Stream::LocalPositionNed, &t).1 else {
        panic!("wrong message")
    };
    assert_eq!(m.time_boot_ms, 12_345);
    assert!(close(m.x, 0.3) && close(m.y, -1.2) && close(m.z, -1.5));
    assert!(close(m.vx, 0.4) && close(m.vy, 0.1) && close(m.vz, -0.2));
}

#[test]
fn odometry_round_trip_mirrors_px4_frames_and_covariances() {
    let t = snapshot();
    let MavMessage::ODOMETRY(m) = round_trip(Stream::Odometry, &t).1 else {
        panic!("wrong message")
    };
    assert_eq!(m.time_usec, 12_345_678);
    assert_eq!(m.frame_id, MavFrame::MAV_FRAME_LOCAL_NED);
    assert_eq!(m.child_frame_id, MavFrame::MAV_FRAME_LOCAL_NED);
    assert_eq!(
        m.estimator_type,
        MavEstimatorType::MAV_ESTIMATOR_TYPE_AUTOPILOT
    );
    assert_eq!(m.reset_counter, 2);
    assert!(close(m.x, 0.3) && close(m.y, -1.2) && close(m.z, -1.5));
    // Velocity stays in NED, as PX4 sends EKF2's odometry (velocity_frame NED).
    assert!(close(m.vx, 0.4) && close(m.vy, 0.1) && close(m.vz, -0.2));
    assert!(close(m.rollspeed, 0.01) && close(m.yawspeed, 0.3));
    let q = t.attitude_body_to_ned.quaternion();
    assert!(close(m.q[0], q.w) && close(m.q[3], q.k));
    for (k, c) in m.pose_covariance.iter().enumerate() {
        match k {
            0 => assert!(close(*c, 1e-4)),
            6 => assert!(close(*c, 2e-4)),
            11 => assert!(close(*c, 3e-4)),
            _ => assert!(c.is_nan(), "pose_covariance[{k}] = {c}, expected NaN"),
        }
    }
    for (k, c) in m.velocity_covariance.iter().enumerate() {
        match k {
            0 => assert!(close(*c, 4e-4)),
            6 => assert!(close(*c, 5e-4)),
            11 => assert!(close(*c, 6e-4)),
            _ => assert!(c.is_nan(), "velocity_covariance[{k}] = {c}, expected NaN"),
        }
    }
}

#[test]
fn esc_status_round_trip_converts_rad_s_to_rpm() {
    let t = snapshot();
    let MavMessage::ESC_STATUS(m) = round_trip(Stream::EscStatus, &t).1 else {
        panic!("wrong message")
    };
    // 760 rad/s * 60 / 2 pi = 7257.46 rpm, ...
    assert_eq!(m.rpm, [7257, 7353, 7448, 7544]);
    assert_eq!(m.index, 0);
    assert_eq!(m.time_usec, 12_345_678);
    assert_eq!(rpm_from_rad_s(-104.72), -1000);
}

#[test]
fn autopilot_version_claims_mavlink2_and_attitude_target() {
    let mut writer = FrameWriter::new(2, 1);
    let bytes = writer.encode(&autopilot_version(2)).to_vec();
    let (_, msg) = MavlinkReader::new(&bytes[..])
        .read_message::<MavMessage>(MavlinkVersion::V2)
        .unwrap();
    let MavMessage::AUTOPILOT_VERSION(v) = msg else {
        panic!("wrong message")
    };
    assert_eq!(v.flight_sw_version >> 16, (1 << 8) | 16, "version 1.16");
    assert_eq!(v.capabilities.bits(), 8192 | 64);
}

#[test]
fn unknown_system_status_reads_as_uninit() {
    let t = Telemetry {
        system_status: 200,
        ..snapshot()
    };
    let MavMessage::HEARTBEAT(h) = heartbeat(&t) else {
        panic!()
    };
    assert_eq!(h.system_status, MavState::MAV_STATE_UNINIT);
}
