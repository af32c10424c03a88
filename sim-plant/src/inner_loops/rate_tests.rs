use super::*;

const DT: f64 = 0.0025;

fn no_yaw_filter() -> RateControlParams {
    RateControlParams {
        yaw_torque_cutoff_hz: 0.0,
        ..RateControlParams::default()
    }
}

#[test]
fn first_step_is_the_hand_computed_p_term() {
    let mut rc = RateControl::new(&no_yaw_filter()).unwrap();
    let sp = Vector3::new(1.0, -0.5, 0.8);
    let t = rc.update(DT, &Vector3::zeros(), &sp, false).unwrap();
    // Integrator starts at 0 and is updated after the output; no acceleration yet.
    assert!((t.x - 0.15).abs() < 1e-12, "{t:?}");
    assert!((t.y + 0.075).abs() < 1e-12, "{t:?}");
    assert!((t.z - 0.16).abs() < 1e-12, "{t:?}");

    // With PX4's 2 Hz yaw torque filter the first yaw output is alpha * 0.16.
    let mut rc = RateControl::new(&RateControlParams::default()).unwrap();
    let t = rc.update(DT, &Vector3::zeros(), &sp, false).unwrap();
    let tau = 1.0 / (2.0 * std::f64::consts::PI * 2.0);
    assert!((t.z - 0.16 * DT / (tau + DT)).abs() < 1e-12, "{t:?}");
}

#[test]
fn integrator_grows_with_i_gain_and_clamps_at_limit() {
    let mut rc = RateControl::new(&RateControlParams::default()).unwrap();
    let sp = Vector3::new(1.0, 0.0, 0.0);
    for _ in 0..400 {
        rc.update(DT, &Vector3::zeros(), &sp, false).unwrap();
    }
    // 1 s at 1 rad/s error: 0.2 * i_factor * 1, i_factor = 1 - (1 / 6.981)^2.
    let i_factor = 1.0 - (1.0 / I_FADE_RATE_RAD_S).powi(2);
    assert!(
        (rc.integral().x - 0.2 * i_factor).abs() < 1e-9,
        "{}",
        rc.integral().x
    );
    for _ in 0..4000 {
        rc.update(DT, &Vector3::zeros(), &sp, false).unwrap();
    }
    assert_eq!(rc.integral().x, 0.3);
    // Output = P + I = 0.15 + 0.3 (not clamped below 1).
    let t = rc.update(DT, &Vector3::zeros(), &sp, false).unwrap();
    assert!((t.x - 0.45).abs() < 1e-12, "{t:?}");
    rc.reset_integral();
    assert_eq!(rc.integral(), Vector3::zeros());
}

#[test]
fn landed_freezes_and_saturation_blocks_the_integrator() {
    let mut rc = RateControl::new(&RateControlParams::default()).unwrap();
    let sp = Vector3::new(1.0, 1.0, 0.0);
    for _ in 0..100 {
        rc.update(DT, &Vector3::zeros(), &sp, true).unwrap();
    }
    assert_eq!(rc.integral(), Vector3::zeros());

    // Roll saturated positive: a positive error must not wind it up; pitch free.
    rc.set_saturation([true, false, false], [false; 3]);
    for _ in 0..100 {
        rc.update(DT, &Vector3::zeros(), &sp, false).unwrap();
    }
    assert_eq!(rc.integral().x, 0.0);
    assert!(rc.integral().y > 0.04);
    // A negative error still unwinds it.
    let sp_neg = Vector3::new(-1.0, 0.0, 0.0);
    rc.update(DT, &Vector3::zeros(), &sp_neg, false).unwrap();
    assert!(rc.integral().x < 0.0);
    // Negative saturation blocks negative errors.
    rc.set_saturation([false; 3], [true, false, false]);
    let before = rc.integral().x;
    rc.update(DT, &Vector3::zeros(), &sp_neg, false).unwrap();
    assert_eq!(rc.integral().x, before);
}

#[test]
fn setpoint_step_gives_no_derivative_kick() {
    let params = RateControlParams {
        i: [0.0; 3],
        ..no_yaw_filter()
    };
    let mut rc = RateControl::new(&params).unwrap();
    let meas = Vector3::new(0.3, -0.2, 0.1);
    let mut before = Vector3::zeros();
    for _ in 0..400 {
        before = rc.update(DT, &meas, &Vector3::zeros(), false).unwrap();
    }
    let sp = Vector3::new(1.0, 1.0, 1.0);
    let after = rc.update(DT, &meas, &sp, false).unwrap();
    let jump = after - before;
    assert!((jump.x - 0.15).abs() < 1e-12, "{jump:?}");
    assert!((jump.y - 0.15).abs() < 1e-12, "{jump:?}");
    assert!((jump.z - 0.2).abs() < 1e-12, "{jump:?}");
}

#[test]
fn d_term_acts_on_measured_angular_acceleration() {
    let params = RateControlParams {
        i: [0.0; 3],
        ..no_yaw_filter()
    };
    let mut rc = RateControl::new(&params).unwrap();
    let accel = 2.0; // rad/s^2 on roll: rate stays below the output clamp
    let mut t = Vector3::zeros();
    for k in 0..400 {
        let meas = Vector3::new(accel * k as f64 * DT, 0.0, 0.0);
        t = rc.update(DT, &meas, &Vector3::zeros(), false).unwrap();
    }
    assert!((rc.angular_accel_frd().x - accel).abs() < 1e-6);
    let expected = -0.15 * rc.filtered_rate_frd().x - 0.003 * accel;
    assert!((t.x - expected).abs() < 1e-8, "{} vs {expected}", t.x);
    // The 40 Hz Butterworth delays a ramp by sqrt(2) / (2 pi 40) = 5.6 ms.
    let lag = (accel * 399.0 * DT - rc.filtered_rate_frd().x) / accel;
    assert!(
        (lag - 2f64.sqrt() / (2.0 * std::f64::consts::PI * 40.0)).abs() < 0.3e-3,
        "{lag}"
    );
}

#[test]
fn output_is_clamped_and_bad_inputs_rejected() {
    let mut rc = RateControl::new(&no_yaw_filter()).unwrap();
    let t = rc
        .update(
            DT,
            &Vector3::zeros(),
            &Vector3::new(20.0, -20.0, 0.0),
            false,
        )
        .unwrap();
    assert_eq!((t.x, t.y), (1.0, -1.0));
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    assert_eq!(
        rc.update(DT, &nan, &Vector3::zeros(), false),
        Err(StepError::NonFinite { name: "rate_frd" })
    );
    assert_eq!(
        rc.update(0.0, &Vector3::zeros(), &Vector3::zeros(), false),
        Err(StepError::InvalidDt { dt: 0.0 })
    );
    let p = RateControlParams {
        p: [0.1, -1.0, 0.1],
        ..RateControlParams::default()
    };
    assert_eq!(RateControl::new(&p).unwrap_err().key, "rate.p");
}
