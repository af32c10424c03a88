//! Outbound messages built from a [`Telemetry`] snapshot the way PX4 v1.16's streams fill them.

use std::f64::consts::PI;

use mavlink::dialects::common::{
    HighresImuUpdatedFlags, MavAutopilot, MavEstimatorType, MavFrame, MavMessage, MavModeFlag,
    MavProtocolCapability, MavState, MavType, ATTITUDE_QUATERNION_DATA, AUTOPILOT_VERSION_DATA,
    ESC_STATUS_DATA, HEARTBEAT_DATA, HIGHRES_IMU_DATA, LOCAL_POSITION_NED_DATA, ODOMETRY_DATA,
};

use super::config::Stream;
use super::telemetry::Telemetry;

/// HEARTBEAT mavlink_version field (MAVLink 2 = 3).
const MAVLINK_VERSION: u8 = 3;
/// PX4 v1.16.0 release in AUTOPILOT_VERSION encoding (major, minor, patch, type 255 = release).
pub const PX4_FLIGHT_SW_VERSION: u32 = (1 << 24) | (16 << 16) | 255;

/// MAV_STATE for a raw value; values past the enum read as UNINIT.
fn mav_state(raw: u8) -> MavState {
    match raw {
        1 => MavState::MAV_STATE_BOOT,
        2 => MavState::MAV_STATE_CALIBRATING,
        3 => MavState::MAV_STATE_STANDBY,
        4 => MavState::MAV_STATE_ACTIVE,
        5 => MavState::MAV_STATE_CRITICAL,
        6 => MavState::MAV_STATE_EMERGENCY,
        7 => MavState::MAV_STATE_POWEROFF,
        8 => MavState::MAV_STATE_FLIGHT_TERMINATION,
        _ => MavState::MAV_STATE_UNINIT,
    }
}

fn f32x3(v: &nalgebra::Vector3<f64>) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// Quaternion (w, x, y, z) body FRD -> NED, as PX4's vehicle_attitude.q.
fn quaternion_wxyz(t: &Telemetry) -> [f32; 4] {
    let q = t.attitude_body_to_ned.quaternion();
    [q.w as f32, q.i as f32, q.j as f32, q.k as f32]
}

/// HEARTBEAT: quadrotor, PX4 autopilot, mode/state from the snapshot.
pub fn heartbeat(t: &Telemetry) -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: t.custom_mode,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        base_mode: MavModeFlag::from_bits_retain(t.base_mode),
        system_status: mav_state(t.system_status),
        mavlink_version: MAVLINK_VERSION,
    })
}

/// ATTITUDE_QUATERNION: q body -> NED, body rates FRD; repr_offset_q zeros as PX4 sends it.
pub fn attitude_quaternion(t: &Telemetry) -> MavMessage {
    let q = quaternion_wxyz(t);
    let w = f32x3(&t.body_rates_frd_rad_s);
    MavMessage::ATTITUDE_QUATERNION(ATTITUDE_QUATERNION_DATA {
        time_boot_ms: t.time_boot_ms(),
        q1: q[0],
        q2: q[1],
        q3: q[2],
        q4: q[3],
        rollspeed: w[0],
        pitchspeed: w[1],
        yawspeed: w[2],
        repr_offset_q: [0.0; 4],
    })
}

/// HIGHRES_IMU: specific force and gyro in body FRD; only accel and gyro marked updated
/// (the plant has no magnetometer or barometer, so those fields stay 0).
pub fn highres_imu(t: &Telemetry) -> MavMessage {
    let a = f32x3(&t.specific_force_frd_m_s2);
    let g = f32x3(&t.gyro_frd_rad_s);
    MavMessage::HIGHRES_IMU(HIGHRES_IMU_DATA {
        time_usec: t.time_boot_us(),
        xacc: a[0],
        yacc: a[1],
        zacc: a[2],
        xgyro: g[0],
        ygyro: g[1],
        zgyro: g[2],
        xmag: 0.0,
        ymag: 0.0,
        zmag: 0.0,
        abs_pressure: 0.0,
        diff_pressure: 0.0,
        pressure_alt: 0.0,
        temperature: 0.0,
        fields_updated: HighresImuUpdatedFlags::from_bits_retain(0x3F),
        id: 0,
    })
}

/// LOCAL_POSITION_NED: position and velocity, NED.
pub fn local_position_ned(t: &Telemetry) -> MavMessage {
    let p = f32x3(&t.position_ned_m);
    let v = f32x3(&t.velocity_ned_m_s);
    MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
        time_boot_ms: t.time_boot_ms(),
        x: p[0],
        y: p[1],
        z: p[2],
        vx: v[0],
        vy: v[1],
        vz: v[2],
    })
}

/// ODOMETRY as PX4 v1.14+ sends EKF2's vehicle_odometry: pose in MAV_FRAME_LOCAL_NED, velocity
/// frame = vehicle_odometry.velocity_frame = NED, hence child_frame_id MAV_FRAME_LOCAL_NED and
/// velocity in NED; body rates FRD; covariance diagonals from the variances, NaN elsewhere;
/// estimator_type AUTOPILOT; quality 0 (EKF2 leaves it unset).
pub fn odometry(t: &Telemetry) -> MavMessage {
    let p = f32x3(&t.position_ned_m);
    let v = f32x3(&t.velocity_ned_m_s);
    let w = f32x3(&t.body_rates_frd_rad_s);
    let mut pose_covariance = [f32::NAN; 21];
    let mut velocity_covariance = [f32::NAN; 21];
    for (k, &diag) in [0usize, 6, 11].iter().enumerate() {
        pose_covariance[diag] = t.position_variance_ned_m2[k] as f32;
        velocity_covariance[diag] = t.velocity_variance_ned_m2_s2[k] as f32;
    }
    for (k, &diag) in [15usize, 18, 20].iter().enumerate() {
        pose_covariance[diag] = t.attitude_variance_rad2[k] as f32;
    }
    MavMessage::ODOMETRY(ODOMETRY_DATA {
        time_usec: t.time_boot_us(),
        x: p[0],
        y: p[1],
        z: p[2],
        q: quaternion_wxyz(t),
        vx: v[0],
        vy: v[1],
        vz: v[2],
        rollspeed: w[0],
        pitchspeed: w[1],
        yawspeed: w[2],
        pose_covariance,
        velocity_covariance,
        frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        child_frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
        reset_counter: t.reset_counter,
        estimator_type: MavEstimatorType::MAV_ESTIMATOR_TYPE_AUTOPILOT,
        quality: 0,
    })
}

/// ESC rpm for a rotor speed in rad/s, rounded, saturated to i32.
pub fn rpm_from_rad_s(omega_rad_s: f64) -> i32 {
    (omega_rad_s * 60.0 / (2.0 * PI)).round() as i32
}

/// ESC_STATUS: rpm of motors 1..4 (index 0); voltage and current 0 (not modelled).
pub fn esc_status(t: &Telemetry) -> MavMessage {
    MavMessage::ESC_STATUS(ESC_STATUS_DATA {
        time_usec: t.time_boot_us(),
        rpm: t.rotor_speeds_rad_s.map(rpm_from_rad_s),
        voltage: [0.0; 4],
        current: [0.0; 4],
        index: 0,
    })
}

/// The message of `stream` for snapshot `t`.
pub fn stream_message(stream: Stream, t: &Telemetry) -> MavMessage {
    match stream {
        Stream::Heartbeat => heartbeat(t),
        Stream::AttitudeQuaternion => attitude_quaternion(t),
        Stream::HighresImu => highres_imu(t),
        Stream::LocalPositionNed => local_position_ned(t),
        Stream::Odometry => odometry(t),
        Stream::EscStatus => esc_status(t),
    }
}

/// AUTOPILOT_VERSION (answer to MAV_CMD_REQUEST_MESSAGE 148 and
/// MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES): MAVLink 2, SET_ATTITUDE_TARGET, COMMAND_INT is not
/// claimed because the endpoint handles COMMAND_LONG only.
pub fn autopilot_version(system_id: u8) -> MavMessage {
    let capabilities = MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MAVLINK2
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_SET_ATTITUDE_TARGET;
    MavMessage::AUTOPILOT_VERSION(AUTOPILOT_VERSION_DATA {
        capabilities,
        uid: 0x7461_7574_0000_0000 | u64::from(system_id),
        flight_sw_version: PX4_FLIGHT_SW_VERSION,
        middleware_sw_version: PX4_FLIGHT_SW_VERSION,
        os_sw_version: 0,
        board_version: 0,
        vendor_id: 0,
        product_id: 0,
        flight_custom_version: [0; 8],
        middleware_custom_version: [0; 8],
        os_custom_version: [0; 8],
        uid2: [0; 18],
    })
}

#[cfg(test)]
#[path = "outbound_tests.rs"]
mod tests;
