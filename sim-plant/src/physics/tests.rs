//! Unit tests: parameters, construction errors, bookkeeping, readings. The closed-form
//! acceptance tests are in `sim-plant/tests/physics_*.rs`.

use nalgebra::{UnitQuaternion, Vector3};

use super::*;

fn formation() -> (WorldParams, HangingFormation) {
    let params = WorldParams::default();
    let f = hanging_formation(&params, Vector3::new(0.0, 0.0, -3.0), 1.6);
    (params, f)
}

#[test]
fn defaults_validate_and_parse_partially() {
    WorldParams::default().validate().unwrap();
    let toml = r#"
        gravity_m_s2 = 9.8
        integrator = "semi_implicit_euler"
        [payload]
        mass_kg = 1.2
        [[cables]]
        rest_length_m = 1.4
        [[cables]]
        [[boxes]]
        center_ned = [1.0, 0.0, -0.225]
        half_extents = [0.2, 0.2, 0.225]
    "#;
    let p: WorldParams = toml::from_str(toml).unwrap();
    p.validate().unwrap();
    assert_eq!(p.payload.mass_kg, 1.2);
    assert_eq!(p.payload.box_size_m, [0.2, 0.2, 0.1]);
    assert_eq!(p.cables[0].rest_length_m, 1.4);
    assert_eq!(p.cables[1].rest_length_m, 1.5);
    assert_eq!(p.integrator, Integrator::SemiImplicitEuler);
    assert_eq!(p.boxes[0].top_z_ned(), -0.45);
    assert_eq!(p.quads[0], QuadParams::x500());
    assert!(toml::from_str::<WorldParams>("gravity = 9.8").is_err());
    assert!(toml::from_str::<WorldParams>("[contact]\nmu = 0.3").is_err());
}

#[test]
fn x500_numbers() {
    let q = QuadParams::x500();
    assert!((q.mass_kg - 2.064).abs() < 1e-12);
    let total_max_thrust = 4.0 * q.thrust_coeff_n_per_rad2_s2 * 1000.0f64.powi(2);
    assert!((total_max_thrust - 34.19).abs() < 0.01);
    let i = PayloadParams::default().inertia_diag_kg_m2();
    assert!((i[0] - 0.05 / 12.0).abs() < 1e-15 && (i[2] - 0.08 / 12.0).abs() < 1e-15);
}

#[test]
fn validation_names_the_parameter() {
    let mut p = WorldParams::default();
    p.quads[1].inertia_diag_kg_m2[2] = 0.0;
    let e = p.validate().unwrap_err();
    assert_eq!(e.key, "quads[1].inertia_diag_kg_m2[2]");
    assert!(e.to_string().contains("quads[1].inertia_diag_kg_m2[2]"));
    let mut p = WorldParams::default();
    p.cables[0].damping_n_s_per_m = f64::NAN;
    assert_eq!(p.validate().unwrap_err().key, "cables[0].damping_n_s_per_m");
    let mut p = WorldParams::default();
    p.quads[0].rotor_spin[3] = 0.5;
    assert_eq!(p.validate().unwrap_err().key, "quads[0].rotor_spin[3]");
    let mut p = WorldParams::default();
    p.boxes.push(BoxObstacle {
        center_ned: [0.0; 3],
        half_extents: [1.0, -1.0, 1.0],
    });
    assert_eq!(p.validate().unwrap_err().key, "boxes[0].half_extents[1]");
    let p = WorldParams {
        max_substep_s: 0.0,
        ..WorldParams::default()
    };
    assert_eq!(p.validate().unwrap_err().key, "max_substep_s");
}

#[test]
fn construction_rejects_bad_initial_states() {
    let (params, f) = formation();
    let mut s = f.state;
    s.payload.velocity_ned.y = f64::INFINITY;
    assert_eq!(
        World::new(params.clone(), s).unwrap_err(),
        WorldError::NonFiniteState { field: "payload" }
    );
    let mut s = f.state;
    s.quads[1].rotor_speed[2] = 1200.0;
    assert!(matches!(
        World::new(params.clone(), s),
        Err(WorldError::RotorSpeed {
            quad: 1,
            rotor: 2,
            ..
        })
    ));
    let mut bad = params;
    bad.payload.mass_kg = -1.0;
    assert!(matches!(
        World::new(bad, f.state),
        Err(WorldError::Params(_))
    ));
}

#[test]
fn bad_steps_are_ignored_and_counted() {
    let (params, f) = formation();
    let mut w = World::new(params, f.state).unwrap();
    let cmd = [[0.0; 4]; 2];
    for dt in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e6] {
        w.step(dt, &cmd);
    }
    assert_eq!(w.rejected_input_count(), 5);
    assert_eq!(*w.state(), f.state);
    w.set_external_force(BodyId::Payload, Vector3::new(f64::NAN, 0.0, 0.0));
    assert_eq!(w.rejected_input_count(), 6);
    assert_eq!(w.external_force(BodyId::Payload), Vector3::zeros());
}

#[test]
fn long_steps_split_into_the_same_substeps() {
    let (params, f) = formation();
    let cmd = [[600.0, 700.0, 800.0, 750.0], [900.0; 4]];
    let mut a = World::new(params.clone(), f.state).unwrap();
    let mut b = World::new(params, f.state).unwrap();
    for _ in 0..200 {
        a.step(0.001, &cmd);
        b.step(0.0005, &cmd);
        b.step(0.0005, &cmd);
    }
    let (sa, sb) = (a.state(), b.state());
    assert!((sa.time_s - 0.2).abs() < 1e-12);
    assert_eq!(sa.quads, sb.quads);
    assert_eq!(sa.payload, sb.payload);
}

#[test]
fn pinned_quad_is_frozen_and_still_pulls() {
    let (params, f) = formation();
    let mut s = f.state;
    s.quads[0].body.velocity_ned = Vector3::new(1.0, 0.0, 0.0);
    let mut w = World::new(params, s).unwrap();
    w.pin_quad(0, true);
    assert!(w.is_quad_pinned(0) && !w.is_quad_pinned(1));
    let frozen = w.state().quads[0];
    assert_eq!(frozen.body.velocity_ned, Vector3::zeros());
    for _ in 0..1000 {
        w.step(0.0005, &[[1000.0; 4], [0.0; 4]]);
    }
    assert_eq!(w.state().quads[0], frozen);
    assert!(w.cable(0).tension_n > 1.0);
    assert_eq!(w.specific_force_frd(0), Vector3::new(0.0, 0.0, -9.81));
    w.pin_quad(0, false);
    w.step(0.0005, &[[1000.0; 4], [0.0; 4]]);
    assert_ne!(w.state().quads[0], frozen);
}

#[test]
fn cable_reading_directions_and_the_anchor_force_frame() {
    let (params, f) = formation();
    let mut s = f.state;
    // Quad 0 yawed by 90 degrees: its body x points east (+y NED).
    s.quads[0].body.attitude =
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 90f64.to_radians());
    let w = World::new(params, s).unwrap();
    let c = w.cable(0);
    assert!(!c.slack);
    assert!(
        (c.tension_n - f.tension_n).abs() < 1e-9,
        "{} vs {}",
        c.tension_n,
        f.tension_n
    );
    // Quad 0 is on the -y side: its cable pulls it toward +y (east) and down.
    assert!(c.force_on_quad_ned.y > 0.0 && c.force_on_quad_ned.z > 0.0);
    assert_eq!(c.force_on_payload_ned, -c.force_on_quad_ned);
    assert!((c.direction_ned.norm() - 1.0).abs() < 1e-12);
    let frd = w.anchor_force_frd(0);
    // East in NED is body +x after a 90 degree yaw; down stays body +z.
    assert!((frd.x - c.force_on_quad_ned.y).abs() < 1e-12);
    assert!((frd.y + c.force_on_quad_ned.x).abs() < 1e-12);
    assert!((frd.z - c.force_on_quad_ned.z).abs() < 1e-12);
    assert!((c.stretch_m - f.tension_n / 1500.0).abs() < 1e-9);
}

#[test]
fn energy_parts_add_up() {
    let (params, f) = formation();
    let mut s = f.state;
    s.payload.velocity_ned = Vector3::new(0.3, 0.0, 0.0);
    s.payload.rate_frd = Vector3::new(0.0, 0.0, 2.0);
    let w = World::new(params, s).unwrap();
    let e = w.energy();
    let kinetic = 0.5 * 0.09 + 0.5 * 4.0 * 0.08 / 12.0;
    assert!((e.kinetic_j - kinetic).abs() < 1e-12);
    let potential = 9.81 * (2.0 * 2.064 * 3.0 - s.payload.position_ned.z);
    assert!((e.potential_j - potential).abs() < 1e-9);
    let stretch = f.tension_n / 1500.0;
    assert!((e.cable_elastic_j - 1500.0 * stretch * stretch).abs() < 1e-9);
    assert_eq!(e.contact_elastic_j, 0.0);
    assert!((e.total_j - (e.kinetic_j + e.potential_j + e.cable_elastic_j)).abs() < 1e-12);
}

#[test]
fn box_top_only_within_its_depth() {
    let params = WorldParams {
        boxes: vec![BoxObstacle {
            center_ned: [0.0, 0.0, -1.0],
            half_extents: [1.0, 1.0, 1.0],
        }],
        ..WorldParams::default()
    };
    let (_, f) = formation();
    let mut s = f.state;
    // Gear 1 cm into the top face of a 2 m box: on it. 10 cm in (deeper than 5 cm): not.
    s.quads[0].body.position_ned = Vector3::new(0.5, 0.0, -2.0 - 0.12 + 0.01);
    s.quads[1].body.position_ned = Vector3::new(-0.5, 0.0, -2.0 - 0.12 + 0.1);
    let w = World::new(params, s).unwrap();
    assert_eq!(w.quad_contact_surface(0), Some(ContactSurface::Box(0)));
    assert_eq!(w.quad_contact_surface(1), None);
}

#[test]
fn runs_are_deterministic() {
    let (params, f) = formation();
    let run = || {
        let mut w = World::new(params.clone(), f.state).unwrap();
        for k in 0..2000 {
            let wobble = 760.0 + 20.0 * ((k % 37) as f64 / 37.0);
            w.step(0.0005, &[[wobble, 780.0, 770.0, 775.0], [775.0; 4]]);
        }
        *w.state()
    };
    assert_eq!(run(), run());
}
