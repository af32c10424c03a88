//! Limits, anti-windup and the non-finite guard of the stage.

use super::*;

#[test]
fn tilt_and_thrust_are_limited_without_windup() {
    let q = level(0.0);
    let far = [OWN[0] + 10.0, OWN[1], OWN[2] - 10.0];
    let mut s = stage();
    let mut sp = AttitudeSetpoint::default();
    for k in 0..6000u64 {
        let t = k * DT_NS;
        sp = s.step(t, &vehicle_at(t, far, &q), None, Some(&mission(t, 0.0, 0)));
        let tilt = attitude(&sp).to_rotation_matrix()[(2, 2)].acos();
        assert!(tilt <= 35f64.to_radians() + 1e-9);
        assert!(sp.thrust_n <= 32.0);
    }
    // 10 m off: v_d clamped (3 m/s back south, 1.5 m/s down); both outputs saturated the
    // whole minute, so conditional integration kept the velocity integrals at zero.
    let a = Vector3::from(sp.acceleration_desired_ned_m_s2);
    assert!(
        (a - Vector3::new(-2.7 * 3.0, 0.0, 6.0 * 1.5)).norm() < 1e-9,
        "{a}"
    );
    let far_up = [OWN[0], OWN[1], OWN[2] + 10.0];
    let mut s = stage();
    for k in 0..6000u64 {
        let t = k * DT_NS;
        sp = s.step(
            t,
            &vehicle_at(t, far_up, &q),
            None,
            Some(&mission(t, 0.0, 0)),
        );
        assert_eq!(sp.thrust_n, 32.0);
        assert!(sp.flags & setpoint_flags::THRUST_LIMITED != 0);
    }
    assert!((sp.acceleration_desired_ned_m_s2[2] + 6.0 * 1.5).abs() < 1e-9);
    assert!(s.counters().thrust_limited_steps == 6000);
}

/// A persistent unsaturated velocity error (drifting 0.5 m/s south at the setpoint): the
/// integral contribution grows at 1.9 * 0.5 m/s³ and stops at its 3 m/s² bound.
#[test]
fn velocity_integral_is_bounded() {
    let q = level(0.0);
    let mut s = stage();
    let mut sp = AttitudeSetpoint::default();
    for k in 0..1000u64 {
        let t = k * DT_NS;
        let mut v = vehicle_at(t, OWN, &q);
        v.velocity_ned_m_s = [-0.5, 0.0, 0.0];
        sp = s.step(t, &v, None, Some(&mission(t, 0.0, 0)));
        let integral = sp.acceleration_desired_ned_m_s2[0] - 2.7 * 0.5;
        let expected = (1.9 * 0.5 * k as f64 * 0.01).min(3.0);
        assert!((integral - expected).abs() < 1e-9, "step {k}: {integral}");
    }
    assert_eq!(sp.flags & setpoint_flags::TILT_LIMITED, 0);
}

/// A non-finite input gives the safe output and changes nothing: the step after it equals the
/// same step in a run that never saw it.
#[test]
fn non_finite_input_is_safe_and_leaves_the_state_untouched() {
    let q = level(0.3);
    let inputs = |k: u64| {
        let t = k * DT_NS;
        let mut v = vehicle_at(t, [OWN[0] + 0.2, OWN[1], OWN[2] + 0.1], &q);
        v.velocity_ned_m_s = [0.1, -0.2, 0.05 * k as f64];
        (t, v, tension(t, &(0.8 * t_d()), &q), mission(t, 0.3, ON))
    };
    let (mut a, mut b) = (stage(), stage());
    for k in 0..3 {
        let (t, v, ten, m) = inputs(k);
        assert_eq!(
            a.step(t, &v, Some(&ten), Some(&m)),
            b.step(t, &v, Some(&ten), Some(&m))
        );
    }
    let (t, v, ten, m) = inputs(3);
    for poison in 0..3 {
        let (mut v, mut ten, mut m) = (v, ten, m);
        match poison {
            0 => v.position_ned_m[1] = f64::NAN,
            1 => ten.force_body_n[2] = f64::INFINITY,
            _ => m.yaw_rad = f64::NAN,
        }
        let sp = b.step(t, &v, Some(&ten), Some(&m));
        assert!(sp.flags & setpoint_flags::NON_FINITE != 0);
        assert!(attitude(&sp).angle_to(&level(0.3)) < 1e-12);
        assert!((sp.thrust_n - weight()).abs() < 1e-12);
    }
    let (t, v, ten, m) = inputs(4);
    assert_eq!(
        a.step(t, &v, Some(&ten), Some(&m)),
        b.step(t, &v, Some(&ten), Some(&m))
    );
    assert_eq!(b.counters().non_finite_inputs, 3);
}
