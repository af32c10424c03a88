//! Paper IV.C: desired acceleration and yaw -> attitude quaternion and collective thrust.
//!
//! F_d = m a_d − P with P = m g e3 (NED, gravity +z), so hover asks F_d = (0, 0, −m g).
//! Vertical priority: F_d,z is kept (at least `min_thrust_n` upwards) and the horizontal part is
//! scaled down until the tilt of F_d from up (−e3) is at most `max_tilt`. The thrust is
//! u = −F_d,z / (cos φ cos θ) with the vehicle's CURRENT roll and pitch (the paper's "corrected
//! by the vehicle tilt"; cos φ cos θ = R_33), the cosine floored at [`MIN_TILT_COSINE`] so a
//! vehicle knocked over does not ask for unbounded thrust, then clamped to the thrust limits.
//! Body z (FRD, pointing down) is z_d = −F_d/|F_d| (+e3 in hover), y_d = z_d × χ / |·| with
//! χ = (cos ψ_d, sin ψ_d, 0), x_d = y_d × z_d, R_d = [x_d y_d z_d] (columns, body FRD -> NED).

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// Floor of cos φ cos θ in the thrust correction (60° of combined tilt).
pub const MIN_TILT_COSINE: f64 = 0.5;

/// What the mapping needs besides the acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MappingParams {
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
    pub max_tilt_rad: f64,
    pub min_thrust_n: f64,
    pub max_thrust_n: f64,
}

/// Which thrust limit, if any, the command hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThrustLimit {
    None,
    /// More thrust was asked than `max_thrust_n` (or a downward force below `min_thrust_n`).
    Max,
    Min,
}

/// The attitude-and-thrust command.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mapped {
    /// Desired attitude, body FRD -> NED.
    pub attitude: UnitQuaternion<f64>,
    /// Collective thrust, N.
    pub thrust_n: f64,
    /// The force after the limits, NED, N.
    pub force_ned_n: Vector3<f64>,
    pub tilt_limited: bool,
    pub thrust_limit: ThrustLimit,
}

/// Level attitude (body FRD -> NED) at `yaw_rad`.
pub fn level(yaw_rad: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw_rad)
}

/// Yaw of an attitude (ZYX Euler), rad.
pub fn yaw_of(q: &UnitQuaternion<f64>) -> f64 {
    let r = q.to_rotation_matrix();
    r[(1, 0)].atan2(r[(0, 0)])
}

/// Maps the desired acceleration `accel_ned` (m/s²) and yaw to attitude and thrust, with the
/// thrust corrected by the current attitude `current`.
pub fn map_acceleration(
    accel_ned: &Vector3<f64>,
    yaw_rad: f64,
    current: &UnitQuaternion<f64>,
    p: &MappingParams,
) -> Mapped {
    let mut f = accel_ned * p.mass_kg - Vector3::new(0.0, 0.0, p.mass_kg * p.gravity_m_s2);
    let mut thrust_limit = ThrustLimit::None;
    if f.z > -p.min_thrust_n {
        // Down (or no) force asked: the rotors cannot push down; keep the minimum up.
        f.z = -p.min_thrust_n.max(1e-6);
        thrust_limit = ThrustLimit::Min;
    }
    let horizontal = f.xy().norm();
    let max_horizontal = -f.z * p.max_tilt_rad.tan();
    let tilt_limited = horizontal > max_horizontal;
    if tilt_limited {
        let s = max_horizontal / horizontal;
        f.x *= s;
        f.y *= s;
    }
    let r33 = current.to_rotation_matrix()[(2, 2)];
    let raw_thrust = -f.z / r33.max(MIN_TILT_COSINE);
    let thrust_n = raw_thrust.clamp(p.min_thrust_n, p.max_thrust_n);
    if raw_thrust > p.max_thrust_n {
        thrust_limit = ThrustLimit::Max;
    } else if raw_thrust < p.min_thrust_n {
        thrust_limit = ThrustLimit::Min;
    }
    let z = -f / f.norm();
    let heading = Vector3::new(yaw_rad.cos(), yaw_rad.sin(), 0.0);
    let y = z.cross(&heading).normalize();
    let x = y.cross(&z);
    let r = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
    let mut attitude = UnitQuaternion::from_rotation_matrix(&r);
    if attitude.w < 0.0 {
        // One sign for the same rotation, so the log reads continuously.
        attitude = UnitQuaternion::new_unchecked(-attitude.into_inner());
    }
    Mapped {
        attitude,
        thrust_n,
        force_ned_n: f,
        tilt_limited,
        thrust_limit,
    }
}

#[cfg(test)]
#[path = "mapping_tests.rs"]
mod tests;
