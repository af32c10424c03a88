//! The sign of T checked in the plant: two ControllerStages fly sim-plant's Test B start (both
//! drones hovering 1 m apart, payload hanging) through the emulated PX4's offboard interface at
//! 100 Hz, fed the true cable pull at each anchor. With the crate's sign the formation holds
//! its setpoints and the measured T settles on T_d; with the sign flipped it does not.

use controller::{static_tension, ControllerStage};
use nalgebra::Vector3;
use rt_config::{ControllerConfig, VehicleConfig};
use shared_types::{
    mission_flags, vehicle_flags, AttitudeSetpoint, Header, MissionPhase, MissionSetpoint,
    TensionSample, VehicleState,
};
use sim_plant::estimator::ImuParams;
use sim_plant::mavlink_link::{
    px4_custom_mode, Inbound, MavResult, MAV_MODE_FLAG_SAFETY_ARMED, PX4_MAIN_MODE_OFFBOARD,
};
use sim_plant::plant::{Plant, PlantConfig};
use sim_plant::scenario::Scenario;

const PERIOD_NS: u64 = 10_000_000;
const HOVER_THROTTLE: f64 = 0.6;

/// What one flight did, from the switch to offboard on.
#[derive(Debug, Default)]
struct Flight {
    /// When both drones flew in offboard, s.
    offboard_at_s: f64,
    /// Distance of a drone from its nominal setpoint when the controllers took over (the sag
    /// PX4's own Position mode left during the 1.2 s handshake), m.
    error_at_switch_m: f64,
    /// Largest distance of a drone from its nominal setpoint, after the switch / last 4 s, m.
    max_error_m: f64,
    settled_error_m: f64,
    /// Largest |T − T_d| over the last 4 s (either drone), N, and |T_d| of each drone, N.
    settled_tension_error_n: f64,
    tension_desired_n: [f64; 2],
    /// Largest |T − T_d| at any time after the switch, N.
    max_tension_error_n: f64,
    non_finite: u64,
    crash_flags: [u32; 2],
}

fn header(t_ns: u64, sequence: u64) -> Header {
    Header {
        sequence,
        t_origin_ns: t_ns,
        t_publish_ns: t_ns,
    }
}

fn command(command: u16, p1: f32, p2: f32) -> Inbound {
    Inbound::Command {
        command,
        params: [p1, p2, 0.0, 0.0, 0.0, 0.0, 0.0],
        from: (255, 190),
    }
}

/// Flies `seconds` after the offboard switch. `sign` multiplies the measured pull (−1 flips
/// the convention); `drop_m(k, t_s)` lowers drone k's nominal setpoint (NED +z) at time t_s
/// after the switch.
fn fly(sign: f64, seconds: f64, drop_m: impl Fn(usize, f64) -> f64) -> Flight {
    let scenario = Scenario::load("test-b").unwrap();
    let cfg = PlantConfig {
        perturbation_enabled: false,
        imu: ImuParams::ideal(),
        ..Default::default()
    };
    let mut plant = Plant::new(&scenario, &cfg).unwrap();
    // The plant's gravity (its motor map normalises with 9.81).
    let vehicle = VehicleConfig {
        gravity_m_s2: 9.81,
        ..Default::default()
    };
    let stage = || ControllerStage::new(&vehicle, &ControllerConfig::default()).unwrap();
    let mut stages = [stage(), stage()];
    let start = [0, 1].map(|k| Vector3::from(scenario.drones[k].position_ned_m));
    let mut offboard_at: [Option<u64>; 2] = [None, None];
    let mut mode_requested = [false; 2];
    let mut flight = Flight::default();
    let mut next_ns = 0;
    let mut seq = 0;
    let end_ns = |t0: u64| t0 + (seconds * 1e9) as u64;
    loop {
        plant.step();
        let now = plant.time_ns();
        if now < next_ns {
            continue;
        }
        next_ns = now + PERIOD_NS;
        seq += 1;
        let both = match offboard_at {
            [Some(a), Some(b)] => Some(a.max(b)),
            _ => None,
        };
        if both.is_some_and(|t0| now > end_ns(t0)) {
            break;
        }
        let since_s = both.map_or(0.0, |t0| now.saturating_sub(t0) as f64 * 1e-9);
        let nominal = [0, 1].map(|k| start[k] + Vector3::new(0.0, 0.0, drop_m(k, since_s)));
        let truth = plant.truth();
        for k in 0..2 {
            let tel = plant.telemetry(k);
            let q = tel.attitude_body_to_ned;
            let armed = tel.base_mode & MAV_MODE_FLAG_SAFETY_ARMED != 0;
            let state = VehicleState {
                header: header(now, seq),
                px4_time_us: tel.time_boot_ns / 1000,
                position_ned_m: tel.position_ned_m.into(),
                velocity_ned_m_s: tel.velocity_ned_m_s.into(),
                attitude_wxyz: [q.w, q.i, q.j, q.k],
                rate_frd_rad_s: tel.body_rates_frd_rad_s.into(),
                custom_mode: tel.custom_mode,
                flags: if armed { vehicle_flags::ARMED } else { 0 },
            };
            let pull = Vector3::from(plant.anchor_force_frd(k)) * sign;
            let tension = TensionSample {
                header: header(now, seq),
                force_body_n: pull.into(),
                ..Default::default()
            };
            let mission = MissionSetpoint {
                header: header(now, seq),
                phase: MissionPhase::Hold,
                flags: mission_flags::TENSION_ENABLED | mission_flags::ARM_REQUEST,
                position_ned_m: nominal[k].into(),
                yaw_rad: scenario.yaw_rad(k),
                peer_position_ned_m: nominal[1 - k].into(),
                ..Default::default()
            };
            let sp = stages[k].step(now, &state, Some(&tension), Some(&mission));
            if std::env::var("PLANT_TRACE").is_ok() && seq % 20 == 0 {
                trace(now, k, &truth.drones[k].body.position_ned_m, &sp);
            }
            let throttle = HOVER_THROTTLE * (sp.thrust_n / vehicle.mass_kg) / vehicle.gravity_m_s2;
            let [w, x, y, z] = sp.attitude_wxyz;
            plant.handle(
                k,
                Inbound::AttitudeTarget {
                    time_boot_ms: (now / 1_000_000) as u32,
                    q: [w as f32, x as f32, y as f32, z as f32],
                    body_rates: [0.0; 3],
                    thrust: throttle as f32,
                    type_mask: 7,
                    thrust_body: [0.0; 3],
                },
            );
            // Handshake (the vehicle starts armed in Position mode): stream > 1 s, then offboard.
            let offboard = tel.custom_mode == px4_custom_mode(PX4_MAIN_MODE_OFFBOARD, 0);
            if offboard && armed && offboard_at[k].is_none() {
                offboard_at[k] = Some(now);
            } else if !mode_requested[k] && now >= 1_200_000_000 {
                let r = plant.handle(k, command(176, 1.0, 6.0));
                mode_requested[k] = r == Some(MavResult::MAV_RESULT_ACCEPTED);
            }
            let Some(t0) = both else { continue };
            // Measure against the truth: position of the body, T from the true pull (unflipped).
            let p = Vector3::from(truth.drones[k].body.position_ned_m);
            let error = (p - nominal[k]).norm();
            let t_true = -(q * Vector3::from(plant.anchor_force_frd(k)));
            let t_d = Vector3::from(
                static_tension(&nominal[k].into(), &nominal[1 - k].into(), &vehicle).own_ned_n,
            );
            let t_err = (t_true - t_d).norm();
            if now == t0 || flight.offboard_at_s == 0.0 {
                flight.error_at_switch_m = flight.error_at_switch_m.max(error);
            }
            flight.max_error_m = flight.max_error_m.max(error);
            flight.max_tension_error_n = flight.max_tension_error_n.max(t_err);
            if now + 4_000_000_000 > end_ns(t0) {
                flight.settled_error_m = flight.settled_error_m.max(error);
                flight.settled_tension_error_n = flight.settled_tension_error_n.max(t_err);
                flight.tension_desired_n[k] = t_d.norm();
            }
        }
        if let (Some(t0), 0.0) = (both, flight.offboard_at_s) {
            flight.offboard_at_s = t0 as f64 * 1e-9;
        }
    }
    flight.non_finite = stages.iter().map(|s| s.counters().non_finite_inputs).sum();
    flight.crash_flags = plant.crash_flags();
    flight
}

/// PLANT_TRACE=1: one line per drone every 0.2 s.
fn trace(now_ns: u64, k: usize, position: &[f64; 3], sp: &AttitudeSetpoint) {
    let v = |a: &[f64; 3]| format!("[{:.3} {:.3} {:.3}]", a[0], a[1], a[2]);
    let shift = Vector3::from(sp.shifted_position_ned_m) - Vector3::from(sp.nominal_position_ned_m);
    eprintln!(
        "t {:.2} k {k} pos {} shift {} T_f {} T_d {} a_d {} u {:.2} flags {:x}",
        now_ns as f64 * 1e-9,
        v(position),
        v(&shift.into()),
        v(&sp.tension_filtered_ned_n),
        v(&sp.tension_desired_ned_n),
        v(&sp.acceleration_desired_ned_m_s2),
        sp.thrust_n,
        sp.flags
    );
}

#[test]
fn the_sign_holds_the_formation_and_the_flipped_sign_does_not() {
    let right = fly(1.0, 12.0, |_, _| 0.0);
    let flipped = fly(-1.0, 12.0, |_, _| 0.0);
    eprintln!("right sign:   {right:?}");
    eprintln!("flipped sign: {flipped:?}");
    assert_eq!((right.non_finite, right.crash_flags), (0, [0, 0]));
    assert!(right.offboard_at_s > 1.2 && right.offboard_at_s < 2.0);
    // Right sign: within 3 cm of the setpoints and T within 0.25 N (5 %) of T_d once settled.
    assert!(right.settled_error_m < 0.03, "{right:?}");
    assert!(right.settled_tension_error_n < 0.25, "{right:?}");
    // Flipped: the tension loop walks the setpoints off to its 0.5 m bound.
    assert!(flipped.settled_error_m > 0.3, "{flipped:?}");
    assert!(flipped.settled_error_m > 10.0 * right.settled_error_m);
    assert!(flipped.settled_tension_error_n > 1.0, "{flipped:?}");
    assert!(flipped.settled_tension_error_n > 10.0 * right.settled_tension_error_n);
}

/// A step in the formation: drone 0's setpoint drops 5 cm at 2 s, so T_d redistributes (the
/// higher drone 1 takes 6.2 N of vertical load instead of 4.9 N); the measured T follows T_d.
#[test]
fn a_height_step_redistributes_the_tension_as_t_d_says() {
    let f = fly(
        1.0,
        14.0,
        |k, t| if k == 0 && t >= 2.0 { 0.05 } else { 0.0 },
    );
    eprintln!("height step: {f:?}");
    assert_eq!((f.non_finite, f.crash_flags), (0, [0, 0]));
    assert!(f.settled_error_m < 0.05, "{f:?}");
    assert!(f.settled_tension_error_n < 0.3, "{f:?}");
}
