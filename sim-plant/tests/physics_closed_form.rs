//! The payload between two pinned quads against closed-form mechanics: statics, the small
//! swing period, energy conservation, free fall. Run with `--nocapture` to see the numbers.

use nalgebra::{UnitQuaternion, Vector3};
use sim_plant::physics::{
    hanging_formation, BodyState, HangingFormation, Integrator, World, WorldParams, WorldState,
};

const DT: f64 = 0.0005;
const SPACING: f64 = 1.6;

fn center() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -3.0)
}

fn pinned_world(params: WorldParams, state: WorldState) -> World {
    let mut w = World::new(params, state).unwrap();
    w.pin_quad(0, true);
    w.pin_quad(1, true);
    w
}

fn run(w: &mut World, seconds: f64, mut each: impl FnMut(&World)) {
    let n = (seconds / DT).round() as usize;
    for _ in 0..n {
        w.step(DT, &[[0.0; 4]; 2]);
        each(w);
    }
}

#[test]
fn statics_of_the_symmetric_formation() {
    let params = WorldParams::default();
    let f = hanging_formation(&params, center(), SPACING);
    let mut state = f.state;
    state.payload.position_ned.z += 0.01; // released 1 cm low: bounces, damped by the cables
    let mut w = pinned_world(params, state);
    run(&mut w, 15.0, |_| {});
    let g = 9.81;
    let mut worst = 0.0f64;
    for i in 0..2 {
        let c = w.cable(i);
        let cos_theta = c.direction_ned.z;
        let expected = 1.0 * g / (2.0 * cos_theta);
        let err = (c.tension_n - expected).abs() / expected;
        println!(
            "statics cable {i}: T = {:.5} N, m g / (2 cos theta) = {:.5} N (theta = {:.3} deg), \
             closed-form equilibrium {:.5} N; error {:.2e}",
            c.tension_n,
            expected,
            cos_theta.acos().to_degrees(),
            f.tension_n,
            err
        );
        worst = worst.max(err);
        assert!(err < 0.01, "cable {i} tension error {err}");
        assert!((c.tension_n - f.tension_n).abs() / f.tension_n < 0.01);
    }
    let v = w.state().payload.velocity_ned.norm();
    assert!(v < 1e-3, "payload has not settled: {v} m/s");
    println!("statics worst relative error {worst:.2e}");
}

/// Initial state of the out-of-plane swing and the predicted period.
///
/// With both quads pinned, the drone anchors A1, A2 fix a hinge line (along y). The payload
/// anchors B1, B2 stay parallel to it at distance h (the cables' vertical extent at rest), so
/// the cable plane swings about the hinge like a massless link of length h (angle t1). The
/// cables pass through B1, B2 and exert no torque about the line B1B2, so the payload swings
/// about that line as a compound pendulum (angle t2): its centre of mass is l = 0.05 m below
/// the anchor line (anchors on the top face), with inertia I_c = m (a^2 + c^2) / 12 about its
/// own y axis. Linearised Lagrangian (x = h t1 + l t2):
///   T = m (h t1' + l t2')^2 / 2 + I_c t2'^2 / 2,   V = m g (h t1^2 + l t2^2) / 2
///   h t1'' + l t2'' = -g t1,   I_c t2'' = m g l (t1 - t2)
/// With t = A exp(i w t) and k = I_c / (m g l): A1 = A2 (1 - w^2 k) and
///   h k w^4 - (h + l + g k) w^2 + g = 0,
/// whose smaller root is the swing (the larger one, ~11 rad/s, is the payload's own wobble).
/// The initial state puts all the motion in the swing mode: t2 = t1 / (1 - w^2 k).
fn swing_setup(params: &WorldParams, amplitude_deg: f64) -> (WorldState, f64, HangingFormation) {
    let f = hanging_formation(params, center(), SPACING);
    let g = params.gravity_m_s2;
    let m = params.payload.mass_kg;
    let ic = params.payload.inertia_diag_kg_m2()[1];
    let l = -params.payload.anchors_frd_m[0][2];
    let h = f.cable_length_m * f.cable_angle_rad.cos();
    let k = ic / (m * g * l);
    let b = h + l + g * k;
    let w2 = (b - (b * b - 4.0 * h * k * g).sqrt()) / (2.0 * h * k);
    let period = 2.0 * std::f64::consts::PI / w2.sqrt();
    let t1 = amplitude_deg.to_radians();
    let t2 = t1 / (1.0 - w2 * k);
    let hinge =
        f.state.quads[0].body.position_ned + Vector3::from(params.quads[0].cable_anchor_frd_m);
    let anchor_line = Vector3::new(h * t1.sin(), 0.0, hinge.z + h * t1.cos());
    let attitude = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), t2);
    let mut state = f.state;
    state.payload = BodyState {
        position_ned: anchor_line + attitude * Vector3::new(0.0, 0.0, l),
        attitude,
        ..BodyState::at_rest(Vector3::zeros())
    };
    println!(
        "swing: h = {h:.4} m, l = {l} m, I_c = {ic:.6} kg m^2, predicted period {period:.5} s \
         (simple pendulum h + l: {:.5} s)",
        2.0 * std::f64::consts::PI * ((h + l) / g).sqrt()
    );
    (state, period, f)
}

fn undamped() -> WorldParams {
    let mut p = WorldParams::default();
    for c in &mut p.cables {
        c.damping_n_s_per_m = 0.0;
    }
    p
}

/// Mean period from upward zero crossings of `x(t)` about its mean.
fn measured_period(times: &[f64], xs: &[f64]) -> f64 {
    let mean = xs.iter().sum::<f64>() / xs.len() as f64;
    let mut crossings = Vec::new();
    for k in 1..xs.len() {
        let (a, b) = (xs[k - 1] - mean, xs[k] - mean);
        if a < 0.0 && b >= 0.0 {
            crossings.push(times[k - 1] + (times[k] - times[k - 1]) * (-a / (b - a)));
        }
    }
    assert!(crossings.len() >= 5, "only {} crossings", crossings.len());
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// Swing period measured over 20 s with `integrator`, and the closed-form prediction.
fn swing_period(integrator: Integrator) -> (f64, f64) {
    let params = WorldParams {
        integrator,
        ..undamped()
    };
    let (state, predicted, _) = swing_setup(&params, 3.0);
    let mut w = pinned_world(params, state);
    let (mut ts, mut xs) = (Vec::new(), Vec::new());
    run(&mut w, 20.0, |w| {
        ts.push(w.state().time_s);
        xs.push(w.state().payload.position_ned.x);
    });
    (measured_period(&ts, &xs), predicted)
}

#[test]
fn small_swing_period_matches_the_double_pendulum() {
    let (measured, predicted) = swing_period(Integrator::Rk4);
    let err = (measured - predicted) / predicted;
    println!(
        "RK4 swing period: measured {measured:.5} s, predicted {predicted:.5} s, error {:.3} %",
        err * 100.0
    );
    assert!(err.abs() < 0.02, "period error {err}");
    assert!(
        err.abs() < 0.002,
        "period error {err} (expected near-exact agreement)"
    );
    let (measured, predicted) = swing_period(Integrator::SemiImplicitEuler);
    let err = (measured - predicted) / predicted;
    println!(
        "semi-implicit Euler swing period: measured {measured:.5} s, error {:.3} %",
        err * 100.0
    );
    assert!(err.abs() < 0.02, "period error {err}");
}

/// Free swing, no damping, no contact: returns the worst |E(t) - E(0)| over 20 s relative to
/// the total energy and relative to the swing energy (E(0) minus the energy at rest).
fn energy_drift(integrator: Integrator) -> (f64, f64) {
    let params = WorldParams {
        integrator,
        ..undamped()
    };
    let (state, _, f) = swing_setup(&params, 3.0);
    let rest = pinned_world(params.clone(), f.state).energy().total_j;
    let mut w = pinned_world(params, state);
    let e0 = w.energy().total_j;
    let mut worst = 0.0f64;
    let mut k = 0;
    run(&mut w, 20.0, |w| {
        k += 1;
        if k % 10 == 0 {
            assert!(!w.payload_contact().in_contact);
            worst = worst.max((w.energy().total_j - e0).abs());
        }
    });
    (worst / e0.abs(), worst / (e0 - rest))
}

#[test]
fn energy_is_conserved_in_the_undamped_swing() {
    let (of_total, of_swing) = energy_drift(Integrator::Rk4);
    println!(
        "RK4 energy drift over 20 s: {:.2e} % of total, {:.2e} % of swing energy",
        of_total * 100.0,
        of_swing * 100.0
    );
    assert!(of_total < 0.01);
    assert!(of_swing < 0.01, "drift is {of_swing} of the swing energy");
    let (of_total, of_swing) = energy_drift(Integrator::SemiImplicitEuler);
    println!(
        "semi-implicit Euler energy drift over 20 s: {:.2e} % of total, {:.2e} % of swing energy",
        of_total * 100.0,
        of_swing * 100.0
    );
    assert!(of_total < 0.01);
}

#[test]
fn free_fall_with_slack_cables() {
    let params = WorldParams::default();
    let f = hanging_formation(&params, Vector3::new(0.0, 0.0, -10.0), SPACING);
    let mut state = f.state;
    let z0 = -11.0; // 1 m above the quads: the cables stay slack for ~0.7 s of fall
    state.payload = BodyState::at_rest(Vector3::new(0.0, 0.0, z0));
    let mut w = pinned_world(params, state);
    run(&mut w, 0.6, |w| {
        assert!(w.cable(0).slack && w.cable(1).slack);
    });
    let t = w.state().time_s;
    let fallen = w.state().payload.position_ned.z - z0;
    let expected = 0.5 * 9.81 * t * t;
    let err = (fallen - expected).abs() / expected;
    println!("free fall: {fallen:.9} m in {t:.4} s, expected {expected:.9} m, error {err:.2e}");
    assert!(err < 1e-3);
    let sf = w.payload_acceleration_ned();
    assert!((sf - Vector3::new(0.0, 0.0, 9.81)).norm() < 1e-9, "{sf}");
}
