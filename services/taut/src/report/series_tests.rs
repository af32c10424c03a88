use super::*;
use crate::report::latency::drone_spans;
use crate::sim::metrics::MetricsRecorder;
use shared_types::{AttitudeSetpoint, ContactKind, MissionSetpoint, VehicleState};

const T0: u64 = 5_000_000_000;

fn timed<T>(t_ns: u64, sample: T) -> Timed<T> {
    Timed {
        log_time_ns: t_ns + 10_000,
        sample,
    }
}

/// Yaw `deg` about NED z (down), as (w, x, y, z).
fn yaw(deg: f64) -> [f64; 4] {
    let h = deg.to_radians() / 2.0;
    [h.cos(), 0.0, 0.0, h.sin()]
}

fn tension(t_ns: u64, body: [f64; 3]) -> TensionSample {
    let mut s = TensionSample {
        force_body_n: body,
        ..Default::default()
    };
    s.header.t_origin_ns = t_ns;
    s.header.t_publish_ns = t_ns + 1_000_000;
    s
}

/// Drone uav2 (truth index 1): estimate yawed +90° until 1.5 s, then 180°; truth yawed −90°.
fn flight() -> (FlightData, DroneData) {
    let mut d = DroneData {
        id: "uav2".into(),
        truth_index: 1,
        ..Default::default()
    };
    for (t_s, q) in [(0.0, yaw(90.0)), (1.5, yaw(180.0))] {
        let mut s = VehicleState {
            attitude_wxyz: q,
            ..Default::default()
        };
        s.header.t_origin_ns = T0 + (t_s * 1e9) as u64;
        d.vehicle_state.push(timed(s.header.t_origin_ns, s));
    }
    for t_s in [1.0, 2.0] {
        let t = T0 + (t_s * 1e9) as u64;
        d.tension.push(timed(t, tension(t, [1.0, 0.0, 5.0])));
        d.tension_estimate
            .push(timed(t, tension(t, [0.0, 2.0, 4.0])));
    }
    for (t_s, flags) in [(1.0, setpoint_flags::IDLE), (2.0, 0)] {
        let sp = AttitudeSetpoint {
            step_ns: T0 + (t_s * 1e9) as u64,
            flags,
            tension_desired_ned_n: [1.0, 2.0, -3.0],
            shifted_position_ned_m: [0.5, 0.6, -2.0],
            ..Default::default()
        };
        d.attitude.push(timed(sp.step_ns, sp));
    }
    let mut truth = PlantTruth::default();
    truth.header.t_origin_ns = T0;
    truth.drones[1].body.attitude_wxyz = yaw(-90.0);
    truth.drones[1].anchor_force_frd_n = [1.0, 0.0, 5.0];
    truth.drones[0].body.attitude_wxyz = yaw(45.0);
    truth.drones[0].anchor_force_frd_n = [9.0, 9.0, 9.0];
    let f = FlightData {
        drones: vec![d.clone()],
        truth: vec![timed(T0, truth)],
        t0_ns: T0,
        ..Default::default()
    };
    (f, d)
}

fn values(series: &[Series], source: Source) -> Vec<(f64, f64)> {
    series
        .iter()
        .find(|s| s.source == source)
        .map(|s| s.points.clone())
        .unwrap_or_default()
}

fn close(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| (p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9)
}

#[test]
fn attitude_track_takes_the_newest_at_or_before() {
    let tr = AttitudeTrack::new([(20, yaw(20.0)), (10, yaw(10.0))]);
    let deg = |q: UnitQuaternion<f64>| q.euler_angles().2.to_degrees();
    assert!(
        (deg(tr.at(5).unwrap()) - 10.0).abs() < 1e-9,
        "before the start: the first"
    );
    assert!((deg(tr.at(10).unwrap()) - 10.0).abs() < 1e-9);
    assert!((deg(tr.at(19).unwrap()) - 10.0).abs() < 1e-9);
    assert!((deg(tr.at(25).unwrap()) - 20.0).abs() < 1e-9);
    assert!(AttitudeTrack::default().at(1).is_none());
}

#[test]
fn forces_are_the_pull_on_the_drone_in_ned() {
    let (f, d) = flight();
    let mut notes = Vec::new();
    let [x, y, z] = forces(&f, &d, &mut notes);
    assert!(notes.is_empty(), "{notes:?}");
    // Sensor (1, 0, 5) FRD: at 1 s yaw 90° -> NED (0, 1, 5); at 2 s yaw 180° -> (-1, 0, 5).
    assert!(close(
        &values(&x, Source::Sensor),
        &[(1.0, 0.0), (2.0, -1.0)]
    ));
    assert!(close(
        &values(&y, Source::Sensor),
        &[(1.0, 1.0), (2.0, 0.0)]
    ));
    assert!(close(
        &values(&z, Source::Sensor),
        &[(1.0, 5.0), (2.0, 5.0)]
    ));
    // Estimator (0, 2, 4) FRD: yaw 90° -> (-2, 0, 4); yaw 180° -> (0, -2, 4).
    assert!(close(
        &values(&x, Source::Estimator),
        &[(1.0, -2.0), (2.0, 0.0)]
    ));
    assert!(close(
        &values(&y, Source::Estimator),
        &[(1.0, 0.0), (2.0, -2.0)]
    ));
    // Truth: drone index 1 with its own attitude (yaw −90°): (1, 0, 5) -> (0, −1, 5).
    assert!(close(&values(&x, Source::Truth), &[(0.0, 0.0)]));
    assert!(close(&values(&y, Source::Truth), &[(0.0, -1.0)]));
    assert!(close(&values(&z, Source::Truth), &[(0.0, 5.0)]));
    // −T_d, flight steps only (the IDLE step at 1 s is left out).
    assert!(close(&values(&x, Source::Desired), &[(2.0, -1.0)]));
    assert!(close(&values(&y, Source::Desired), &[(2.0, -2.0)]));
    assert!(close(&values(&z, Source::Desired), &[(2.0, 3.0)]));
}

#[test]
fn without_vehicle_state_the_true_attitude_rotates_and_a_note_says_so() {
    let (mut f, mut d) = flight();
    d.vehicle_state.clear();
    f.drones[0].vehicle_state.clear();
    let mut notes = Vec::new();
    let [_, y, _] = forces(&f, &d, &mut notes);
    assert_eq!(notes.len(), 1, "{notes:?}");
    // Yaw −90°: (1, 0, 5) -> (0, −1, 5) at both times.
    assert!(close(
        &values(&y, Source::Sensor),
        &[(1.0, -1.0), (2.0, -1.0)]
    ));
    assert!(y.iter().any(|s| s.label.contains("true attitude")));
}

#[test]
fn positions_leave_out_idle_controller_steps() {
    let (f, d) = flight();
    let [x, _, z] = positions(&f, &d);
    assert!(close(&values(&x, Source::Shifted), &[(2.0, 0.5)]));
    assert!(close(&values(&z, Source::Shifted), &[(2.0, -2.0)]));
    assert!(close(
        &values(&x, Source::Estimate),
        &[(0.0, 0.0), (1.5, 0.0)]
    ));
}

fn swing_truth(t_s: f64, contact: ContactKind, tilt: f64) -> PlantTruth {
    let mut t = PlantTruth {
        sim_time_ns: (t_s * 1e9) as u64,
        payload_contact: contact,
        ..Default::default()
    };
    t.header.t_origin_ns = T0 + t.sim_time_ns;
    t.drones[0].body.position_ned_m = [0.1, -0.8, -2.1];
    t.drones[0].body.attitude_wxyz = [(tilt / 2.0).cos(), (tilt / 2.0).sin(), 0.0, 0.0];
    t.drones[1].body.position_ned_m = [-0.1, 0.7, -2.3];
    t.drones[1].body.attitude_wxyz = yaw(30.0);
    t.payload.position_ned_m = [0.4 * t_s, 0.05, -0.9];
    t
}

#[test]
fn swing_matches_the_flight_metrics() {
    let anchor = [0.0, 0.0, 0.08];
    let mut rec = MetricsRecorder::new(
        ["uav1".into(), "uav2".into()],
        vec!["move".into()],
        vec![true],
        anchor,
    );
    rec.on_truth(&swing_truth(0.0, ContactKind::Box, 0.0));
    let last = swing_truth(1.0, ContactKind::Free, 0.2);
    rec.on_truth(&last);
    let m = rec.finish().payload.final_swing_deg.expect("a swing");
    let mine = swing_deg(&last, anchor);
    assert!(mine.abs() > 5.0, "a non-trivial angle: {mine}");
    assert!((mine - m).abs() < 1e-12, "report {mine} vs metrics {m}");
    // Hand-computed case: level drones on the y axis, payload 1.2 m below, 10° across.
    let mut t = PlantTruth::default();
    t.drones[0].body.position_ned_m = [0.0, -0.8, -2.1];
    t.drones[1].body.position_ned_m = [0.0, 0.8, -2.1];
    t.drones[0].body.attitude_wxyz = [1.0, 0.0, 0.0, 0.0];
    t.drones[1].body.attitude_wxyz = [1.0, 0.0, 0.0, 0.0];
    t.payload.position_ned_m = [1.2 * 10f64.to_radians().tan(), 0.0, -2.1 + 0.08 + 1.2];
    assert!((swing_deg(&t, anchor) - 10.0).abs() < 1e-9);
}

#[test]
fn phases_become_spans_to_the_end() {
    let mut d = DroneData::default();
    for (t_s, phase) in [
        (0.0, MissionPhase::Idle),
        (0.5, MissionPhase::Idle),
        (1.0, MissionPhase::Takeoff),
        (2.0, MissionPhase::Move),
        (2.5, MissionPhase::Move),
    ] {
        let mut m = MissionSetpoint {
            phase,
            ..Default::default()
        };
        m.header.t_origin_ns = T0 + (t_s * 1e9) as u64;
        d.mission.push(timed(m.header.t_origin_ns, m));
    }
    let f = FlightData {
        t0_ns: T0,
        ..Default::default()
    };
    let p = phases(&f, &d, 4.0);
    let want = [
        (MissionPhase::Idle, 0.0, 1.0),
        (MissionPhase::Takeoff, 1.0, 2.0),
        (MissionPhase::Move, 2.0, 4.0),
    ];
    assert_eq!(p.len(), 3, "{p:?}");
    for (s, (ph, a, b)) in p.iter().zip(want) {
        assert_eq!(s.phase, ph);
        assert!(
            (s.from_s - a).abs() < 1e-9 && (s.to_s - b).abs() < 1e-9,
            "{s:?}"
        );
    }
}

#[test]
fn latency_spans_from_headers() {
    let (_, d) = flight();
    let spans = drone_spans(&d);
    let get = |name: &str| spans.iter().find(|s| s.span == name).unwrap();
    // Tension: publish − origin = 1 ms for both samples.
    assert_eq!(get("tension stage").count(), 2);
    assert!((get("tension stage").quantile_ms(0.5) - 1.0).abs() < 1e-3);
    // Setpoints carry no input origins here: nothing recorded.
    assert_eq!(get("controller from tension").count(), 0);
    // Transport: log time − publish time, every channel. The tension samples were logged
    // before their publication (10 µs after origin, published 1 ms after): 4 negatives; the
    // states and setpoints (publish 0) count.
    assert_eq!(get("recorder transport").count(), 4);
    assert_eq!(get("recorder transport").negatives, 4);
}
