//! The vehicle snapshot the streams are built from.

use nalgebra::{UnitQuaternion, Vector3};

/// HEARTBEAT base_mode bit: custom mode is valid (PX4 always sets it).
pub const MAV_MODE_FLAG_CUSTOM_MODE_ENABLED: u8 = 1;
/// HEARTBEAT base_mode bit: motors armed.
pub const MAV_MODE_FLAG_SAFETY_ARMED: u8 = 128;
/// PX4 main mode "position" (custom_mode = 3 << 16).
pub const PX4_MAIN_MODE_POSCTL: u8 = 3;
/// PX4 main mode "offboard" (custom_mode = 6 << 16).
pub const PX4_MAIN_MODE_OFFBOARD: u8 = 6;

/// PX4's HEARTBEAT custom_mode: `main_mode << 16 | sub_mode << 24` (px4_custom_mode union).
pub fn px4_custom_mode(main_mode: u8, sub_mode: u8) -> u32 {
    (u32::from(main_mode) << 16) | (u32::from(sub_mode) << 24)
}

/// One snapshot of what PX4 would publish, in the plant's f64 SI conventions.
///
/// Times are the vehicle's time since boot (PX4's hrt). The same snapshot feeds every stream
/// sent in one `send_due` call, as PX4 streams read the latest uORB sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Telemetry {
    /// Sample time since boot, ns (message timestamps: time_boot_ms / time_usec).
    pub time_boot_ns: u64,
    /// HEARTBEAT base_mode (MAV_MODE_FLAG bits; 128 = armed, 1 = custom mode enabled).
    pub base_mode: u8,
    /// HEARTBEAT custom_mode (PX4: see [`px4_custom_mode`]; offboard = 6 << 16).
    pub custom_mode: u32,
    /// HEARTBEAT system_status (MAV_STATE: 3 standby, 4 active, 5 critical, ...).
    pub system_status: u8,
    /// Estimated position, NED, m.
    pub position_ned_m: Vector3<f64>,
    /// Estimated velocity, NED, m/s.
    pub velocity_ned_m_s: Vector3<f64>,
    /// Estimated attitude, rotates body FRD -> NED.
    pub attitude_body_to_ned: UnitQuaternion<f64>,
    /// Angular velocity (bias-corrected), body FRD, rad/s.
    pub body_rates_frd_rad_s: Vector3<f64>,
    /// Accelerometer specific force, body FRD, m/s^2 (about (0, 0, -9.81) in hover).
    pub specific_force_frd_m_s2: Vector3<f64>,
    /// Raw gyro, body FRD, rad/s.
    pub gyro_frd_rad_s: Vector3<f64>,
    /// Rotor speeds in motor order, rad/s (ESC_STATUS rpm = rad/s * 60 / 2 pi).
    pub rotor_speeds_rad_s: [f64; 4],
    /// Position variance, NED axes, m^2; NaN when unknown (ODOMETRY pose_covariance diagonal).
    pub position_variance_ned_m2: [f64; 3],
    /// Velocity variance, NED axes, m^2/s^2; NaN when unknown.
    pub velocity_variance_ned_m2_s2: [f64; 3],
    /// Roll/pitch/yaw variance, rad^2; NaN when unknown.
    pub attitude_variance_rad2: [f64; 3],
    /// Estimator reset counter (ODOMETRY reset_counter).
    pub reset_counter: u8,
}

impl Default for Telemetry {
    /// Disarmed in position mode, standing level at the origin, rotors stopped, variances unknown.
    fn default() -> Self {
        Telemetry {
            time_boot_ns: 0,
            base_mode: MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
            custom_mode: px4_custom_mode(PX4_MAIN_MODE_POSCTL, 0),
            system_status: 3,
            position_ned_m: Vector3::zeros(),
            velocity_ned_m_s: Vector3::zeros(),
            attitude_body_to_ned: UnitQuaternion::identity(),
            body_rates_frd_rad_s: Vector3::zeros(),
            specific_force_frd_m_s2: Vector3::new(0.0, 0.0, -9.81),
            gyro_frd_rad_s: Vector3::zeros(),
            rotor_speeds_rad_s: [0.0; 4],
            position_variance_ned_m2: [f64::NAN; 3],
            velocity_variance_ned_m2_s2: [f64::NAN; 3],
            attitude_variance_rad2: [f64::NAN; 3],
            reset_counter: 0,
        }
    }
}

impl Telemetry {
    /// True when every state value is finite (variances may be NaN: that means "unknown").
    pub fn is_finite(&self) -> bool {
        let q = self.attitude_body_to_ned.quaternion();
        self.position_ned_m.iter().all(|v| v.is_finite())
            && self.velocity_ned_m_s.iter().all(|v| v.is_finite())
            && q.coords.iter().all(|v| v.is_finite())
            && self.body_rates_frd_rad_s.iter().all(|v| v.is_finite())
            && self.specific_force_frd_m_s2.iter().all(|v| v.is_finite())
            && self.gyro_frd_rad_s.iter().all(|v| v.is_finite())
            && self.rotor_speeds_rad_s.iter().all(|v| v.is_finite())
    }

    /// Time since boot in ms, wrapping like PX4's `timestamp / 1000` cast to u32.
    pub fn time_boot_ms(&self) -> u32 {
        (self.time_boot_ns / 1_000_000) as u32
    }

    /// Time since boot in us.
    pub fn time_boot_us(&self) -> u64 {
        self.time_boot_ns / 1_000
    }
}
