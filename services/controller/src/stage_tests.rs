use super::*;
use shared_types::{vehicle_flags, Header, MissionPhase};

const DT_NS: u64 = 10_000_000;
/// Test B's start: drone 0 west of drone 1, 1 m apart, 2.1 m up.
const OWN: [f64; 3] = [-1.25, -0.5, -2.1];
const PEER: [f64; 3] = [-1.25, 0.5, -2.1];

fn stage() -> ControllerStage {
    ControllerStage::new(&VehicleConfig::default(), &ControllerConfig::default()).unwrap()
}

fn header(t_ns: u64, sequence: u64) -> Header {
    Header {
        sequence,
        t_origin_ns: t_ns,
        t_publish_ns: t_ns,
    }
}

fn vehicle_at(t_ns: u64, position: [f64; 3], q: &UnitQuaternion<f64>) -> VehicleState {
    VehicleState {
        header: header(t_ns, 7),
        position_ned_m: position,
        attitude_wxyz: wxyz(q),
        flags: vehicle_flags::ARMED,
        ..Default::default()
    }
}

fn mission(t_ns: u64, yaw: f64, flags: u32) -> MissionSetpoint {
    MissionSetpoint {
        header: header(t_ns, 11),
        phase: MissionPhase::Hold,
        flags,
        position_ned_m: OWN,
        yaw_rad: yaw,
        peer_position_ned_m: PEER,
        ..Default::default()
    }
}

/// A sample whose T (NED, force on the cable) is `t_ned` for a vehicle at attitude `q`.
fn tension(t_ns: u64, t_ned: &Vector3<f64>, q: &UnitQuaternion<f64>) -> TensionSample {
    TensionSample {
        header: header(t_ns, 5),
        force_body_n: (-(q.inverse() * t_ned)).into(),
        ..Default::default()
    }
}

fn t_d() -> Vector3<f64> {
    static_tension(&OWN, &PEER, &VehicleConfig::default())
        .own_ned_n
        .into()
}

fn weight() -> f64 {
    let v = VehicleConfig::default();
    v.mass_kg * v.gravity_m_s2
}

fn shift(sp: &AttitudeSetpoint) -> Vector3<f64> {
    Vector3::from(sp.shifted_position_ned_m) - Vector3::from(sp.nominal_position_ned_m)
}

fn attitude(sp: &AttitudeSetpoint) -> UnitQuaternion<f64> {
    let [w, x, y, z] = sp.attitude_wxyz;
    UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z))
}

const ON: u32 = mission_flags::TENSION_ENABLED;

#[test]
fn hover_is_level_at_the_yaw_with_weight_thrust() {
    let yaw = 0.7;
    let q = level(yaw);
    for (flags, with_tension) in [(0, false), (ON, true)] {
        let mut s = stage();
        for k in 0..200 {
            let t = k * DT_NS;
            let ten = tension(t, &t_d(), &q);
            let sp = s.step(
                t,
                &vehicle_at(t, OWN, &q),
                with_tension.then_some(&ten),
                Some(&mission(t, yaw, flags)),
            );
            assert!(attitude(&sp).angle_to(&q) < 1e-9, "{:?}", sp.attitude_wxyz);
            assert!((sp.thrust_n - weight()).abs() < 1e-9, "{}", sp.thrust_n);
            assert!(shift(&sp).norm() < 1e-12);
            assert_eq!(sp.flags & setpoint_flags::POSITION_ONLY != 0, !with_tension);
        }
    }
}

/// The current tilt corrects the thrust: level command, vehicle at roll 10°, pitch 20°.
#[test]
fn thrust_is_corrected_by_the_current_tilt() {
    let q = UnitQuaternion::from_euler_angles(10f64.to_radians(), 20f64.to_radians(), 0.0);
    let sp = stage().step(0, &vehicle_at(0, OWN, &q), None, Some(&mission(0, 0.0, 0)));
    let expected = weight() / (10f64.to_radians().cos() * 20f64.to_radians().cos());
    assert!((sp.thrust_n - expected).abs() < 1e-9);
    assert!(attitude(&sp).angle_to(&level(0.0)) < 1e-9);
}

/// Slack (T_f = 0): e_T = T_d; the P part moves the setpoint up (z shift 0.06 e_z < 0) and out
/// (y shift 0.22 e_y, away from the peer, tightening the cable) at once. The integral does not
/// wind up on a slack cable (anti-windup): the shift stays the P part.
#[test]
fn slack_cable_moves_the_setpoint_up_and_out() {
    let mut s = stage();
    let q = level(0.0);
    let e = t_d();
    assert!(e.z < -4.9 && e.y < -1.3);
    for k in 0..100u64 {
        let t = k * DT_NS;
        let ten = tension(t, &Vector3::zeros(), &q);
        let sp = s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&ten),
            Some(&mission(t, 0.0, ON)),
        );
        let sh = shift(&sp);
        assert!(
            (sh.z - 0.06 * e.z).abs() < 1e-9,
            "step {k}: {} vs {}",
            sh.z,
            0.06 * e.z
        );
        assert!((sh.y - 0.22 * e.y).abs() < 1e-9, "step {k}: {}", sh.y);
        assert!(sh.z < -0.29 && sh.y < -0.29);
        assert_eq!(sp.tension_origin_ns, t);
        assert_eq!(sp.header.t_origin_ns, t);
    }
}

/// A cable carrying half its share (taut, T_f = T_d / 2): e_T = T_d / 2 is integrated, so the
/// setpoint keeps climbing, z shift = 0.06 e_z + 0.18 e_z Σdt, up to the 0.5 m bound.
#[test]
fn light_cable_keeps_climbing_until_it_takes_its_share() {
    let mut s = stage();
    let q = level(0.0);
    let e = 0.5 * t_d();
    let mut last = 0.0;
    for k in 0..300u64 {
        let t = k * DT_NS;
        let ten = tension(t, &(0.5 * t_d()), &q);
        let sp = s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&ten),
            Some(&mission(t, 0.0, ON)),
        );
        let sh = shift(&sp);
        let n = (k + 1) as f64 * 0.01;
        let z = (0.06 * e.z + (0.18 * e.z * n).max(-0.5)).max(-0.5);
        let y = 0.22 * e.y + 0.08 * e.y * n;
        assert!((sh.z - z).abs() < 1e-9, "step {k}: {} vs {z}", sh.z);
        assert!((sh.y - y).abs() < 1e-9, "step {k}: {} vs {y}", sh.y);
        assert!(sh.z <= last);
        last = sh.z;
    }
    assert!((last + 0.5).abs() < 1e-12);
}

/// A pull 1.5x stronger than nominal: e_T = −0.5 T_d; the setpoint yields down (+z, towards the
/// load) and inwards (+y, towards the pull and the peer).
#[test]
fn stronger_pull_makes_it_yield_down_and_towards_the_pull() {
    let mut s = stage();
    let q = level(0.0);
    let e = -0.5 * t_d();
    let ten = tension(0, &(1.5 * t_d()), &q);
    let sp = s.step(
        0,
        &vehicle_at(0, OWN, &q),
        Some(&ten),
        Some(&mission(0, 0.0, ON)),
    );
    let sh = shift(&sp);
    assert!((sh.z - (0.06 + 0.18 * 0.01) * e.z).abs() < 1e-12 && sh.z > 0.15);
    assert!((sh.y - (0.22 + 0.08 * 0.01) * e.y).abs() < 1e-12 && sh.y > 0.149);
    assert!(sh.x.abs() < 1e-12);
}

/// Stale tension with the loop on: POSITION_ONLY, P dropped, the integral frozen.
#[test]
fn stale_tension_freezes_the_integral() {
    let mut s = stage();
    let q = level(0.0);
    // A taut cable carrying half its share, so the integral runs.
    let e = 0.5 * t_d();
    for k in 0..10u64 {
        let t = k * DT_NS;
        let ten = tension(t, &(0.5 * t_d()), &q);
        s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&ten),
            Some(&mission(t, 0.0, ON)),
        );
    }
    let old = tension(9 * DT_NS, &(0.5 * t_d()), &q);
    // The old sample stays fresh (age <= 50 ms) up to step 14: 15 integrating steps in all.
    let integral = 0.18 * e.z * 0.01 * 15.0;
    for k in 10..40u64 {
        let t = k * DT_NS;
        let sp = s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&old),
            Some(&mission(t, 0.0, ON)),
        );
        let stale = t - 9 * DT_NS > 50_000_000;
        assert_eq!(
            sp.flags & setpoint_flags::POSITION_ONLY != 0,
            stale,
            "step {k}"
        );
        if stale {
            assert!((shift(&sp).z - integral).abs() < 1e-12, "{}", shift(&sp).z);
            assert_eq!((sp.tension_origin_ns, sp.header.t_origin_ns), (0, t));
        }
    }
    assert_eq!(s.counters().stale_tension_steps, 25);
}

/// Loop switched off: the shift decays from where it was (bumpless), time constant 1 s.
#[test]
fn tension_off_decays_the_shift_bumplessly() {
    let mut s = stage();
    let q = level(0.0);
    let mut before = Vector3::zeros();
    for k in 0..10u64 {
        let t = k * DT_NS;
        let ten = tension(t, &Vector3::zeros(), &q);
        before = shift(&s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&ten),
            Some(&mission(t, 0.0, ON)),
        ));
    }
    for k in 10..310u64 {
        let t = k * DT_NS;
        let ten = tension(t, &Vector3::zeros(), &q);
        let sp = s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&ten),
            Some(&mission(t, 0.0, 0)),
        );
        let expected = before * (-0.01 * (k - 9) as f64).exp();
        assert!((shift(&sp) - expected).norm() < 1e-12, "step {k}");
    }
}

#[test]
fn not_armed_is_idle_and_resets() {
    let q = level(0.4);
    let mut s = stage();
    for k in 0..50u64 {
        let t = k * DT_NS;
        let ten = tension(t, &Vector3::zeros(), &q);
        s.step(
            t,
            &vehicle_at(t, OWN, &q),
            Some(&ten),
            Some(&mission(t, 0.0, ON)),
        );
    }
    let t = 50 * DT_NS;
    let mut v = vehicle_at(t, OWN, &q);
    v.flags = 0;
    let ten = tension(t, &Vector3::zeros(), &q);
    let m = mission(t, 0.0, ON | mission_flags::ARM_REQUEST);
    let sp = s.step(t, &v, Some(&ten), Some(&m));
    assert!(sp.flags & setpoint_flags::IDLE != 0 && sp.flags & setpoint_flags::ARM_REQUEST != 0);
    assert!(attitude(&sp).angle_to(&q) < 1e-12);
    assert_eq!(sp.thrust_n, ControllerConfig::default().min_thrust_n);
    // Armed again: the same as a fresh stage (integrals and filters reset).
    let t = 51 * DT_NS;
    let ten = tension(t, &Vector3::zeros(), &q);
    let v = vehicle_at(t, OWN, &q);
    let m = mission(t, 0.0, ON);
    assert_eq!(
        s.step(t, &v, Some(&ten), Some(&m)),
        stage().step(t, &v, Some(&ten), Some(&m))
    );
}

#[test]
fn stale_mission_holds_the_current_position_and_yaw() {
    let q = level(-1.0);
    let mut s = stage();
    let here = [0.3, 0.2, -1.0];
    let sp = s.step(DT_NS, &vehicle_at(DT_NS, here, &q), None, None);
    assert!(sp.flags & setpoint_flags::STALE_MISSION != 0);
    assert_eq!(sp.flags & setpoint_flags::ARM_REQUEST, 0);
    assert_eq!(sp.shifted_position_ned_m, here);
    assert!(attitude(&sp).angle_to(&q) < 1e-9 && (sp.thrust_n - weight()).abs() < 1e-9);
    // The hold point is latched: moving away does not move it.
    let t = 2 * DT_NS;
    let old = mission(0, 0.0, mission_flags::ARM_REQUEST);
    let sp = s.step(
        t + 300_000_000,
        &vehicle_at(t, [1.0, 0.2, -1.0], &q),
        None,
        Some(&old),
    );
    assert_eq!(sp.nominal_position_ned_m, here);
    assert!(sp.flags & setpoint_flags::STALE_ODOMETRY != 0);
    assert!(sp.acceleration_desired_ned_m_s2[0] < 0.0);
    assert_eq!(s.counters().stale_mission_steps, 2);
}

#[test]
fn fields_carry_the_inputs() {
    let q = level(0.0);
    let ten = tension(DT_NS, &t_d(), &q);
    let sp = stage().step(
        2 * DT_NS,
        &vehicle_at(DT_NS + 1, OWN, &q),
        Some(&ten),
        Some(&mission(2 * DT_NS, 0.0, ON | mission_flags::ARM_REQUEST)),
    );
    assert_eq!(
        (
            sp.tension_sequence,
            sp.odometry_sequence,
            sp.mission_sequence
        ),
        (5, 7, 11)
    );
    // What a replay needs: the step's time and which inputs it was handed.
    assert_eq!(
        (
            sp.step_ns,
            sp.given_inputs,
            sp.given_tension_sequence,
            sp.given_mission_sequence
        ),
        (
            2 * DT_NS,
            given_inputs::ODOMETRY | given_inputs::TENSION | given_inputs::MISSION,
            5,
            11
        )
    );
    assert_eq!(
        (sp.header.t_origin_ns, sp.odometry_origin_ns),
        (DT_NS, DT_NS + 1)
    );
    assert_eq!(sp.phase, MissionPhase::Hold);
    assert!(sp.flags & setpoint_flags::ARM_REQUEST != 0);
    assert!((Vector3::from(sp.tension_filtered_ned_n) - t_d()).norm() < 1e-12);
    assert_eq!(Vector3::from(sp.tension_desired_ned_n), t_d());
}

#[test]
fn bad_parameters_name_the_key() {
    let mut c = ControllerConfig::default();
    c.k_p[2] = f64::NAN;
    let e = ControllerStage::new(&VehicleConfig::default(), &c).unwrap_err();
    assert!(e.to_string().contains("controller.k_p[2]"), "{e}");
    let c = ControllerConfig {
        max_thrust_n: 15.0,
        ..Default::default()
    };
    let e = ControllerStage::new(&VehicleConfig::default(), &c).unwrap_err();
    assert!(e.to_string().contains("controller.max_thrust_n"), "{e}");
}

#[path = "stage_limits_tests.rs"]
mod limits;
