//! Test A in miniature: two quads (held by a minimal controller written here, not PX4's) take
//! off beside the box with slack cables, climb, and translate 2 m; the cables jerk the payload
//! off the box and it swings below them. Checks the hand-over from contact to cables stays
//! finite and bounded.

use nalgebra::{Matrix3, Vector3};
use sim_plant::physics::{
    BodyState, BoxObstacle, ContactSurface, FrictionState, QuadState, World, WorldParams,
    WorldState,
};

const DT: f64 = 0.0005;

/// Rotor speeds that hold quad `i` of `world` at `target` (NED), level yaw: position PD with
/// cable feed-forward, geometric attitude PD, exact X500 allocation.
fn hover_command(world: &World, i: usize, target: &Vector3<f64>) -> [f64; 4] {
    let p = &world.params().quads[i];
    let g = world.params().gravity_m_s2;
    let body = &world.state().quads[i].body;
    let a_d = (target - body.position_ned) * 4.0 - body.velocity_ned * 3.0;
    let cable = world.cable(i).force_on_quad_ned;
    // Required rotor force (NED): m a = F + m g e3 + cable.
    let f = (a_d - Vector3::new(0.0, 0.0, g)) * p.mass_kg - cable;
    let z_d = -f.normalize();
    let y_d = z_d.cross(&Vector3::x()).normalize();
    let x_d = y_d.cross(&z_d);
    let r_d = Matrix3::from_columns(&[x_d, y_d, z_d]);
    let r = body.attitude.to_rotation_matrix().into_inner();
    let e = r_d.transpose() * r - r.transpose() * r_d;
    let e_r = Vector3::new(e[(2, 1)], e[(0, 2)], e[(1, 0)]) * 0.5;
    let inertia = Vector3::from(p.inertia_diag_kg_m2);
    let anchor = Vector3::from(p.cable_anchor_frd_m);
    let tau = -e_r.component_mul(&inertia) * 400.0
        - body.rate_frd.component_mul(&inertia) * 28.0
        - anchor.cross(&world.anchor_force_frd(i));
    let thrust = -f.dot(&(r * Vector3::z()));
    let a = p.rotor_positions_frd_m[0][0];
    let c = p.moment_constant_m;
    let t = [
        thrust / 4.0 - tau.x / (4.0 * a) + tau.y / (4.0 * a) + tau.z / (4.0 * c),
        thrust / 4.0 + tau.x / (4.0 * a) - tau.y / (4.0 * a) + tau.z / (4.0 * c),
        thrust / 4.0 + tau.x / (4.0 * a) + tau.y / (4.0 * a) - tau.z / (4.0 * c),
        thrust / 4.0 - tau.x / (4.0 * a) - tau.y / (4.0 * a) - tau.z / (4.0 * c),
    ];
    t.map(|t| (t.max(0.0) / p.thrust_coeff_n_per_rad2_s2).sqrt())
}
#[test]
fn payload_is_pulled_off_the_box_and_swings() {
    let params = WorldParams {
        boxes: vec![BoxObstacle {
            center_ned: [1.0, 0.0, -0.225],
            half_extents: [0.5, 0.5, 0.225],
        }],
        ..WorldParams::default()
    };
    let quad = |y: f64| QuadState {
        body: BodyState::at_rest(Vector3::new(1.0, y, -0.1205)),
        rotor_speed: [0.0; 4],
    };
    let state = WorldState {
        time_s: 0.0,
        quads: [quad(-0.8), quad(0.8)],
        payload: BodyState::at_rest(Vector3::new(1.0, 0.0, -0.5005)),
    };
    let mut w = World::new(params, state).unwrap();
    let mut peak_tension = 0.0f64;
    let mut left_box_at = None;
    for k in 0..32000 {
        let t = k as f64 * DT;
        let x = if t < 6.0 {
            1.0
        } else {
            (1.0 + (t - 6.0)).min(3.0)
        };
        let targets = [Vector3::new(x, -0.8, -1.9), Vector3::new(x, 0.8, -1.9)];
        let cmd = if t < 1.0 {
            [[0.0; 4]; 2]
        } else {
            [0, 1].map(|i| hover_command(&w, i, &targets[i]))
        };
        w.step(DT, &cmd);
        peak_tension = peak_tension.max(w.cable(0).tension_n.max(w.cable(1).tension_n));
        let c = w.payload_contact();
        if (0.5..6.0).contains(&t) {
            assert_eq!(c.surface, Some(ContactSurface::Box(0)), "t = {t}");
            assert_eq!(c.friction, FrictionState::Sticking, "t = {t}");
            assert!(w.cable(0).slack && w.cable(1).slack);
        } else if t >= 6.0 && left_box_at.is_none() && !c.in_contact {
            left_box_at = Some(t);
        }
    }
    let p = w.state().payload.position_ned;
    println!(
        "left the box at {left_box_at:?} s, peak tension {peak_tension:.2} N, payload at {p:?}"
    );
    assert_eq!(w.non_finite_step_count(), 0);
    assert!(left_box_at.is_some());
    assert!(!w.payload_contact().in_contact);
    assert!(peak_tension < 3.0 * 5.54, "peak tension {peak_tension}");
    assert!((p.x - 3.0).abs() < 0.8 && p.z < -0.3 && p.z > -0.7, "{p:?}");
}
