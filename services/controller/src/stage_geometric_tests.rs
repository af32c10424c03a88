//! The geometric law through the stage: the same checks, flags and fields as the cascade.

use nalgebra::{UnitQuaternion, Vector3};
use rt_config::{ControllerConfig, ControllerLaw, VehicleConfig};
use shared_types::{
    mission_flags, setpoint_flags, vehicle_flags, Header, MissionPhase, MissionSetpoint,
    TensionSample, VehicleState,
};

use crate::mapping::level;
use crate::ControllerStage;

const DT_NS: u64 = 10_000_000;
const AT: [f64; 3] = [0.0, 0.0, -2.0];

fn stage() -> ControllerStage {
    let cfg = ControllerConfig {
        law: ControllerLaw::Geometric,
        ..Default::default()
    };
    ControllerStage::new(&VehicleConfig::default(), &cfg).unwrap()
}

fn header(t_ns: u64) -> Header {
    Header {
        sequence: t_ns / DT_NS,
        t_origin_ns: t_ns,
        t_publish_ns: t_ns,
    }
}

fn vehicle(t_ns: u64, q: &UnitQuaternion<f64>) -> VehicleState {
    VehicleState {
        header: header(t_ns),
        position_ned_m: AT,
        attitude_wxyz: [q.w, q.i, q.j, q.k],
        flags: vehicle_flags::ARMED,
        ..Default::default()
    }
}

fn mission(t_ns: u64, flags: u32) -> MissionSetpoint {
    MissionSetpoint {
        header: header(t_ns),
        phase: MissionPhase::Hold,
        flags,
        position_ned_m: AT,
        peer_position_ned_m: [0.0, 1.0, -2.0],
        ..Default::default()
    }
}

fn load(t_ns: u64, frd: [f64; 3]) -> TensionSample {
    TensionSample {
        header: header(t_ns),
        force_body_n: frd,
        ..Default::default()
    }
}

fn weight() -> f64 {
    let v = VehicleConfig::default();
    v.mass_kg * v.gravity_m_s2
}

#[test]
fn compensates_a_hanging_load_while_the_loop_is_on_and_holds_it_while_stale() {
    let q = level(0.3);
    let mut s = stage();
    let on = mission_flags::TENSION_ENABLED;
    let t0 = 100 * DT_NS;
    let mut m = mission(t0, on);
    m.yaw_rad = 0.3;
    let sp = s.step(
        t0,
        &vehicle(t0, &q),
        Some(&load(t0, [0.0, 0.0, 5.0])),
        Some(&m),
    );
    assert!(
        (sp.thrust_n - (weight() + 5.0)).abs() < 1e-9,
        "{}",
        sp.thrust_n
    );
    assert_ne!(sp.flags & setpoint_flags::GEOMETRIC, 0);
    assert_eq!(sp.flags & setpoint_flags::POSITION_ONLY, 0);
    assert_eq!(sp.tension_origin_ns, t0);
    assert_eq!(sp.header.t_origin_ns, t0);
    assert_eq!(sp.shifted_position_ned_m, AT);
    assert_eq!(
        Vector3::from(sp.tension_filtered_ned_n),
        Vector3::new(0.0, 0.0, -5.0)
    );
    // The tension goes stale (sample 1 s old): T_f held, POSITION_ONLY.
    let t = 200 * DT_NS;
    let mut m = mission(t, on);
    m.yaw_rad = 0.3;
    let sp = s.step(
        t,
        &vehicle(t, &q),
        Some(&load(t0, [0.0, 0.0, 5.0])),
        Some(&m),
    );
    assert!((sp.thrust_n - (weight() + 5.0)).abs() < 1e-9);
    assert_ne!(sp.flags & setpoint_flags::POSITION_ONLY, 0);
    assert_eq!(sp.tension_origin_ns, 0);
    // Loop off: no compensation.
    let t = 201 * DT_NS;
    let mut m = mission(t, 0);
    m.yaw_rad = 0.3;
    let sp = s.step(
        t,
        &vehicle(t, &q),
        Some(&load(t, [0.0, 0.0, 5.0])),
        Some(&m),
    );
    assert!((sp.thrust_n - weight()).abs() < 1e-9);
    assert!(sp
        .attitude_wxyz
        .iter()
        .zip([q.w, q.i, q.j, q.k])
        .all(|(a, b)| (a - b).abs() < 1e-12));
}

#[test]
fn filters_the_force_like_the_proposed_law() {
    // A step of the pull from 0 to 5 N: after one 10 ms step T_f has moved by
    // 1 − exp(−2π · 10 Hz · 0.01 s) = 46.6 % of it.
    let q = level(0.0);
    let mut s = stage();
    let on = mission_flags::TENSION_ENABLED;
    s.step(
        0,
        &vehicle(0, &q),
        Some(&load(0, [0.0; 3])),
        Some(&mission(0, on)),
    );
    let t = DT_NS;
    let sp = s.step(
        t,
        &vehicle(t, &q),
        Some(&load(t, [0.0, 0.0, 5.0])),
        Some(&mission(t, on)),
    );
    let alpha = 1.0 - (-2.0 * std::f64::consts::PI * 0.1f64).exp();
    assert!(
        (sp.thrust_n - (weight() + 5.0 * alpha)).abs() < 1e-9,
        "{}",
        sp.thrust_n
    );
}
