use super::*;

const MS: u64 = 1_000_000;

fn resting(throttle: Option<f64>) -> LandInputs {
    LandInputs {
        armed: true,
        climb_rate_controlled: throttle.is_none(),
        in_descend: false,
        throttle,
        ground_contact_hint: true,
        velocity_ned: Vector3::zeros(),
        rate_frd: Vector3::zeros(),
        specific_force_frd: Vector3::new(0.0, 0.0, -9.81),
    }
}

/// A detector that has just seen the vehicle fly (all stages false) at t = 0.
fn airborne() -> LandDetector {
    let mut d = LandDetector::new(LandDetectorParams::default());
    let flying = LandInputs {
        ground_contact_hint: false,
        ..resting(Some(0.5))
    };
    d.update(0, &flying);
    d.update(10 * MS, &flying);
    assert!(!d.landed() && !d.maybe_landed() && !d.ground_contact());
    d
}

/// Feeds `input` every 10 ms from `from_ms` (inclusive) to `to_ms` (inclusive).
fn feed(d: &mut LandDetector, input: &LandInputs, from_ms: u64, to_ms: u64) {
    for t in (from_ms..=to_ms).step_by(10) {
        d.update(t * MS, input);
    }
}

#[test]
fn starts_landed_and_disarmed_reads_landed() {
    let mut d = LandDetector::new(LandDetectorParams::default());
    assert!(d.landed() && d.maybe_landed() && d.ground_contact() && !d.freefall());
    let disarmed = LandInputs {
        armed: false,
        ..resting(Some(0.9))
    };
    feed(&mut d, &disarmed, 0, 1000);
    assert!(d.landed());
}

#[test]
fn throttle_up_clears_landed_two_steps_later() {
    let mut d = LandDetector::new(LandDetectorParams::default());
    d.update(0, &resting(Some(0.5)));
    assert!(!d.ground_contact() && !d.maybe_landed());
    assert!(d.landed(), "landed reads the previous maybe-landed state");
    d.update(10 * MS, &resting(Some(0.5)));
    assert!(!d.landed());
}

#[test]
fn offboard_landing_takes_the_trigger_time_in_three_stages() {
    // Offboard: throttle known, not climb-rate controlled. Conditions hold from t = 20 ms.
    let mut d = airborne();
    let input = resting(Some(0.05));
    // Ground contact after 1/3 s: first step at or after 20 + 333.3 ms is 360 ms.
    feed(&mut d, &input, 20, 350);
    assert!(!d.ground_contact());
    feed(&mut d, &input, 360, 360);
    assert!(d.ground_contact());
    // Maybe landed is requested at 370 ms (reads ground contact one step late) -> 710 ms.
    feed(&mut d, &input, 370, 700);
    assert!(!d.maybe_landed());
    feed(&mut d, &input, 710, 710);
    assert!(d.maybe_landed());
    // Landed requested at 720 ms -> true at the first step >= 1053.3 ms: 1060 ms.
    feed(&mut d, &input, 720, 1050);
    assert!(!d.landed());
    feed(&mut d, &input, 1060, 1060);
    assert!(d.landed());
}

#[test]
fn movement_or_throttle_prevents_ground_contact() {
    let mut d = airborne();
    let sinking = LandInputs {
        velocity_ned: Vector3::new(0.0, 0.0, 0.3),
        ..resting(Some(0.05))
    };
    feed(&mut d, &sinking, 20, 2000);
    assert!(!d.ground_contact());
    let sliding = LandInputs {
        velocity_ned: Vector3::new(1.2, 1.2, 0.0),
        ..resting(Some(0.05))
    };
    feed(&mut d, &sliding, 2010, 4000);
    assert!(!d.ground_contact());
    // Just above the low-throttle level 0.12 + 0.38 * 0.3 = 0.234.
    feed(&mut d, &resting(Some(0.24)), 4010, 6000);
    assert!(!d.ground_contact());
    // Between the levels: ground contact, but maybe-landed needs <= 0.09 out of climb-rate control.
    feed(&mut d, &resting(Some(0.2)), 6010, 8000);
    assert!(d.ground_contact() && !d.maybe_landed());
}

#[test]
fn position_modes_use_the_hint_and_need_a_commanded_descent() {
    let mut d = airborne();
    let hold_on_ground = resting(None);
    feed(&mut d, &hold_on_ground, 20, 3000);
    assert!(!d.ground_contact(), "no descent commanded");
    let landing = LandInputs {
        in_descend: true,
        ..resting(None)
    };
    feed(&mut d, &landing, 3010, 4060);
    assert!(d.landed());
    let no_contact = LandInputs {
        ground_contact_hint: false,
        ..landing
    };
    feed(&mut d, &no_contact, 4070, 4080);
    assert!(!d.maybe_landed() && !d.landed());
}

#[test]
fn free_fall_after_0_3_s_blocks_maybe_landed() {
    let mut d = airborne();
    let falling = LandInputs {
        specific_force_frd: Vector3::new(0.0, 0.0, -0.5),
        ..resting(Some(0.0))
    };
    feed(&mut d, &falling, 20, 310);
    assert!(!d.freefall());
    feed(&mut d, &falling, 320, 2000);
    assert!(d.freefall());
    assert!(
        !d.maybe_landed(),
        "ground contact {} but free fall",
        d.ground_contact()
    );
}
