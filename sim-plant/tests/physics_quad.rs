//! A free quad against closed form: hover, roll and yaw torque signs and magnitudes, motor
//! lag, resting on the ground. The payload sits on the ground with slack cables.
//! Run with `--nocapture` to see the numbers.

use nalgebra::Vector3;
use sim_plant::physics::{BodyState, QuadParams, QuadState, World, WorldParams, WorldState};

const DT: f64 = 0.0005;
const G: f64 = 9.81;

/// Quads hovering 1 m up at y = -/+0.8, rotors at `rotors`, payload on the ground below.
fn world_with_rotors(rotors: [[f64; 4]; 2], z: f64) -> World {
    let quad = |y: f64, rotor_speed| QuadState {
        body: BodyState::at_rest(Vector3::new(0.0, y, z)),
        rotor_speed,
    };
    let state = WorldState {
        time_s: 0.0,
        quads: [quad(-0.8, rotors[0]), quad(0.8, rotors[1])],
        payload: BodyState::at_rest(Vector3::new(0.0, 0.0, -0.05)),
    };
    World::new(WorldParams::default(), state).unwrap()
}

fn hover_speed() -> f64 {
    let q = QuadParams::x500();
    q.hover_rotor_speed(q.mass_kg, G)
}

/// Thrust per rotor at `w` rad/s, N.
fn thrust(w: f64) -> f64 {
    QuadParams::x500().thrust_coeff_n_per_rad2_s2 * w * w
}

#[test]
fn hover_speed_holds_a_free_quad() {
    let wh = hover_speed();
    println!("hover rotor speed {wh:.3} rad/s");
    assert!((wh - 769.5).abs() < 0.5, "{wh}");
    let cmd = [[wh; 4]; 2];
    let mut w = world_with_rotors(cmd, -1.0);
    let p0 = w.state().quads[0].body.position_ned;
    for _ in 0..4000 {
        w.step(DT, &cmd);
        assert!(w.cable(0).slack && w.cable(1).slack);
    }
    let q = &w.state().quads[0];
    let moved = (q.body.position_ned - p0).norm();
    let sf = w.specific_force_frd(0);
    println!("after 2 s hover: moved {moved:.2e} m, specific force {sf:?}");
    assert!(moved < 1e-9);
    assert!((sf - Vector3::new(0.0, 0.0, -G)).norm() < 1e-9);
    assert!(!w.quad_on_ground(0));
}

/// Rotor speeds `wh +/- d` by rotor, and the torque they make about body x, y, z.
fn differential(signs: [f64; 4], d: f64) -> ([f64; 4], Vector3<f64>) {
    let p = QuadParams::x500();
    let wh = hover_speed();
    let speeds = signs.map(|s| wh + s * d);
    let mut tau = Vector3::zeros();
    for ((&w, r), spin) in speeds
        .iter()
        .zip(&p.rotor_positions_frd_m)
        .zip(&p.rotor_spin)
    {
        let t = thrust(w);
        tau += Vector3::new(-r[1] * t, r[0] * t, spin * p.moment_constant_m * t);
    }
    (speeds, tau)
}

#[test]
fn roll_torque_tips_the_right_side_down() {
    // Motors 2 and 3 are on the left (y < 0): speeding them up rolls right (positive roll).
    let (speeds, tau) = differential([-1.0, 1.0, 1.0, -1.0], 30.0);
    assert!(
        tau.x > 0.0 && tau.y.abs() < 1e-12 && tau.z.abs() < 1e-12,
        "{tau}"
    );
    let mut w = world_with_rotors([speeds; 2], -1.0);
    for _ in 0..200 {
        w.step(DT, &[speeds; 2]);
    }
    let b = &w.state().quads[0].body;
    let expected = tau.x / 0.02167 * 0.1;
    let err = (b.rate_frd.x - expected) / expected;
    let right_ned = b.attitude * Vector3::y();
    println!("roll: rate {:.5} rad/s after 0.1 s, closed form {expected:.5}, error {:.2e}; right side z {:.5}", b.rate_frd.x, err, right_ned.z);
    assert!(err.abs() < 1e-3);
    assert!(right_ned.z > 0.0, "right side must go down (NED z > 0)");
    assert!(b.attitude.euler_angles().0 > 0.0);
}

#[test]
fn ccw_rotor_reaction_yaws_clockwise_seen_from_above() {
    // CCW rotors 1, 2 faster, CW rotors 3, 4 slower: +yaw (nose from north toward east).
    let (speeds, tau) = differential([1.0, 1.0, -1.0, -1.0], 30.0);
    assert!(
        tau.z > 0.0 && tau.x.abs() < 1e-12 && tau.y.abs() < 1e-12,
        "{tau}"
    );
    let mut w = world_with_rotors([speeds; 2], -1.0);
    for _ in 0..400 {
        w.step(DT, &[speeds; 2]);
    }
    let b = &w.state().quads[0].body;
    let expected = tau.z / 0.04 * 0.2;
    let err = (b.rate_frd.z - expected) / expected;
    let nose_ned = b.attitude * Vector3::x();
    println!("yaw: rate {:.5} rad/s after 0.2 s, closed form {expected:.5}, error {:.2e}; nose east {:.5}", b.rate_frd.z, err, nose_ned.y);
    assert!(err.abs() < 1e-3);
    assert!(nose_ned.y > 0.0);
}

#[test]
fn motor_lag_reaches_63_percent_in_tau() {
    let mut w = world_with_rotors([[0.0; 4]; 2], -1.0);
    w.pin_quad(1, true);
    let cmd = [[500.0; 4], [500.0; 4]];
    for _ in 0..25 {
        w.step(DT, &cmd); // 25 x 0.5 ms = tau_up = 12.5 ms
    }
    let up = w.state().quads[0].rotor_speed[0] / 500.0;
    let target = 1.0 - (-1.0f64).exp();
    println!(
        "motor up: {:.4} of the step after tau_up (theory {target:.4})",
        up
    );
    assert!(((up - target) / target).abs() < 0.05);
    assert_eq!(
        w.state().quads[1].rotor_speed,
        [0.0; 4],
        "a pinned quad keeps its rotors"
    );
    for _ in 0..400 {
        w.step(DT, &cmd);
    }
    let start = w.state().quads[0].rotor_speed[2];
    for _ in 0..25 {
        w.step(0.001, &[[0.0; 4]; 2]); // 25 x 1 ms = tau_down = 25 ms, in two sub-steps each
    }
    let down = w.state().quads[0].rotor_speed[2] / start;
    println!(
        "motor down: {:.4} left after tau_down (theory {:.4})",
        down,
        1.0 - target
    );
    assert!(((down - (1.0 - target)) / (1.0 - target)).abs() < 0.05);
}

#[test]
fn commands_are_clamped_and_nan_is_counted() {
    let mut w = world_with_rotors([[0.0; 4]; 2], -1.0);
    let cmd = [[f64::NAN, 5000.0, -10.0, f64::INFINITY], [0.0; 4]];
    for _ in 0..2000 {
        w.step(DT, &cmd);
    }
    let r = w.state().quads[0].rotor_speed;
    assert_eq!(w.nan_command_count(), 2000);
    assert!(r[0].abs() < 1e-9 && r[2].abs() < 1e-9, "{r:?}");
    assert!(
        (r[1] - 1000.0).abs() < 1e-6 && (r[3] - 1000.0).abs() < 1e-6,
        "{r:?}"
    );
}

#[test]
fn quad_rests_on_the_ground_and_takes_off() {
    let mut w = world_with_rotors([[0.0; 4]; 2], -0.1205);
    for _ in 0..2000 {
        w.step(DT, &[[0.0; 4]; 2]);
    }
    let b = w.state().quads[0].body;
    let sink = b.position_ned.z + 0.12;
    println!("quad on the ground: gear penetration {:.4} mm", sink * 1e3);
    assert!(w.quad_on_ground(0) && w.quad_on_ground(1));
    assert!(sink > 0.0 && sink < 1e-3);
    assert!(b.velocity_ned.norm() < 1e-5 && b.rate_frd.norm() < 1e-4);
    assert!((w.specific_force_frd(0) - Vector3::new(0.0, 0.0, -G)).norm() < 1e-3);
    let climb = [[hover_speed() * 1.1; 4]; 2];
    for _ in 0..2000 {
        w.step(DT, &climb);
    }
    assert!(!w.quad_on_ground(0));
    assert!(w.state().quads[0].body.position_ned.z < -0.5);
}
