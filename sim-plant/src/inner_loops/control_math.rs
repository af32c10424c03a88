//! PX4's ControlMath helpers used by the position controller.
//!
//! Followed: PX4-Autopilot src/modules/mc_pos_control/PositionControl/ControlMath.cpp
//! (`thrustToAttitude`, `bodyzToAttitude`, `limitTilt`, `constrainXY`) and ControlMath.hpp
//! (`addIfNotNan`, `setZeroIfNan`). All vectors here are NED.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector2, Vector3};

/// Attitude setpoint (body FRD -> NED) and collective thrust (normalized) from a thrust
/// vector `thrust_ned` (normalized, pointing where the thrust pushes) and a yaw, rad.
pub fn thrust_to_attitude(thrust_ned: &Vector3<f64>, yaw_rad: f64) -> (UnitQuaternion<f64>, f64) {
    (body_z_to_attitude(-thrust_ned, yaw_rad), thrust_ned.norm())
}

/// Attitude whose body z axis points along `body_z_ned` with heading `yaw_rad`.
pub fn body_z_to_attitude(mut body_z: Vector3<f64>, yaw_rad: f64) -> UnitQuaternion<f64> {
    // PX4 tests against FLT_EPSILON: a zero vector means "level".
    if body_z.norm_squared() < f32::EPSILON as f64 {
        body_z.z = 1.0;
    }
    body_z.normalize_mut();
    // Desired yaw direction in the horizontal plane, rotated by +90 degrees.
    let y_c = Vector3::new(-yaw_rad.sin(), yaw_rad.cos(), 0.0);
    let mut body_x = y_c.cross(&body_z);
    if body_z.z < 0.0 {
        // Keep the nose to the front while upside down.
        body_x = -body_x;
    }
    if body_z.z.abs() < 1e-6 {
        // Thrust in the horizontal plane: yaw is meaningless, point x down.
        body_x = Vector3::z();
    }
    body_x.normalize_mut();
    let body_y = body_z.cross(&body_x);
    let r = Matrix3::from_columns(&[body_x, body_y, body_z]);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r))
}

/// Rotates the unit vector `body_unit` towards `world_unit` until the angle between them is
/// at most `max_angle_rad`.
pub fn limit_tilt(body_unit: &mut Vector3<f64>, world_unit: &Vector3<f64>, max_angle_rad: f64) {
    let dot = body_unit.dot(world_unit);
    let angle = dot.clamp(-1.0, 1.0).acos().min(max_angle_rad);
    let mut rejection = *body_unit - dot * world_unit;
    if rejection.norm_squared() < f32::EPSILON as f64 {
        rejection.x = 1.0;
    }
    *body_unit = angle.cos() * world_unit + angle.sin() * rejection.normalize();
}

/// `v0 + v1` limited to norm `max`, giving `v0` priority over `v1`.
pub fn constrain_xy(v0: &Vector2<f64>, v1: &Vector2<f64>, max: f64) -> Vector2<f64> {
    let sum = v0 + v1;
    if sum.norm() <= max {
        sum
    } else if v0.norm() >= max || (v1 - v0).norm() < 0.001 {
        // v0 alone reaches the limit, or both point the same way.
        v0.normalize() * max
    } else if v0.norm() < 0.001 {
        v1.normalize() * max
    } else {
        // Largest s >= 0 with |v0 + s u1| = max.
        let u1 = v1.normalize();
        let m = u1.dot(v0);
        let c = v0.dot(v0) - max * max;
        let s = -m + (m * m - c).sqrt();
        v0 + u1 * s
    }
}

/// PX4's `addIfNotNan`: NaN setpoint takes the addition; NaN addition leaves it.
pub fn add_if_not_nan(setpoint: &mut f64, addition: f64) {
    if setpoint.is_finite() && addition.is_finite() {
        *setpoint += addition;
    } else if !setpoint.is_finite() {
        *setpoint = addition;
    }
}

/// Element-wise [`add_if_not_nan`].
pub fn add_if_not_nan3(setpoint: &mut Vector3<f64>, addition: &Vector3<f64>) {
    for i in 0..3 {
        add_if_not_nan(&mut setpoint[i], addition[i]);
    }
}

/// NaN elements become 0.
pub fn set_zero_if_nan3(v: &mut Vector3<f64>) {
    add_if_not_nan3(v, &Vector3::zeros());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_thrust_gives_level_attitude_with_yaw() {
        let (q, t) = thrust_to_attitude(&Vector3::new(0.0, 0.0, -0.6), 0.7);
        assert!((t - 0.6).abs() < 1e-12);
        let (roll, pitch, yaw) = q.euler_angles();
        assert!(roll.abs() < 1e-12 && pitch.abs() < 1e-12 && (yaw - 0.7).abs() < 1e-12);
        let (q0, t0) = thrust_to_attitude(&Vector3::zeros(), 0.0);
        assert_eq!(t0, 0.0);
        assert!(q0.angle() < 1e-12);
    }

    #[test]
    fn limit_tilt_caps_the_angle_and_keeps_direction() {
        let mut v = Vector3::new(1.0, 1.0, 0.5).normalize();
        let up = Vector3::z();
        limit_tilt(&mut v, &up, 45f64.to_radians());
        assert!((v.dot(&up).acos() - 45f64.to_radians()).abs() < 1e-12);
        assert!((v.x - v.y).abs() < 1e-12 && v.x > 0.0);
        let mut small = Vector3::new(0.1, 0.0, 1.0).normalize();
        let before = small;
        limit_tilt(&mut small, &up, 45f64.to_radians());
        assert!((small - before).norm() < 1e-12);
    }

    #[test]
    fn constrain_xy_prioritizes_the_first_vector() {
        let v0 = Vector2::new(3.0, 0.0);
        let v1 = Vector2::new(0.0, 10.0);
        let r = constrain_xy(&v0, &v1, 5.0);
        assert!((r.norm() - 5.0).abs() < 1e-12);
        assert!((r.x - 3.0).abs() < 1e-12 && (r.y - 4.0).abs() < 1e-12);
        let r = constrain_xy(&Vector2::new(8.0, 0.0), &v1, 5.0);
        assert!((r - Vector2::new(5.0, 0.0)).norm() < 1e-12);
    }
}
