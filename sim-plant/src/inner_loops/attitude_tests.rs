use super::*;

fn ctrl() -> AttitudeControl {
    AttitudeControl::new(&AttitudeControlParams::default()).unwrap()
}

fn rot(axis: Vector3<f64>, angle: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle)
}

#[test]
fn small_roll_error_gives_roll_p_times_error() {
    let c = ctrl();
    let q = UnitQuaternion::identity();
    for angle in [0.05, -0.1, 0.2] {
        let sp = rot(Vector3::x(), angle);
        let r = c.update(&q, &sp, f64::NAN).unwrap();
        // Error vector is 2 sin(angle/2) about body x (= angle to first order).
        let expected = 6.5 * 2.0 * (angle / 2.0).sin();
        assert!((r.x - expected).abs() < 1e-12, "{angle}: {r:?}");
        assert!(r.y.abs() < 1e-12 && r.z.abs() < 1e-12, "{r:?}");
        assert!((r.x - 6.5 * angle).abs() < 6.5 * angle.abs() * 0.01);
    }
    // Pitch the same way, and from a tilted current attitude the error is in body axes.
    let sp = rot(Vector3::y(), -0.1);
    let r = c.update(&q, &sp, f64::NAN).unwrap();
    assert!((r.y - 6.5 * 2.0 * (-0.05f64).sin()).abs() < 1e-12);
    let q = rot(Vector3::x(), 0.3);
    let sp = rot(Vector3::x(), 0.35);
    let r = c.update(&q, &sp, f64::NAN).unwrap();
    assert!((r.x - 13.0 * 0.025f64.sin()).abs() < 1e-12, "{r:?}");
}

#[test]
fn pure_yaw_error_is_weighted_then_regained_by_the_gain() {
    let c = ctrl();
    let psi = 0.3;
    let r = c
        .update(
            &UnitQuaternion::identity(),
            &rot(Vector3::z(), psi),
            f64::NAN,
        )
        .unwrap();
    // Yaw error scaled by 0.4, gain 2.8 / 0.4 = 7.
    let expected = 7.0 * 2.0 * (0.4 * psi / 2.0).sin();
    assert!((r.z - expected).abs() < 1e-12, "{r:?}");
    assert!((r.z - 2.8 * psi).abs() < 0.01 * 2.8 * psi);
    assert!(r.x.abs() < 1e-12 && r.y.abs() < 1e-12);
}

#[test]
fn tilt_part_is_unaffected_by_yaw_error_and_yaw_weight() {
    let theta: f64 = 0.2;
    let tilt_norm = 6.5 * 2.0 * (theta / 2.0).sin();
    for yaw_weight in [0.4, 1.0] {
        let c = AttitudeControl::new(&AttitudeControlParams {
            yaw_weight,
            ..AttitudeControlParams::default()
        })
        .unwrap();
        for alpha in [0.0, 0.5, 1.0, -0.8] {
            // Tilt theta about body x, then yaw alpha about world z.
            let sp = rot(Vector3::z(), alpha) * rot(Vector3::x(), theta);
            let r = c
                .update(&UnitQuaternion::identity(), &sp, f64::NAN)
                .unwrap();
            let xy = (r.x * r.x + r.y * r.y).sqrt();
            assert!(
                (xy - tilt_norm).abs() < 1e-12,
                "w {yaw_weight} a {alpha}: {xy}"
            );
            // The yaw residual after the tilt is exactly alpha here.
            let yaw =
                2.8 / yaw_weight * 2.0 * (theta / 2.0).cos() * (yaw_weight * alpha / 2.0).sin();
            assert!((r.z - yaw).abs() < 1e-12, "w {yaw_weight} a {alpha}: {r:?}");
        }
    }
}

#[test]
fn rates_are_clamped_to_px4_limits() {
    let c = ctrl();
    let q = UnitQuaternion::identity();
    let r = c.update(&q, &rot(Vector3::x(), 1.0), f64::NAN).unwrap();
    assert!((r.x - 220f64.to_radians()).abs() < 1e-12, "{r:?}");
    let r = c.update(&q, &rot(Vector3::y(), -1.0), f64::NAN).unwrap();
    assert!((r.y + 220f64.to_radians()).abs() < 1e-12, "{r:?}");
    let r = c.update(&q, &rot(Vector3::z(), 3.0), f64::NAN).unwrap();
    assert!((r.z - 200f64.to_radians()).abs() < 1e-12, "{r:?}");
    let r = c.update(&q, &q, 10.0).unwrap();
    assert!((r.z - 200f64.to_radians()).abs() < 1e-12, "{r:?}");
}

#[test]
fn yaw_rate_feed_forward_is_about_world_z() {
    let c = ctrl();
    let q = rot(Vector3::x(), 0.4);
    let r = c.update(&q, &q, 0.5).unwrap();
    // World z in body FRD at 0.4 rad roll: (0, sin 0.4, cos 0.4).
    assert!(r.x.abs() < 1e-12);
    assert!((r.y - 0.5 * 0.4f64.sin()).abs() < 1e-12, "{r:?}");
    assert!((r.z - 0.5 * 0.4f64.cos()).abs() < 1e-12, "{r:?}");
}

#[test]
fn upside_down_setpoint_gives_finite_limited_rates() {
    let c = ctrl();
    let r = c
        .update(
            &UnitQuaternion::identity(),
            &rot(Vector3::x(), std::f64::consts::PI),
            f64::NAN,
        )
        .unwrap();
    assert!(r.iter().all(|v| v.is_finite()));
    assert!(r.x.abs() <= 220f64.to_radians() + 1e-12);
}

#[test]
fn non_finite_inputs_are_rejected() {
    let c = ctrl();
    let bad = UnitQuaternion::new_unchecked(Quaternion::new(f64::NAN, 0.0, 0.0, 0.0));
    let ok = UnitQuaternion::identity();
    assert_eq!(
        c.update(&bad, &ok, 0.0),
        Err(StepError::NonFinite { name: "attitude" })
    );
    assert_eq!(
        c.update(&ok, &bad, 0.0),
        Err(StepError::NonFinite {
            name: "attitude_sp"
        })
    );
    let p = AttitudeControlParams {
        yaw_weight: 1.5,
        ..AttitudeControlParams::default()
    };
    assert_eq!(
        AttitudeControl::new(&p).unwrap_err().key,
        "attitude.yaw_weight"
    );
}
