use super::*;

/// Round numbers for hand computation: m = 2 kg, g = 10 m/s².
fn params() -> MappingParams {
    MappingParams {
        mass_kg: 2.0,
        gravity_m_s2: 10.0,
        max_tilt_rad: 35f64.to_radians(),
        min_thrust_n: 2.0,
        max_thrust_n: 32.0,
    }
}

fn body_axis(q: &UnitQuaternion<f64>, i: usize) -> Vector3<f64> {
    q.to_rotation_matrix().matrix().column(i).into_owned()
}

#[test]
fn hover_is_level_at_the_yaw_with_weight_thrust() {
    for yaw in [0.0, 0.5, -2.0] {
        let m = map_acceleration(&Vector3::zeros(), yaw, &level(0.3), &params());
        assert!(m.attitude.angle_to(&level(yaw)) < 1e-12);
        assert!((m.thrust_n - 20.0).abs() < 1e-12);
        // Body z (FRD, down) along +e3.
        assert!((body_axis(&m.attitude, 2) - Vector3::z()).norm() < 1e-12);
        assert!(!m.tilt_limited && m.thrust_limit == ThrustLimit::None);
    }
}

/// a_d = 3 m/s² north at yaw 0: F_d = (6, 0, −20) N, tilt atan(6/20) = 16.699°, a pure pitch
/// nose-down (rotation about +y by −16.699°), x axis yaw 0; thrust 20 / (cos 10° cos 20°) =
/// 21.612 N with the vehicle currently at roll 10°, pitch 20°.
#[test]
fn forward_acceleration_at_yaw_0_pitches_nose_down() {
    let current = UnitQuaternion::from_euler_angles(10f64.to_radians(), 20f64.to_radians(), 0.0);
    let m = map_acceleration(&Vector3::new(3.0, 0.0, 0.0), 0.0, &current, &params());
    let tilt = (6.0f64 / 20.0).atan();
    let expected = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -tilt);
    assert!(m.attitude.angle_to(&expected) < 1e-12, "{:?}", m.attitude);
    let (roll, pitch, yaw) = m.attitude.euler_angles();
    assert!(roll.abs() < 1e-12 && (pitch + 16.699_2f64.to_radians()).abs() < 1e-5);
    assert!(yaw.abs() < 1e-12);
    let thrust = 20.0 / (10f64.to_radians().cos() * 20f64.to_radians().cos());
    assert!((m.thrust_n - thrust).abs() < 1e-12 && (thrust - 21.612).abs() < 1e-3);
    // The thrust (−body z) points along F_d.
    let z = body_axis(&m.attitude, 2);
    assert!((z + m.force_ned_n.normalize()).norm() < 1e-12);
}

/// Yaw 30°: along the heading the tilt is a pure pitch in the yawed frame (x axis yaw exactly
/// 30°, tilt axis the heading's y axis); sideways (a_d = 3 m/s² east) the tilt axis is +x
/// (north) and, by the paper's construction y_d ⊥ χ, the x axis yaws to
/// atan(cos²(16.699°) tan 30°) = 27.91°.
#[test]
fn tilted_forces_at_yaw_30() {
    let psi = 30f64.to_radians();
    let tilt = (6.0f64 / 20.0).atan();
    let a = Vector3::new(psi.cos(), psi.sin(), 0.0) * 3.0;
    let m = map_acceleration(&a, psi, &level(0.0), &params());
    let expected = level(psi) * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -tilt);
    assert!(m.attitude.angle_to(&expected) < 1e-12);
    assert!((yaw_of(&m.attitude) - psi).abs() < 1e-12);
    let tilt_rot = m.attitude * level(psi).inverse();
    let axis = tilt_rot.axis().unwrap().into_inner();
    assert!(
        (axis - Vector3::new(psi.sin(), -psi.cos(), 0.0)).norm() < 1e-9,
        "{axis}"
    );
    assert!((tilt_rot.angle() - tilt).abs() < 1e-12);

    let m = map_acceleration(&Vector3::new(0.0, 3.0, 0.0), psi, &level(0.0), &params());
    let z = body_axis(&m.attitude, 2);
    let swing = UnitQuaternion::rotation_between(&Vector3::z(), &z).unwrap();
    assert!((swing.angle() - tilt).abs() < 1e-12);
    assert!((swing.axis().unwrap().into_inner() - Vector3::x()).norm() < 1e-12);
    let x_yaw = (tilt.cos().powi(2) * psi.tan()).atan();
    assert!((yaw_of(&m.attitude) - x_yaw).abs() < 1e-12);
    assert!((x_yaw.to_degrees() - 27.91).abs() < 0.01);
    // y_d is horizontal-orthogonal to the heading χ.
    let y = body_axis(&m.attitude, 1);
    assert!(y.dot(&Vector3::new(psi.cos(), psi.sin(), 0.0)).abs() < 1e-12);
    assert!((m.thrust_n - 20.0).abs() < 1e-12);
}

#[test]
fn tilt_is_limited_keeping_the_vertical_component() {
    let m = map_acceleration(&Vector3::new(20.0, 0.0, 0.0), 0.0, &level(0.0), &params());
    assert!(m.tilt_limited);
    let tilt = body_axis(&m.attitude, 2).angle(&Vector3::z());
    assert!(
        (tilt - 35f64.to_radians()).abs() < 1e-12,
        "{}",
        tilt.to_degrees()
    );
    assert!((m.force_ned_n.z + 20.0).abs() < 1e-12 && (m.thrust_n - 20.0).abs() < 1e-12);
    assert!((m.force_ned_n.x - 20.0 * 35f64.to_radians().tan()).abs() < 1e-12);
}

#[test]
fn thrust_is_clamped_both_ways() {
    let up = map_acceleration(&Vector3::new(0.0, 0.0, -20.0), 0.0, &level(0.0), &params());
    assert_eq!((up.thrust_n, up.thrust_limit), (32.0, ThrustLimit::Max));
    let down = map_acceleration(&Vector3::new(0.0, 0.0, 15.0), 1.0, &level(0.0), &params());
    assert_eq!((down.thrust_n, down.thrust_limit), (2.0, ThrustLimit::Min));
    assert!(down.attitude.angle_to(&level(1.0)) < 1e-12);
    // Knocked over (90° roll): the cosine floor caps the correction at 2x.
    let over = UnitQuaternion::from_euler_angles(1.5, 0.0, 0.0);
    let roomy = MappingParams {
        max_thrust_n: 50.0,
        ..params()
    };
    let m = map_acceleration(&Vector3::zeros(), 0.0, &over, &roomy);
    assert!((m.thrust_n - 20.0 / MIN_TILT_COSINE).abs() < 1e-12);
}
