use super::*;

fn close(a: Vector3<f64>, b: [f64; 3], tol: f64) -> bool {
    (a - path::v3(b)).norm() < tol
}

#[test]
fn built_in_scenarios_parse_and_validate() {
    let a = Scenario::load("test-a").unwrap();
    assert_eq!(a.phases.len(), 3);
    assert_eq!(a.payload.start, PayloadStart::Resting);
    let b = Scenario::load("test-b").unwrap();
    assert_eq!(b.obstacles.len(), 2);
    assert_eq!(b.drones[1].start, DroneStart::Hover);
}

#[test]
fn test_a_moves_two_metres() {
    let a = Scenario::load("test-a").unwrap();
    let paths = a.paths_of(0);
    let before = paths[0].end();
    let after = paths[1].end();
    assert!(((before - after).xy().norm() - 2.0).abs() < 1e-12);
    // The step takes effect at once.
    assert!(close(
        paths[1].sample(0.0).position_ned_m,
        [-1.0, -0.8, -2.1],
        1e-12
    ));
}

#[test]
fn test_b_round_trip_returns_to_start_and_threads_the_gap() {
    let b = Scenario::load("test-b").unwrap();
    for k in 0..2 {
        let paths = b.paths_of(k);
        let start = b.takeoff_point(k);
        assert!(
            (paths.last().unwrap().end() - start).norm() < 1e-9,
            "drone {k}"
        );
        let (pass, back) = (&paths[1], &paths[3]);
        assert!((pass.duration_s() - 5.0).abs() < 1e-12);
        assert!((back.duration_s() - 5.0).abs() < 1e-12);
        // Formation restored after the passage: mirror image across x = 0.
        let mid = pass.end();
        assert!((mid.x + start.x).abs() < 1e-9 && (mid.y - start.y).abs() < 1e-9);
        // Never inside a wall (grown by the drone's 0.35 m reach), sampled every 10 ms.
        for p in [pass, back] {
            let mut t = 0.0;
            while t <= p.duration_s() {
                let s = p.sample(t).position_ned_m;
                for o in &b.obstacles {
                    assert!(!o.contains(&s, 0.35), "drone {k} at {s:?} hits {}", o.name);
                }
                t += 0.01;
            }
        }
    }
}

#[test]
fn paths_are_continuous_with_consistent_feed_forward() {
    let b = Scenario::load("test-b").unwrap();
    let p = &b.paths_of(0)[1];
    let dt = 1e-4;
    let mut t = 0.0;
    while t + dt <= p.duration_s() {
        let (s0, s1) = (p.sample(t), p.sample(t + dt));
        let jump = (s1.position_ned_m - s0.position_ned_m).norm();
        assert!(jump < 1e-3, "jump {jump} at {t}");
        let fd = (s1.position_ned_m - s0.position_ned_m) / dt;
        let v = (s0.velocity_ned_m_s + s1.velocity_ned_m_s) / 2.0;
        assert!((fd - v).norm() < 1e-3, "velocity {v:?} vs {fd:?} at {t}");
        t += 0.0137;
    }
}

#[test]
fn arc_has_centripetal_acceleration() {
    let p = Path::new(
        Vector3::new(1.0, 0.0, -1.0),
        vec![Segment::Arc {
            center_ned_m: [0.0, 0.0],
            sweep_deg: 90.0,
            duration_s: 2.0,
        }],
    );
    let end = p.end();
    assert!((end - Vector3::new(0.0, 1.0, -1.0)).norm() < 1e-12);
    let mid = p.sample(1.0);
    // Peak angular rate of the min-jerk law: 1.875 * sweep / duration.
    let w = 1.875 * std::f64::consts::FRAC_PI_2 / 2.0;
    assert!((mid.velocity_ned_m_s.norm() - w).abs() < 1e-9);
    let radial = -mid.position_ned_m.xy().normalize();
    let a_c = mid.acceleration_ned_m_s2.xy().dot(&radial);
    assert!((a_c - w * w).abs() < 1e-9);
}

#[test]
fn errors_name_the_key() {
    let text = Scenario::load("test-a")
        .map(|_| super::TEST_A.replace("id = \"uav2\"", "id = \"uav1\""))
        .unwrap();
    let e = Scenario::from_toml_str("x", &text).unwrap_err().to_string();
    assert!(e.contains("drones[1].id"), "{e}");
    let text = super::TEST_A.replace(
        "to_ned_m = [-1.0, 0.8, -2.1]",
        "to_ned_m = [-1.0, 0.8, -3.1]",
    );
    let e = Scenario::from_toml_str("x", &text).unwrap_err().to_string();
    assert!(e.contains("outside the arena") && e.contains("uav2"), "{e}");
    let text = super::TEST_A.replace("timeout_s = 25.0", "timeout_s = -1.0");
    let e = Scenario::from_toml_str("x", &text).unwrap_err().to_string();
    assert!(e.contains("phases[1].timeout_s"), "{e}");
    let text = super::TEST_A.replace("kind = \"move\"", "kind = \"hover\"");
    assert!(Scenario::from_toml_str("x", &text).is_err());
}

#[test]
fn tracker_ends_a_phase_only_after_both_settle() {
    let a = Scenario::load("test-a").unwrap();
    let mut tr = PhaseTracker::new(&a, 0.0);
    let top = [
        tr.setpoint(0, 100.0).position_ned_m,
        tr.setpoint(1, 100.0).position_ned_m,
    ];
    // Path still running at 2 s: not ready even when on the setpoint.
    let on_path = [
        tr.setpoint(0, 2.0).position_ned_m,
        tr.setpoint(1, 2.0).position_ned_m,
    ];
    assert_eq!(tr.update(2.0, &on_path), PhaseEvent::Running);
    // Both at the top from 4 s; one drone 0.31 m off until 4.5 s.
    let off = [top[0] + Vector3::new(0.31, 0.0, 0.0), top[1]];
    assert_eq!(tr.update(4.0, &off), PhaseEvent::Running);
    assert_eq!(tr.update(4.5, &top), PhaseEvent::Running);
    assert_eq!(tr.update(5.49, &top), PhaseEvent::Running);
    assert_eq!(tr.update(5.5, &top), PhaseEvent::Ended { finished: 0 });
    assert_eq!(tr.phase(), 1);
    assert_eq!(tr.phase_starts_s()[1], 5.5);
    // The move phase's setpoint is the step target at once.
    assert!(close(
        tr.setpoint(0, 5.5).position_ned_m,
        [-1.0, -0.8, -2.1],
        1e-12
    ));
    // Timeout after 25 s in the phase.
    assert_eq!(tr.update(30.4, &top), PhaseEvent::Running);
    assert_eq!(tr.update(30.6, &top), PhaseEvent::TimedOut { phase: 1 });
    assert!(tr.timed_out());
}
