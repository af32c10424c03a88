use super::*;
use crate::inner_loops::errors::StepError;

const DT: f64 = 0.0025;

fn ctrl() -> PositionControl {
    PositionControl::new(&PositionControlParams::default()).unwrap()
}

/// Angle between the setpoint's body z axis and NED down, rad.
fn tilt(out: &PositionControlOutput) -> f64 {
    (out.attitude_sp * Vector3::z()).z.clamp(-1.0, 1.0).acos()
}

#[test]
fn hover_with_zero_error_is_level_at_hover_throttle() {
    let mut pc = ctrl();
    let pos = Vector3::new(1.0, -2.0, -1.5);
    for yaw in [0.0, 1.2] {
        let out = pc
            .update(
                DT,
                &pos,
                &Vector3::zeros(),
                0.3,
                &TrajectorySetpoint::position(pos, yaw),
            )
            .unwrap();
        assert!((out.thrust - 0.6).abs() < 1e-12, "{out:?}");
        assert!(tilt(&out) < 1e-12);
        let (_, _, y) = out.attitude_sp.euler_angles();
        assert!((y - yaw).abs() < 1e-12);
    }
    // NaN yaw holds the current yaw.
    let out = pc
        .update(
            DT,
            &pos,
            &Vector3::zeros(),
            0.3,
            &TrajectorySetpoint::position(pos, f64::NAN),
        )
        .unwrap();
    assert!((out.attitude_sp.euler_angles().2 - 0.3).abs() < 1e-12);
}

#[test]
fn north_error_pitches_nose_down_and_thrusts_north() {
    let mut pc = ctrl();
    let sp = TrajectorySetpoint::position(Vector3::new(1.0, 0.0, 0.0), 0.0);
    let out = pc
        .update(DT, &Vector3::zeros(), &Vector3::zeros(), 0.0, &sp)
        .unwrap();
    // vel_sp = 0.95 m/s, acc_sp = 1.8 * 0.95 = 1.71 m/s^2 north.
    assert!((out.velocity_sp_ned_m_s.x - 0.95).abs() < 1e-12);
    assert!((out.acceleration_sp_ned_m_s2.x - 1.71).abs() < 1e-12);
    let (roll, pitch, _) = out.attitude_sp.euler_angles();
    let expected_pitch = -(1.71f64 / PX4_ONE_G).atan();
    assert!(roll.abs() < 1e-12);
    assert!(
        (pitch - expected_pitch).abs() < 1e-12,
        "{pitch} vs {expected_pitch}"
    );
    assert!((out.thrust - 0.6 / expected_pitch.cos()).abs() < 1e-12);
    let thrust_ned = out.attitude_sp * Vector3::new(0.0, 0.0, -out.thrust);
    assert!((thrust_ned - out.thrust_ned).norm() < 1e-12);
    assert!(thrust_ned.x > 0.0 && thrust_ned.y.abs() < 1e-12);
    // Its horizontal part gives exactly the commanded acceleration with hover = g.
    assert!((thrust_ned.x * PX4_ONE_G / 0.6 - 1.71).abs() < 1e-12);
}

#[test]
fn nan_position_with_velocity_setpoint_controls_velocity_only() {
    let sp = TrajectorySetpoint::velocity(Vector3::new(0.0, 0.0, 0.7), 0.0);
    let mut outs = Vec::new();
    for pos in [
        Vector3::zeros(),
        Vector3::new(5.0, -3.0, -10.0),
        Vector3::repeat(f64::NAN),
    ] {
        let mut pc = ctrl();
        outs.push(pc.update(DT, &pos, &Vector3::zeros(), 0.0, &sp).unwrap());
    }
    assert!(outs.iter().all(|o| o == &outs[0]));
    // Descending at 0.7 m/s from rest: a_z = 4 * 0.7 down, thrust below hover.
    let o = &outs[0];
    assert!((o.acceleration_sp_ned_m_s2.z - 2.8).abs() < 1e-12);
    assert!(
        (o.thrust - (0.6 - 2.8 * 0.6 / PX4_ONE_G)).abs() < 1e-12,
        "{o:?}"
    );

    // PX4's Land: xy position held, z only by velocity, whatever the height.
    let land = TrajectorySetpoint::land(Vector2::new(0.5, 0.0), 0.0, 0.7);
    let a = ctrl()
        .update(
            DT,
            &Vector3::new(0.0, 0.0, -10.0),
            &Vector3::zeros(),
            0.0,
            &land,
        )
        .unwrap();
    let b = ctrl()
        .update(
            DT,
            &Vector3::new(0.0, 0.0, -0.2),
            &Vector3::zeros(),
            0.0,
            &land,
        )
        .unwrap();
    assert_eq!(a, b);
    assert!((a.velocity_sp_ned_m_s - Vector3::new(0.475, 0.0, 0.7)).norm() < 1e-12);
}

#[test]
fn tilt_and_velocities_are_limited() {
    let mut pc = ctrl();
    let sp = TrajectorySetpoint::position(Vector3::new(100.0, 0.0, 0.0), 0.0);
    let out = pc
        .update(DT, &Vector3::zeros(), &Vector3::zeros(), 0.0, &sp)
        .unwrap();
    // vel_sp 95 m/s capped at 12, a = 21.6 m/s^2 would tilt 65.6 deg: capped at 45.
    assert!((out.velocity_sp_ned_m_s.x - 12.0).abs() < 1e-12);
    assert!(
        (tilt(&out) - 45f64.to_radians()).abs() < 1e-9,
        "{}",
        tilt(&out).to_degrees()
    );
    assert!((out.thrust - 0.6 * 2f64.sqrt()).abs() < 1e-12, "{out:?}");

    // Climbing hard as well: vertical priority leaves MPC_THR_XY_MARG = 0.3 horizontally,
    // tilt atan(0.3 / sqrt(1 - 0.3^2)) = 17.46 deg at full thrust.
    let sp = TrajectorySetpoint::position(Vector3::new(100.0, 0.0, -100.0), 0.0);
    let out = ctrl()
        .update(DT, &Vector3::zeros(), &Vector3::zeros(), 0.0, &sp)
        .unwrap();
    assert!((out.velocity_sp_ned_m_s.z + 3.0).abs() < 1e-12);
    assert!(
        (tilt(&out) - 0.3f64.asin()).abs() < 1e-9,
        "{}",
        tilt(&out).to_degrees()
    );
    assert!((out.thrust - 1.0).abs() < 1e-12);
    let down = TrajectorySetpoint::position(Vector3::new(0.0, 0.0, 100.0), 0.0);
    let mut pc = ctrl();
    let climbing = Vector3::new(0.0, 0.0, -1.0);
    let out = pc
        .update(DT, &Vector3::zeros(), &climbing, 0.0, &down)
        .unwrap();
    assert!((out.velocity_sp_ned_m_s.z - 1.5).abs() < 1e-12);
    // 2.5 m/s short of the 1.5 m/s sink rate: a_z = 10 m/s^2 > g (1 - 0.12 / 0.6), so the
    // thrust floors at MPC_THR_MIN and the z integral is frozen.
    assert!((out.thrust - 0.12).abs() < 1e-12, "{out:?}");
    assert_eq!(pc.integral().z, 0.0);
}

#[test]
fn vertical_integral_is_bounded_by_g() {
    let mut pc = ctrl();
    let sp = TrajectorySetpoint::position(Vector3::zeros(), 0.0);
    // Held 1 m low forever (a weight the loop cannot see): integral grows, then stops at g
    // or when the thrust hits its maximum.
    for _ in 0..40_000 {
        pc.update(
            DT,
            &Vector3::new(0.0, 0.0, 1.0),
            &Vector3::zeros(),
            0.0,
            &sp,
        )
        .unwrap();
    }
    assert!(pc.integral().z.abs() <= PX4_ONE_G + 1e-12);
    assert!(pc.integral().z < -1.0);
}

#[test]
fn landed_commands_minimum_thrust_and_holds_integrators() {
    let mut pc = ctrl();
    pc.set_landed(true);
    let sp = TrajectorySetpoint::position(Vector3::new(0.0, 0.0, -5.0), 0.0);
    let out = pc
        .update(DT, &Vector3::zeros(), &Vector3::zeros(), 0.4, &sp)
        .unwrap();
    assert!((out.thrust - 1e-3).abs() < 1e-12, "{out:?}");
    assert!(tilt(&out) < 1e-12);
    assert_eq!(pc.integral(), Vector3::zeros());
}

#[test]
fn invalid_setpoints_are_rejected_without_touching_the_integral() {
    let mut pc = ctrl();
    let z = Vector3::zeros();
    let mut sp = TrajectorySetpoint::position(Vector3::new(1.0, 0.0, 0.0), 0.0);
    pc.update(DT, &z, &z, 0.0, &sp).unwrap();
    let integral = pc.integral();
    let err = |r: Result<PositionControlOutput, StepError>| {
        matches!(r, Err(StepError::InvalidSetpoint { .. }))
    };
    assert!(err(pc.update(
        DT,
        &z,
        &z,
        0.0,
        &TrajectorySetpoint::empty()
    )));
    sp.position_ned_m.y = f64::NAN;
    assert!(err(pc.update(DT, &z, &z, 0.0, &sp)));
    let sp = TrajectorySetpoint::position(Vector3::new(1.0, 0.0, 0.0), 0.0);
    assert!(err(pc.update(DT, &Vector3::repeat(f64::NAN), &z, 0.0, &sp)));
    assert_eq!(pc.integral(), integral);
    assert_eq!(
        pc.update(DT, &z, &z, f64::NAN, &sp),
        Err(StepError::NonFinite { name: "yaw_rad" })
    );
    let bad = PositionControlParams {
        thr_min: 0.9,
        hover_throttle: 0.6,
        thr_max: 0.8,
        ..PositionControlParams::default()
    };
    assert_eq!(
        PositionControl::new(&bad).unwrap_err().key,
        "position.thr_min"
    );
}
