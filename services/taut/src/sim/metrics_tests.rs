use super::*;
use shared_types::{DroneTruth, MissionPhase};

fn recorder() -> MetricsRecorder {
    MetricsRecorder::new(
        ["uav1".into(), "uav2".into()],
        vec!["takeoff".into(), "move".into(), "hold".into()],
        vec![false, true, false],
        [0.0, 0.0, 0.08],
    )
}

/// Drones level at y = ∓0.8, z = -2.1; payload `below` m under the anchors' midpoint, shifted
/// by `dx` (north, across the anchor line) and `dy` (east, along it).
fn truth(t_s: f64, dx: f64, dy: f64, contact: ContactKind) -> PlantTruth {
    let mut t = PlantTruth {
        sim_time_ns: (t_s * 1e9) as u64,
        payload_contact: contact,
        ..Default::default()
    };
    t.header.t_origin_ns = 1_000_000_000 + t.sim_time_ns;
    for (k, y) in [(0, -0.8), (1, 0.8)] {
        t.drones[k] = DroneTruth::default();
        t.drones[k].body.position_ned_m = [0.0, y, -2.1];
        t.drones[k].body.attitude_wxyz = [1.0, 0.0, 0.0, 0.0];
    }
    let below = 1.2;
    t.payload.position_ned_m = [dx, dy, -2.1 + 0.08 + below];
    t
}

#[test]
fn swing_is_the_pendulum_angle_about_the_anchor_line() {
    let r = recorder();
    assert!(r.swing_deg(&truth(0.0, 0.0, 0.0, ContactKind::Free)).abs() < 1e-9);
    let a = r.swing_deg(&truth(
        0.0,
        1.2 * 10f64.to_radians().tan(),
        0.0,
        ContactKind::Free,
    ));
    assert!((a - 10.0).abs() < 1e-9, "{a}");
    // Along the line: not a swing.
    assert!(r.swing_deg(&truth(0.0, 0.0, 0.3, ContactKind::Free)).abs() < 1e-9);
}

#[test]
fn settling_time_counts_from_lift_off_to_the_last_swing_above_two_degrees() {
    let mut r = recorder();
    let dx = |deg: f64| 1.2 * deg.to_radians().tan();
    for i in 0..100 {
        let t = i as f64 * 0.1;
        let (contact, deg) = if t < 2.0 {
            (ContactKind::Box, 0.0)
        } else {
            // 8° decaying by half per second after lift-off at 2 s.
            (ContactKind::Free, 8.0 * 0.5f64.powf(t - 2.0))
        };
        r.on_truth(&truth(t, dx(deg), 0.0, contact));
    }
    let m = r.finish();
    assert_eq!(m.payload.lifted_at_s, Some(2.0));
    // 8 * 0.5^t = 2 at t = 2 s after lift-off: that sample is not below 2° yet, the next is.
    let s = m.payload.settling_time_s.unwrap();
    assert!((s - 2.0).abs() < 1e-6, "{s}");
    assert!((m.payload.swing_max_deg.unwrap() - 8.0).abs() < 1e-6);
}

#[test]
fn z_steady_state_error_is_the_mean_over_the_last_window_of_the_last_move() {
    let mut r = recorder();
    let mut sp = MissionSetpoint {
        phase: MissionPhase::Takeoff,
        position_ned_m: [0.0, -0.8, -2.0],
        ..Default::default()
    };
    r.on_truth(&truth(0.0, 0.0, 0.0, ContactKind::Free));
    sp.phase_start_ns = 1_000_000_000;
    r.on_mission(0, &sp);
    for i in 1..=1000 {
        let t = i as f64 * 0.01;
        if i == 200 {
            sp.phase = MissionPhase::Move;
            sp.phase_index = 1;
            sp.phase_start_ns = 1_000_000_000 + 2_000_000_000;
            assert!(r.on_mission(0, &sp).is_some());
        }
        // Setpoint z -2.0, drone at -2.1: error -0.1 m.
        r.on_truth(&truth(t, 0.0, 0.0, ContactKind::Free));
    }
    let m = r.finish();
    assert_eq!(m.phases[1].start_s[0], Some(2.0));
    let z = m.drones[0].z_steady_state_error_m.unwrap();
    assert!((z + 0.1).abs() < 1e-9, "{z}");
    assert!((m.drones[0].position_rmse_m.unwrap() - 0.1).abs() < 1e-9);
    assert!(m.drones[1].position_rmse_m.is_none());
}
