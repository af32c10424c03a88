use super::*;
use crate::mapping::level;
use rt_config::{ControllerConfig, VehicleConfig};

const G: f64 = 9.80665;

fn params() -> MappingParams {
    let v = VehicleConfig::default();
    let c = ControllerConfig::default();
    MappingParams {
        mass_kg: v.mass_kg,
        gravity_m_s2: v.gravity_m_s2,
        max_tilt_rad: c.max_tilt_deg.to_radians(),
        min_thrust_n: c.min_thrust_n,
        max_thrust_n: c.max_thrust_n,
    }
}

fn gains() -> GeometricGains {
    let c = ControllerConfig::default().geometric;
    GeometricGains {
        kp: c.kp.into(),
        kv: c.kv.into(),
    }
}

fn at_rest_reference(position: [f64; 3], yaw: f64) -> Reference {
    Reference {
        position_m: position.into(),
        velocity_m_s: Vector3::zeros(),
        acceleration_m_s2: Vector3::zeros(),
        yaw_rad: yaw,
    }
}

/// Thrust direction (−body z) of a command, NED.
fn thrust_dir(c: &GeometricCommand) -> Vector3<f64> {
    -(c.mapped.attitude * Vector3::z())
}

fn run(reference: &Reference, f_ext: [f64; 3], current: &UnitQuaternion<f64>) -> GeometricCommand {
    command(
        &gains(),
        reference,
        &Vector3::new(0.0, 0.0, -2.0),
        &Vector3::zeros(),
        &f_ext.into(),
        current,
        &params(),
    )
}

#[test]
fn hanging_load_straight_down_gives_level_and_weight_plus_load() {
    let m = params().mass_kg;
    let yaw = 0.4;
    let c = run(
        &at_rest_reference([0.0, 0.0, -2.0], yaw),
        [0.0, 0.0, 5.0],
        &level(yaw),
    );
    assert!(
        (c.mapped.thrust_n - (m * G + 5.0)).abs() < 1e-9,
        "{}",
        c.mapped.thrust_n
    );
    assert!(c.mapped.attitude.angle_to(&level(yaw)) < 1e-12);
    assert_eq!(c.mapped.thrust_limit, ThrustLimit::None);
    assert_eq!(c.tracking_m_s2, Vector3::zeros());
}

#[test]
fn lateral_pull_is_cancelled_by_tilting_against_it() {
    // A 2 N pull north: the thrust must lean south by atan(2 / m g) and supply |F|.
    let m = params().mass_kg;
    let r = at_rest_reference([0.0, 0.0, -2.0], 0.0);
    let c = run(&r, [2.0, 0.0, 0.0], &level(0.0));
    let d = thrust_dir(&c);
    let tilt = (-d.x).atan2(-d.z);
    assert!((tilt - (2.0 / (m * G)).atan()).abs() < 1e-12, "tilt {tilt}");
    assert!(d.y.abs() < 1e-12);
    // Level now: the projection on the current thrust axis is m g; once tilted, |F|.
    assert!((c.mapped.thrust_n - m * G).abs() < 1e-9);
    let tilted = run(&r, [2.0, 0.0, 0.0], &c.mapped.attitude);
    let norm = (4.0 + (m * G).powi(2)).sqrt();
    assert!((tilted.mapped.thrust_n - norm).abs() < 1e-9);
    // The net horizontal force on the drone: thrust's + the pull = 0.
    assert!((tilted.mapped.thrust_n * thrust_dir(&tilted).x + 2.0).abs() < 1e-9);
}

#[test]
fn position_error_alone_tilts_towards_the_setpoint() {
    // 1 m north of the drone: a = kp_x · 1 = 2.16 m/s² north, pitch forward atan(2.16 / g).
    let r = at_rest_reference([1.0, 0.0, -2.0], 0.0);
    let c = run(&r, [0.0; 3], &level(0.0));
    assert!((c.tracking_m_s2 - Vector3::new(2.16, 0.0, 0.0)).norm() < 1e-12);
    let d = thrust_dir(&c);
    let tilt = d.x.atan2(-d.z);
    assert!((tilt - (2.16 / G).atan()).abs() < 1e-12, "tilt {tilt}");
    // Body x still points north-ish (yaw 0), nose down: body x has a positive down component.
    let x = c.mapped.attitude * Vector3::x();
    assert!(x.x > 0.9 && x.z > 0.0);
    // 1 m too low (z error −1 m): kp_z = 4.2 more upwards.
    let r = at_rest_reference([0.0, 0.0, -3.0], 0.0);
    let c = run(&r, [0.0; 3], &level(0.0));
    let m = params().mass_kg;
    assert!((c.mapped.thrust_n - m * (G + 4.2)).abs() < 1e-9);
}

#[test]
fn acceleration_feed_forward_and_velocity_error_enter_directly() {
    let m = params().mass_kg;
    let mut r = at_rest_reference([0.0, 0.0, -2.0], 0.0);
    r.acceleration_m_s2 = Vector3::new(0.0, 1.0, -0.5);
    let c = run(&r, [0.0; 3], &level(0.0));
    let d = thrust_dir(&c);
    // Roll right (thrust towards east) by atan(1 / (g + 0.5)).
    assert!((d.y.atan2(-d.z) - (1.0 / (G + 0.5)).atan()).abs() < 1e-12);
    assert!((c.mapped.thrust_n - m * (G + 0.5)).abs() < 1e-9);
    // v_ref − v = (0.2, 0, 0) with kv_x = 2.7: 0.54 m/s² north.
    let mut r = at_rest_reference([0.0, 0.0, -2.0], 0.0);
    r.velocity_m_s = Vector3::new(0.2, 0.0, 0.0);
    let c = run(&r, [0.0; 3], &level(0.0));
    assert!((c.tracking_m_s2.x - 0.54).abs() < 1e-12);
}

#[test]
fn limits_are_the_mappings() {
    // 10 m away: the tilt is limited to 35°, the vertical kept.
    let r = at_rest_reference([10.0, 0.0, -2.0], 0.0);
    let c = run(&r, [0.0; 3], &level(0.0));
    assert!(c.mapped.tilt_limited);
    let d = thrust_dir(&c);
    assert!((d.x.atan2(-d.z).to_degrees() - 35.0).abs() < 1e-9);
    // A 40 N pull down: above max thrust.
    let r = at_rest_reference([0.0, 0.0, -2.0], 0.0);
    let c = run(&r, [0.0, 0.0, 40.0], &level(0.0));
    assert_eq!(c.mapped.thrust_limit, ThrustLimit::Max);
    assert_eq!(c.mapped.thrust_n, params().max_thrust_n);
    // Pulled up by 30 N: the rotors cannot push down; minimum thrust, flagged.
    let c = run(&r, [0.0, 0.0, -30.0], &level(0.0));
    assert_eq!(c.mapped.thrust_limit, ThrustLimit::Min);
    assert_eq!(c.mapped.thrust_n, params().min_thrust_n);
}
