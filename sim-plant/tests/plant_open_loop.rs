//! Open loop through the whole emulated PX4 (commander, estimator, attitude and rate loops,
//! allocation, motor map) and the physics: a hover-thrust, level stream holds altitude within the
//! drift computed for it, a thrust offset gives the closed-form climb, and a tilt accelerates the
//! drone along its heading at g·tan(tilt).

use nalgebra::{UnitQuaternion, Vector3};
use sim_plant::mavlink_link::{px4_custom_mode, Inbound, MavResult, PX4_MAIN_MODE_OFFBOARD};
use sim_plant::plant::{Plant, PlantConfig};
use sim_plant::scenario::Scenario;

const G: f64 = 9.81;
const HOVER: f64 = 0.6;
const YAW: f64 = 30.0 * std::f64::consts::PI / 180.0;

fn plant() -> Plant {
    plant_with(PlantConfig {
        perturbation_enabled: false,
        ..PlantConfig::default()
    })
}

fn plant_with(cfg: PlantConfig) -> Plant {
    let text = include_str!("scenarios/hover-free.toml");
    let scenario = Scenario::from_toml_str("hover-free", text).unwrap();
    Plant::new(&scenario, &cfg).unwrap()
}

fn setpoint(t_ns: u64, q: UnitQuaternion<f64>, thrust: f64) -> Inbound {
    let q = q.into_inner();
    Inbound::AttitudeTarget {
        time_boot_ms: (t_ns / 1_000_000) as u32,
        q: [q.w as f32, q.i as f32, q.j as f32, q.k as f32],
        body_rates: [0.0; 3],
        thrust: thrust as f32,
        type_mask: 7,
        thrust_body: [0.0; 3],
    }
}

/// Runs `seconds` of plant time, streaming `q`/`thrust` to drone 0 at 50 Hz.
fn stream(p: &mut Plant, seconds: f64, q: UnitQuaternion<f64>, thrust: f64) {
    let end = p.time_ns() + (seconds * 1e9) as u64;
    while p.time_ns() < end {
        if p.time_ns().is_multiple_of(20_000_000) {
            p.handle(0, setpoint(p.time_ns(), q, thrust));
        }
        p.step();
    }
}

/// Streams a level hover for 1.2 s, then switches drone 0 (hovering in Position mode) to
/// offboard.
fn into_offboard(p: &mut Plant, thrust: f64) {
    let level = UnitQuaternion::from_euler_angles(0.0, 0.0, YAW);
    stream(p, 1.2, level, thrust);
    let r = p.handle(
        0,
        Inbound::Command {
            command: 176,
            params: [1.0, 6.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            from: (255, 190),
        },
    );
    assert_eq!(r, Some(MavResult::MAV_RESULT_ACCEPTED));
    stream(p, 0.01, level, thrust);
    assert_eq!(
        p.telemetry(0).custom_mode,
        px4_custom_mode(PX4_MAIN_MODE_OFFBOARD, 0)
    );
}

fn truth_z(p: &Plant) -> (f64, f64) {
    let b = &p.world().state().quads[0].body;
    (b.position_ned.z, b.velocity_ned.z)
}

/// Streams the hover throttle for 5 s after the switch and returns the largest deviation from
/// z(t) = z0 + v0 t, m.
fn hover_drift(mut p: Plant) -> f64 {
    into_offboard(&mut p, HOVER);
    // Let the switch transient pass (the attitude loop takes over from the position loop).
    let level = UnitQuaternion::from_euler_angles(0.0, 0.0, YAW);
    stream(&mut p, 0.5, level, HOVER);
    let (t0, (z0, v0)) = (p.time_ns(), truth_z(&p));
    let mut worst: f64 = 0.0;
    for _ in 0..10 {
        stream(&mut p, 0.5, level, HOVER);
        let t = (p.time_ns() - t0) as f64 * 1e-9;
        worst = worst.max((truth_z(&p).0 - (z0 + v0 * t)).abs());
    }
    assert_eq!(p.failsafe_count(), [0, 0]);
    worst
}

#[test]
fn hover_thrust_holds_altitude_within_the_computed_drift() {
    // Ideal IMU: the motor map gives exactly m g at the hover throttle, so the only drift is the
    // vertical speed left at the switch, z(t) = z0 + v0 t; allowed residual 1 cm over 5 s.
    let mut cfg = PlantConfig {
        perturbation_enabled: false,
        ..PlantConfig::default()
    };
    cfg.imu.accel_noise_std_mps2 = 0.0;
    cfg.imu.gyro_noise_std_radps = 0.0;
    let ideal = hover_drift(plant_with(cfg));
    assert!(
        ideal < 0.01,
        "ideal IMU: drift {ideal:.4} m beyond z0 + v0 t"
    );
    // Default IMU (gyro noise 0.005 rad/s): the rate loop turns gyro noise into zero-mean
    // rotor-speed noise (about ±0.5 rad/s), which the asymmetric motor lag (12.5 ms up, 25 ms
    // down) rectifies into a small mean excess thrust, measured at about 0.004 m/s². Bound:
    // 0.01 m/s², i.e. ½·0.01·5² = 0.125 m over 5 s.
    let noisy = hover_drift(plant());
    assert!(
        noisy < 0.125,
        "default IMU: drift {noisy:.4} m beyond z0 + v0 t"
    );
    println!(
        "hover drift beyond z0 + v0 t over 5 s: ideal IMU {ideal:.5} m, default IMU {noisy:.4} m"
    );
}

#[test]
fn thrust_offset_climbs_as_closed_form() {
    let mut p = plant();
    into_offboard(&mut p, HOVER);
    let level = UnitQuaternion::from_euler_angles(0.0, 0.0, YAW);
    stream(&mut p, 0.5, level, HOVER);
    let (z0, v0) = truth_z(&p);
    let thrust = 0.61;
    let a_up = G * (thrust / HOVER - 1.0);
    let secs = 2.0;
    stream(&mut p, secs, level, thrust);
    let (z, _) = truth_z(&p);
    let expect = z0 + v0 * secs - 0.5 * a_up * secs * secs;
    let climb = z0 + v0 * secs - z;
    let theory = 0.5 * a_up * secs * secs;
    // Motor lag (12.5 ms) delays the thrust change: a few per cent of the climb at most.
    assert!(
        (climb - theory).abs() < 0.03 * theory,
        "climbed {climb:.4} m, theory {theory:.4} m (z {z:.4} vs {expect:.4})"
    );
}

#[test]
fn tilt_accelerates_along_the_heading() {
    let mut p = plant();
    into_offboard(&mut p, HOVER);
    // Nose down by 5 degrees (negative pitch in FRD) at yaw 30 degrees; thrust raised by
    // 1/cos(tilt) so the vertical component still carries the weight.
    let tilt = 5.0_f64.to_radians();
    let q = UnitQuaternion::from_euler_angles(0.0, -tilt, YAW);
    stream(&mut p, 0.5, q, HOVER / tilt.cos());
    let v1 = p.world().state().quads[0].body.velocity_ned;
    stream(&mut p, 1.0, q, HOVER / tilt.cos());
    let v2 = p.world().state().quads[0].body.velocity_ned;
    let a = v2 - v1;
    let heading = Vector3::new(YAW.cos(), YAW.sin(), 0.0);
    let along = a.dot(&heading);
    let across = (a - heading * along).xy().norm();
    let theory = G * tilt.tan();
    assert!(
        (along - theory).abs() < 0.05 * theory,
        "acceleration along the heading {along:.3} m/s², theory {theory:.3}"
    );
    assert!(across < 0.05 * theory, "sideways {across:.3} m/s²");
    assert!(a.z.abs() < 0.05, "vertical {:.3} m/s²", a.z);
}
