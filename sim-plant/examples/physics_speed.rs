//! Cost of one physics step: two quads hovering with the payload hanging between them, held in
//! place by a minimal position + attitude controller written here (not PX4's), stepped at
//! 2 kHz. Prints ns per step for the physics alone and for the whole loop.
//!
//! `cargo run --release -p sim-plant --example physics_speed [seconds] [integrator]`
//! (integrator: `rk4` (default) or `semi_implicit_euler`).

use std::time::Instant;

use nalgebra::{Matrix3, Vector3};
use sim_plant::physics::{hanging_formation, Integrator, World, WorldParams};

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

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seconds: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let integrator = match args.get(2).map(String::as_str) {
        Some("semi_implicit_euler") => Integrator::SemiImplicitEuler,
        _ => Integrator::Rk4,
    };
    let params = WorldParams {
        integrator,
        ..WorldParams::default()
    };
    let formation = hanging_formation(&params, Vector3::new(0.0, 0.0, -2.5), 1.6);
    let targets = formation.state.quads.map(|q| q.body.position_ned);
    let mut world = World::new(params, formation.state).expect("valid world");
    let steps = (seconds / DT).round() as usize;

    // Timed in blocks of 1000 steps; the fastest block shows the cost without interference
    // from other processes on a shared machine.
    let mut cmd = [[0.0; 4]; 2];
    let mut physics_ns = 0u128;
    let mut fastest_block_ns = u128::MAX;
    let mut block_ns = 0u128;
    let start = Instant::now();
    for k in 0..steps {
        for i in 0..2 {
            cmd[i] = hover_command(&world, i, &targets[i]);
        }
        let t0 = Instant::now();
        world.step(DT, &cmd);
        let ns = t0.elapsed().as_nanos();
        physics_ns += ns;
        block_ns += ns;
        if k % 1000 == 999 {
            fastest_block_ns = fastest_block_ns.min(block_ns);
            block_ns = 0;
        }
    }
    let total_ns = start.elapsed().as_nanos();

    let s = world.state();
    let drift = (0..2)
        .map(|i| (s.quads[i].body.position_ned - targets[i]).norm())
        .fold(0.0, f64::max);
    println!("integrator {integrator:?}, {steps} steps of {DT} s ({seconds} s simulated)");
    println!(
        "physics step: {:.0} ns/step mean, {:.0} ns/step in the fastest 1000-step block; \
         whole loop (controller + step): {:.0} ns/step; {:.0}x real time",
        physics_ns as f64 / steps as f64,
        fastest_block_ns as f64 / 1000.0,
        total_ns as f64 / steps as f64,
        seconds * 1e9 / total_ns as f64
    );
    println!(
        "end: max quad offset from target {:.4} m, tensions {:.3} / {:.3} N (static {:.3} N)",
        drift,
        world.cable(0).tension_n,
        world.cable(1).tension_n,
        formation.tension_n
    );
}
