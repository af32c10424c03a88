use super::*;

fn alloc(airmode: Airmode) -> ControlAllocation {
    ControlAllocation::new(&AllocationParams {
        airmode,
        ..AllocationParams::default()
    })
    .unwrap()
}

/// Body torque (FRD, in units of one motor's full thrust times metres) of normalized motor
/// thrusts, from the default geometry.
fn physical_torque(u: &[f64; 4]) -> Vector3<f64> {
    let p = AllocationParams::default();
    let mut t = Vector3::zeros();
    for (r, ui) in p.rotors.iter().zip(u) {
        let [x, y, _] = r.position_frd_m;
        t += Vector3::new(-y * ui, x * ui, r.moment_ratio_m * ui);
    }
    t
}

const H: f64 = std::f64::consts::FRAC_1_SQRT_2;

#[test]
fn normalized_mix_matches_px4_for_quad_x() {
    let a = alloc(Airmode::Disabled);
    let expected = Matrix4::new(
        -H, H, 1.0, -1.0, // motor 1 front right CCW
        H, -H, 1.0, -1.0, // motor 2 rear left CCW
        H, H, -1.0, -1.0, // motor 3 front left CW
        -H, -H, -1.0, -1.0, // motor 4 rear right CW
    );
    assert!((a.mix() - expected).abs().max() < 1e-12, "{}", a.mix());
}

#[test]
fn pure_thrust_gives_equal_motors() {
    let mut a = alloc(Airmode::Disabled);
    for t in [0.0, 0.3, 0.6, 1.0] {
        let out = a.update(&Vector3::zeros(), t).unwrap();
        for u in out.motor_thrust {
            assert!((u - t).abs() < 1e-12, "{t}: {out:?}");
        }
        assert!((out.allocated_thrust - t).abs() < 1e-12);
        assert_eq!(out.saturation_positive, [false; 3]);
        assert_eq!(out.saturation_negative, [false; 3]);
    }
}

#[test]
fn torque_signs_follow_frd_and_rotor_directions() {
    let mut a = alloc(Airmode::Disabled);
    // Positive roll = right side down: right motors (1, 4; +y) slow, left (2, 3) speed up.
    let u = a
        .update(&Vector3::new(0.1, 0.0, 0.0), 0.5)
        .unwrap()
        .motor_thrust;
    let d = 0.1 * H;
    let want = [0.5 - d, 0.5 + d, 0.5 + d, 0.5 - d];
    for i in 0..4 {
        assert!((u[i] - want[i]).abs() < 1e-12, "{u:?}");
    }
    let tq = physical_torque(&u);
    assert!(
        tq.x > 0.0 && tq.y.abs() < 1e-12 && tq.z.abs() < 1e-12,
        "{tq:?}"
    );

    // Positive pitch = nose up: front motors (1, 3) speed up.
    let u = a
        .update(&Vector3::new(0.0, 0.1, 0.0), 0.5)
        .unwrap()
        .motor_thrust;
    assert!(
        u[0] > 0.5 && u[2] > 0.5 && u[1] < 0.5 && u[3] < 0.5,
        "{u:?}"
    );
    assert!(physical_torque(&u).y > 0.0);

    // Positive yaw: CCW motors (1, 2) speed up, their reaction torque is +km T.
    let u = a
        .update(&Vector3::new(0.0, 0.0, 0.1), 0.5)
        .unwrap()
        .motor_thrust;
    let want = [0.6, 0.6, 0.4, 0.4];
    for i in 0..4 {
        assert!((u[i] - want[i]).abs() < 1e-12, "{u:?}");
    }
    let tq = physical_torque(&u);
    assert!(
        tq.z > 0.0 && tq.x.abs() < 1e-12 && tq.y.abs() < 1e-12,
        "{tq:?}"
    );
}

#[test]
fn near_full_thrust_keeps_roll_pitch_and_lowers_thrust() {
    let mut a = alloc(Airmode::Disabled);
    let torque = Vector3::new(0.2, -0.1, 0.0);
    let out = a.update(&torque, 0.95).unwrap();
    let achieved = physical_torque(&out.motor_thrust);
    let requested = physical_torque(&(a.mix() * Vector4::new(0.2, -0.1, 0.0, 0.0)).into());
    assert!((achieved - requested).norm() < 1e-12, "{out:?}");
    assert!(out.unallocated_torque.norm() < 1e-12);
    // Highest motor exactly at 1, thrust reduced by the excess 0.3 H = 0.212.
    let max = out.motor_thrust.iter().cloned().fold(0.0, f64::max);
    assert!((max - 1.0).abs() < 1e-12, "{out:?}");
    assert!(
        (out.allocated_thrust - (0.95 - (0.3 * H - 0.05))).abs() < 1e-12,
        "{out:?}"
    );
    assert_eq!(out.saturation_positive, [false; 3]);
}

#[test]
fn near_zero_thrust_without_airmode_reduces_roll_as_px4() {
    let mut a = alloc(Airmode::Disabled);
    let out = a.update(&Vector3::new(0.2, 0.0, 0.0), 0.05).unwrap();
    // PX4 without airmode never raises thrust: roll shrinks until the low motors hit 0.
    let min = out.motor_thrust.iter().cloned().fold(1.0, f64::min);
    assert!(min.abs() < 1e-12, "{out:?}");
    assert!((out.allocated_thrust - 0.05).abs() < 1e-12);
    let achieved_roll = 0.2 - out.unallocated_torque.x;
    assert!((achieved_roll - 0.05 / H).abs() < 1e-12, "{out:?}");
    assert_eq!(out.saturation_positive, [true, false, false]);
    assert_eq!(out.saturation_negative, [false; 3]);

    // With airmode (roll/pitch) the roll is kept and thrust raised instead.
    let mut a = alloc(Airmode::RollPitch);
    let out = a.update(&Vector3::new(0.2, 0.0, 0.0), 0.05).unwrap();
    assert!(out.unallocated_torque.norm() < 1e-12, "{out:?}");
    assert!((out.allocated_thrust - 0.2 * H).abs() < 1e-12, "{out:?}");
}

#[test]
fn yaw_gives_way_before_roll() {
    let mut a = alloc(Airmode::Disabled);
    let out = a.update(&Vector3::new(0.5, 0.0, 0.5), 0.5).unwrap();
    assert!(out.unallocated_torque.x.abs() < 1e-12, "{out:?}");
    assert!(out.unallocated_torque.z > 0.3, "{out:?}");
    assert_eq!(out.saturation_positive, [false, false, true], "{out:?}");
    assert!(out.motor_thrust.iter().all(|u| (0.0..=1.0).contains(u)));
}

#[test]
fn bad_inputs_and_geometry_are_rejected() {
    let mut a = alloc(Airmode::Disabled);
    assert_eq!(
        a.update(&Vector3::zeros(), f64::NAN),
        Err(StepError::NonFinite { name: "thrust" })
    );
    let mut p = AllocationParams::default();
    for r in &mut p.rotors {
        r.position_frd_m = [0.1, 0.0, 0.0]; // all on one point: no roll/pitch authority
    }
    assert_eq!(
        ControlAllocation::new(&p).unwrap_err().key,
        "allocation.rotors"
    );
    let p: AllocationParams = toml::from_str("airmode = \"roll_pitch\"\n").unwrap();
    assert_eq!(p.airmode, Airmode::RollPitch);
}
