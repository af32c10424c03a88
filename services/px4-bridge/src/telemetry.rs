//! PX4 telemetry messages -> samples. Frames: ODOMETRY pose in MAV_FRAME_LOCAL_NED, q body FRD
//! -> NED (w, x, y, z), rates body FRD; the velocity frame is `child_frame_id` (PX4 v1.14+
//! sends MAV_FRAME_LOCAL_NED; MAV_FRAME_BODY_FRD is rotated into NED). A sample with a
//! non-finite or unusable field is refused whole (PX4 sends NaN for what EKF2 does not know).

use mavlink::dialects::common::{MavFrame, ESC_STATUS_DATA, HIGHRES_IMU_DATA, ODOMETRY_DATA};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use shared_types::{Header, ImuSample, MotorSpeeds, VehicleState};

/// Why a telemetry message was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Refused {
    NonFinite,
    /// Quaternion norm far from 1 (not an attitude).
    BadQuaternion,
    /// Pose or velocity in a frame we do not handle.
    UnsupportedFrame,
    /// ESC_STATUS for motors 5..8 and beyond (a quadrotor has four).
    OtherEscs,
}

fn header(now_ns: u64) -> Header {
    Header {
        t_origin_ns: now_ns,
        ..Header::default()
    }
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

fn f64x3(v: [f32; 3]) -> [f64; 3] {
    v.map(f64::from)
}

/// ODOMETRY -> VehicleState without the HEARTBEAT-derived fields (custom_mode, flags).
pub(crate) fn vehicle_state(now_ns: u64, o: &ODOMETRY_DATA) -> Result<VehicleState, Refused> {
    let p = [o.x, o.y, o.z];
    let v = [o.vx, o.vy, o.vz];
    let w = [o.rollspeed, o.pitchspeed, o.yawspeed];
    if !(finite(&p) && finite(&v) && finite(&w) && finite(&o.q)) {
        return Err(Refused::NonFinite);
    }
    if o.frame_id != MavFrame::MAV_FRAME_LOCAL_NED {
        return Err(Refused::UnsupportedFrame);
    }
    let q = Quaternion::new(
        f64::from(o.q[0]),
        f64::from(o.q[1]),
        f64::from(o.q[2]),
        f64::from(o.q[3]),
    );
    let norm = q.norm();
    if !(0.9..=1.1).contains(&norm) {
        return Err(Refused::BadQuaternion);
    }
    let q = UnitQuaternion::from_quaternion(q);
    let velocity_ned = match o.child_frame_id {
        MavFrame::MAV_FRAME_LOCAL_NED => f64x3(v),
        MavFrame::MAV_FRAME_BODY_FRD => {
            let v_ned = q * Vector3::from(f64x3(v));
            [v_ned.x, v_ned.y, v_ned.z]
        }
        _ => return Err(Refused::UnsupportedFrame),
    };
    Ok(VehicleState {
        header: header(now_ns),
        px4_time_us: o.time_usec,
        position_ned_m: f64x3(p),
        velocity_ned_m_s: velocity_ned,
        attitude_wxyz: [q.w, q.i, q.j, q.k],
        rate_frd_rad_s: f64x3(w),
        custom_mode: 0,
        flags: 0,
    })
}

pub(crate) fn imu_sample(now_ns: u64, m: &HIGHRES_IMU_DATA) -> Result<ImuSample, Refused> {
    let a = [m.xacc, m.yacc, m.zacc];
    let g = [m.xgyro, m.ygyro, m.zgyro];
    if !(finite(&a) && finite(&g)) {
        return Err(Refused::NonFinite);
    }
    Ok(ImuSample {
        header: header(now_ns),
        px4_time_us: m.time_usec,
        specific_force_frd_m_s2: f64x3(a),
        gyro_frd_rad_s: f64x3(g),
    })
}

/// rpm -> rad/s.
pub(crate) fn rad_s_from_rpm(rpm: i32) -> f64 {
    f64::from(rpm) * 2.0 * std::f64::consts::PI / 60.0
}

pub(crate) fn motor_speeds(now_ns: u64, m: &ESC_STATUS_DATA) -> Result<MotorSpeeds, Refused> {
    if m.index != 0 {
        return Err(Refused::OtherEscs);
    }
    Ok(MotorSpeeds {
        header: header(now_ns),
        px4_time_us: m.time_usec,
        rotor_speed_rad_s: m.rpm.map(rad_s_from_rpm),
    })
}
