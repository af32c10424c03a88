use super::*;

const T: u64 = 42;

fn msg(type_mask: u8) -> AttitudeTarget {
    // 0.2 rad roll as (w, x, y, z).
    let (s, c) = (0.1f32.sin(), 0.1f32.cos());
    AttitudeTarget {
        q: [c, s, 0.0, 0.0],
        body_rates: [0.1, -0.2, 0.3],
        thrust: 0.6,
        type_mask,
        thrust_body: [0.1, 0.0, -0.45],
    }
}

fn setpoint(m: &AttitudeTarget) -> (OffboardControlFlags, ControlDemand) {
    match interpret(m, T) {
        Interpretation::Setpoint(f, d) => (f, d),
        other => panic!("expected a setpoint, got {other:?}"),
    }
}

fn attitude_parts(d: ControlDemand) -> (UnitQuaternion<f64>, f64, f64, Option<RateInjection>) {
    match d {
        ControlDemand::Attitude {
            q_sp,
            thrust,
            yaw_rate_ff,
            rate_injection,
        } => (q_sp, thrust, yaw_rate_ff, rate_injection),
        other => panic!("expected attitude, got {other:?}"),
    }
}

#[test]
fn mask_7_is_attitude_and_thrust_only() {
    let (flags, d) = setpoint(&msg(7));
    assert_eq!(
        flags,
        OffboardControlFlags {
            attitude: true,
            body_rate: false
        }
    );
    let (q, thrust, ff, inj) = attitude_parts(d);
    assert!((q.euler_angles().0 - 0.2).abs() < 1e-6);
    assert!((thrust - 0.6).abs() < 1e-7);
    assert_eq!(ff, 0.0);
    assert!(inj.is_none());
}

#[test]
fn clearing_bits_1_and_2_also_makes_a_rate_setpoint() {
    // Mask 0: attitude wins the control mode, the rates are injected, yaw rate is feed-forward.
    let (flags, d) = setpoint(&msg(0));
    assert_eq!(
        flags,
        OffboardControlFlags {
            attitude: true,
            body_rate: true
        }
    );
    let (_, thrust, ff, inj) = attitude_parts(d);
    let inj = inj.expect("rates reach the rate controller too");
    assert!((inj.rates_frd - Vector3::new(0.1, -0.2, 0.3)).norm() < 1e-6);
    assert!((inj.thrust - thrust).abs() < 1e-12);
    assert_eq!(inj.t_ns, T);
    assert!((ff - 0.3).abs() < 1e-6);
    // Mask 4 (yaw ignored only) still has roll and pitch rates: injection with a NaN yaw.
    let (flags, d) = setpoint(&msg(4));
    assert!(flags.body_rate);
    let (_, _, ff, inj) = attitude_parts(d);
    assert_eq!(ff, 0.0);
    assert!(inj.unwrap().rates_frd.z.is_nan());
    // Ignoring only the roll rate (mask 1) is enough to drop the rate setpoint.
    let (flags, d) = setpoint(&msg(1));
    assert!(!flags.body_rate);
    assert!(attitude_parts(d).3.is_none());
}

#[test]
fn attitude_ignored_gives_rates_or_nothing() {
    let (flags, d) = setpoint(&msg(128));
    assert_eq!(
        flags,
        OffboardControlFlags {
            attitude: false,
            body_rate: true
        }
    );
    match d {
        ControlDemand::Rates { rates_frd, thrust } => {
            assert!((rates_frd - Vector3::new(0.1, -0.2, 0.3)).norm() < 1e-6);
            assert!((thrust - 0.6).abs() < 1e-7);
        }
        other => panic!("{other:?}"),
    }
    match setpoint(&msg(128 | 4)).1 {
        ControlDemand::Rates { rates_frd, .. } => assert!(rates_frd.z.is_nan()),
        other => panic!("{other:?}"),
    }
    // The rates branch does not honour thrust_body: thrust comes from `thrust`.
    assert_eq!(
        setpoint(&msg(128 | 32))
            .1
            .thrust()
            .map(|t| (t * 10.0).round()),
        Some(6.0)
    );
    assert_eq!(setpoint(&msg(128 | 64)).1.thrust(), Some(0.0));
    assert_eq!(
        interpret(&msg(128 | 1 | 2), T),
        Interpretation::NoProofOfLife
    );
    assert_eq!(
        interpret(&msg(128 | 2 | 4), T),
        Interpretation::NoProofOfLife
    );
}

#[test]
fn thrust_sources_and_limits() {
    assert_eq!(
        setpoint(&msg(7 | 64)).1.thrust(),
        Some(0.0),
        "ignored throttle is zero"
    );
    let t = setpoint(&msg(7 | 32)).1.thrust().unwrap();
    assert!((t - 0.45).abs() < 1e-7, "thrust_body z, negated");
    let mut m = msg(7);
    m.thrust = 1.5;
    assert_eq!(setpoint(&m).1.thrust(), Some(1.0));
    m.thrust = -0.2;
    assert_eq!(setpoint(&m).1.thrust(), Some(0.0));
    m.thrust = f32::NAN;
    m.type_mask = 7 | 64;
    assert_eq!(
        setpoint(&m).1.thrust(),
        Some(0.0),
        "NaN thrust is fine when ignored"
    );
}

#[test]
fn invalid_messages_are_rejected_but_keep_proof_of_life() {
    let flags = OffboardControlFlags {
        attitude: true,
        body_rate: false,
    };
    let mut m = msg(7);
    m.q = [f32::NAN, 0.0, 0.0, 0.0];
    assert_eq!(interpret(&m, T), Interpretation::Invalid(flags));
    m.q = [0.0; 4];
    assert_eq!(interpret(&m, T), Interpretation::Invalid(flags));
    let mut m = msg(7);
    m.thrust = f32::INFINITY;
    assert_eq!(interpret(&m, T), Interpretation::Invalid(flags));
    let mut m = msg(7 | 32);
    m.thrust_body[2] = f32::NAN;
    assert_eq!(interpret(&m, T), Interpretation::Invalid(flags));
    let mut m = msg(128);
    m.body_rates[0] = f32::NAN;
    let rate_flags = OffboardControlFlags {
        attitude: false,
        body_rate: true,
    };
    assert_eq!(interpret(&m, T), Interpretation::Invalid(rate_flags));
    // A NaN yaw rate is fine when bit 4 ignores it.
    m.body_rates = [0.0, 0.0, f32::NAN];
    m.type_mask = 128 | 4;
    assert!(matches!(interpret(&m, T), Interpretation::Setpoint(..)));
}

#[test]
fn non_unit_quaternion_is_normalised() {
    let mut m = msg(7);
    m.q = [2.0, 0.0, 0.0, 0.0];
    let (q, ..) = attitude_parts(setpoint(&m).1);
    assert!(q.angle() < 1e-12);
    assert!((q.quaternion().norm() - 1.0).abs() < 1e-12);
}
