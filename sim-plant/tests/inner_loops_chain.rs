//! The chained inner loops: configuration, holding on bad input, landed behaviour.

use nalgebra::{UnitQuaternion, Vector3};
use sim_plant::inner_loops::{
    Airmode, InnerLoopParams, MultirotorInnerLoops, StepError, TrajectorySetpoint, VehicleState,
};

const DT: f64 = 0.0025;

fn level_state() -> VehicleState {
    VehicleState {
        attitude: UnitQuaternion::identity(),
        rates_frd_rad_s: Vector3::zeros(),
        position_ned_m: Vector3::zeros(),
        velocity_ned_m_s: Vector3::zeros(),
    }
}

#[test]
fn params_parse_partially_and_reject_unknown_keys() {
    let p: InnerLoopParams = toml::from_str(
        "[attitude]\nroll_p = 5.0\n[allocation]\nairmode = \"roll_pitch_yaw\"\n\
         [position]\nhover_throttle = 0.55\n",
    )
    .unwrap();
    assert_eq!(p.attitude.roll_p, 5.0);
    assert_eq!(p.attitude.pitch_p, 6.5);
    assert_eq!(p.allocation.airmode, Airmode::RollPitchYaw);
    assert_eq!(p.position.hover_throttle, 0.55);
    assert_eq!(p.rate.p, [0.15, 0.15, 0.2]);
    assert!(toml::from_str::<InnerLoopParams>("[rate]\nkp = 1.0\n").is_err());
    let mut bad = InnerLoopParams::default();
    bad.rate.gyro_cutoff_hz = f64::NAN;
    assert_eq!(
        MultirotorInnerLoops::new(&bad).unwrap_err().key,
        "rate.gyro_cutoff_hz"
    );
}

#[test]
fn level_hover_gives_equal_hover_speeds() {
    let mut c = MultirotorInnerLoops::new(&InnerLoopParams::default()).unwrap();
    let w = c.update_attitude(DT, &level_state(), &UnitQuaternion::identity(), 0.6);
    let hover = (2.064 * 9.81 / 4.0 / 8.54858e-6f64).sqrt();
    for wi in w {
        assert!((wi - hover).abs() < 1e-9, "{w:?}");
    }
    let w = c.update_rates(DT, &level_state(), &Vector3::zeros(), 0.6);
    assert!(w.iter().all(|wi| (wi - hover).abs() < 1e-9));
}

#[test]
fn bad_input_holds_the_previous_command_and_is_counted() {
    let mut c = MultirotorInnerLoops::new(&InnerLoopParams::default()).unwrap();
    let good = c.update_rates(DT, &level_state(), &Vector3::new(0.5, 0.0, 0.0), 0.5);
    let mut bad_state = level_state();
    bad_state.rates_frd_rad_s.x = f64::NAN;
    let held = c.update_rates(DT, &bad_state, &Vector3::zeros(), 0.5);
    assert_eq!(held, good);
    let held = c.update_attitude(f64::NAN, &level_state(), &UnitQuaternion::identity(), 0.5);
    assert_eq!(held, good);
    let held = c.update_position(DT, &level_state(), &TrajectorySetpoint::empty());
    assert_eq!(held, good);
    assert_eq!(c.rejected_steps(), 3);
    assert!(matches!(
        c.last_error(),
        Some(StepError::InvalidSetpoint { .. })
    ));
}

#[test]
fn landed_idles_the_motors_and_freezes_integrators() {
    let mut c = MultirotorInnerLoops::new(&InnerLoopParams::default()).unwrap();
    c.set_landed(true);
    let sp = TrajectorySetpoint::position(Vector3::new(0.0, 0.0, -2.0), 0.0);
    let mut state = level_state();
    state.rates_frd_rad_s = Vector3::new(0.2, 0.0, 0.0); // rocking on the ground
    let mut w = [0.0; 4];
    for _ in 0..400 {
        w = c.update_position(DT, &state, &sp);
    }
    assert_eq!(c.rate_integral(), Vector3::zeros());
    assert_eq!(c.velocity_integral(), Vector3::zeros());
    assert!((c.status().thrust - 1e-3).abs() < 1e-12);
    // Minimal thrust: roll is cut back by the allocation (no airmode), motors near zero.
    assert!(w.iter().all(|wi| *wi < 60.0), "{w:?}");
    c.set_landed(false);
    c.update_position(DT, &level_state(), &sp);
    assert!(
        c.status().thrust > 0.6,
        "climbing to -2 m: {}",
        c.status().thrust
    );
}
