//! The payload on a box top and on the ground: resting penetration, no bounce, no creep under
//! a pull below mu N (external force or a taut cable), sliding at mu N above it.
//! Run with `--nocapture` to see the numbers.
//!
//! Test A geometry (our choice, MODEL.md leaves it open): the payload's centre rests at
//! [1.0, 0.0, -0.5] NED on a box whose top face is at z = -0.45 (0.45 m high, standing on the
//! ground): centre [1.0, 0.0, -0.225], half extents [0.5, 0.5, 0.225] (a 1 m table, so the
//! sliding test stays on it).

use nalgebra::Vector3;
use sim_plant::physics::{
    BodyId, BodyState, BoxObstacle, ContactSurface, FrictionState, QuadState, World, WorldParams,
    WorldState,
};

const DT: f64 = 0.0005;
const G: f64 = 9.81;

fn box_params() -> WorldParams {
    WorldParams {
        boxes: vec![BoxObstacle {
            center_ned: [1.0, 0.0, -0.225],
            half_extents: [0.5, 0.5, 0.225],
        }],
        ..WorldParams::default()
    }
}

/// Payload 1 mm above the box top, quads pinned above it with slack cables.
fn payload_on_box(params: WorldParams) -> World {
    let quad = |y: f64| QuadState {
        body: BodyState::at_rest(Vector3::new(1.0, y, -1.2)),
        rotor_speed: [0.0; 4],
    };
    let state = WorldState {
        time_s: 0.0,
        quads: [quad(-0.8), quad(0.8)],
        payload: BodyState::at_rest(Vector3::new(1.0, 0.0, -0.501)),
    };
    let mut w = World::new(params, state).unwrap();
    w.pin_quad(0, true);
    w.pin_quad(1, true);
    w
}

fn run(w: &mut World, seconds: f64, mut each: impl FnMut(&World)) {
    for _ in 0..(seconds / DT).round() as usize {
        w.step(DT, &[[0.0; 4]; 2]);
        each(w);
    }
}

/// Lets the payload drop 1 mm onto the box and settle; checks no bounce and the penetration.
fn settled_on_box(params: WorldParams) -> World {
    let mut w = payload_on_box(params);
    let mut touched = false;
    let mut bounced = false;
    run(&mut w, 2.0, |w| {
        let c = w.payload_contact();
        touched |= c.points_in_contact == 4;
        bounced |= touched && c.points_in_contact < 4;
    });
    assert!(touched && !bounced, "touched {touched}, bounced {bounced}");
    let c = w.payload_contact();
    assert_eq!(c.surface, Some(ContactSurface::Box(0)));
    assert_eq!(c.friction, FrictionState::Sticking);
    let penetration = w.state().payload.position_ned.z + 0.5;
    println!(
        "resting on the box: penetration {:.4} mm, normal force {:.4} N",
        penetration * 1e3,
        c.normal_force_n
    );
    assert!(
        penetration > 0.0 && penetration < 0.5e-3,
        "penetration {penetration}"
    );
    assert!((c.normal_force_n - G).abs() < 1e-3 * G);
    assert!(w.state().payload.velocity_ned.norm() < 1e-5);
    w
}

/// Horizontal displacement of the payload over `seconds`, m, and the largest displacement from
/// where it was 1 s into that time (creep, excluding the initial elastic deflection).
fn displacement(w: &mut World, seconds: f64) -> (f64, f64) {
    let start = w.state().payload.position_ned;
    let mut at_1s = None;
    let mut creep = 0.0f64;
    run(w, seconds, |w| {
        let p = w.state().payload.position_ned;
        if w.state().time_s >= 1.0 + 2.0 - 1e-9 {
            let a = *at_1s.get_or_insert(p);
            creep = creep.max((p - a).xy().norm());
        }
    });
    ((w.state().payload.position_ned - start).xy().norm(), creep)
}

#[test]
fn resting_payload_does_not_creep_under_an_external_pull() {
    let mut w = settled_on_box(box_params());
    let pull = 0.3 * 0.5 * G;
    w.set_external_force(
        BodyId::Payload,
        Vector3::new(1.0, 0.6, 0.0).normalize() * pull,
    );
    let (moved, creep) = displacement(&mut w, 10.0);
    println!(
        "external pull {pull:.3} N (0.3 mu N): moved {:.4} mm in 10 s, creep after the first second {:.2e} mm",
        moved * 1e3,
        creep * 1e3
    );
    assert!(moved < 1e-3, "moved {moved} m");
    assert!(creep < 1e-6, "creep {creep} m");
    assert_eq!(w.payload_contact().friction, FrictionState::Sticking);
}

#[test]
fn resting_payload_does_not_creep_under_a_cable_pull() {
    // Quad 0 pinned so that cable 0 runs horizontally along -x from payload anchor 0 with
    // 1.47 N of tension (0.3 mu N): stretch 1.47 / 1500 m.
    let params = box_params();
    let mut w = payload_on_box(params.clone());
    run(&mut w, 2.0, |_| {});
    let pull = 0.3 * 0.5 * G;
    let p = w.state().payload.position_ned;
    let anchor = p + Vector3::new(0.0, -0.1, -0.05);
    let length = 1.5 + pull / params.cables[0].stiffness_n_per_m;
    let mut state = *w.state();
    state.quads[0].body.position_ned =
        anchor - Vector3::new(length, 0.0, 0.0) - Vector3::new(0.0, 0.0, 0.08);
    let mut w = World::new(params, state).unwrap();
    w.pin_quad(0, true);
    w.pin_quad(1, true);
    let t0 = w.cable(0).tension_n;
    let (moved, creep) = displacement(&mut w, 10.0);
    println!(
        "cable pull {t0:.3} N (0.3 mu N): moved {:.4} mm in 10 s, creep after the first second {:.2e} mm",
        moved * 1e3,
        creep * 1e3
    );
    assert!((t0 - pull).abs() < 0.05 * pull, "tension {t0}");
    assert!(moved < 1e-3, "moved {moved} m");
    assert!(creep < 1e-6, "creep {creep} m");
}

/// Pulls with `factor * mu m g` along x and returns (friction from the measured acceleration,
/// mu N from the measured normal force, friction reported by the contact reading).
fn slide(mut w: World, factor: f64) -> (f64, f64, f64) {
    let pull = factor * 0.5 * G;
    w.set_external_force(BodyId::Payload, Vector3::new(pull, 0.0, 0.0));
    run(&mut w, 0.1, |_| {});
    let (t0, v0) = (w.state().time_s, w.state().payload.velocity_ned.x);
    let mut mu_n = 0.0;
    let mut reported = 0.0;
    let mut n = 0;
    run(&mut w, 0.3, |w| {
        let c = w.payload_contact();
        assert_eq!(c.friction, FrictionState::Slipping);
        mu_n += 0.5 * c.normal_force_n;
        reported += -c.friction_force_ned.x;
        n += 1;
    });
    let a = (w.state().payload.velocity_ned.x - v0) / (w.state().time_s - t0);
    (pull - 1.0 * a, mu_n / n as f64, reported / n as f64)
}

#[test]
fn payload_slides_at_mu_n_above_the_limit() {
    let (friction, mu_n, reported) = slide(settled_on_box(box_params()), 1.5);
    let err = (friction - mu_n) / mu_n;
    println!(
        "sliding on the box at 1.5 mu N: friction {friction:.4} N from F - m a, mu N = {mu_n:.4} N, \
         reported {reported:.4} N, error {:.3} %",
        err * 100.0
    );
    assert!(err.abs() < 0.03, "friction error {err}");
    assert!(((reported - mu_n) / mu_n).abs() < 0.03);
}

#[test]
fn payload_rests_and_slides_on_the_ground() {
    let quad = |y: f64| QuadState {
        body: BodyState::at_rest(Vector3::new(0.0, y, -1.0)),
        rotor_speed: [0.0; 4],
    };
    let state = WorldState {
        time_s: 0.0,
        quads: [quad(-0.8), quad(0.8)],
        payload: BodyState::at_rest(Vector3::new(0.0, 0.0, -0.051)),
    };
    let mut w = World::new(WorldParams::default(), state).unwrap();
    w.pin_quad(0, true);
    w.pin_quad(1, true);
    run(&mut w, 2.0, |_| {});
    let c = w.payload_contact();
    assert_eq!(c.surface, Some(ContactSurface::Ground));
    assert!((c.normal_force_n - G).abs() < 1e-3 * G);
    let (friction, mu_n, _) = slide(w, 2.0);
    println!("sliding on the ground at 2 mu N: friction {friction:.4} N, mu N {mu_n:.4} N");
    assert!(((friction - mu_n) / mu_n).abs() < 0.03);
}

#[test]
fn payload_falling_past_the_box_side_lands_on_the_ground() {
    // Box sides are not modelled: a payload beside the box falls to the ground.
    let mut w = payload_on_box(box_params());
    let mut state = *w.state();
    state.payload.position_ned.x = 1.0 + 0.5 + 0.11;
    w = World::new(box_params(), state).unwrap();
    w.pin_quad(0, true);
    w.pin_quad(1, true);
    run(&mut w, 1.5, |_| {});
    assert_eq!(w.payload_contact().surface, Some(ContactSurface::Ground));
    assert!((w.state().payload.position_ned.z + 0.05).abs() < 1e-3);
}
