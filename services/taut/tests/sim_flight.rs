//! End to end: `taut sim` flies the paper's two tests plant-in-the-loop with the real service
//! processes (plant in real time, per drone sampler, tension, bridge, controller and mission),
//! with the motion-capture position noise on, and its summary.json is checked. The fast mode
//! flies the same scenario and seed in process; the two summaries must agree within the
//! tolerances stated below.
//!
//! The flights are serialised: each takes the whole (2-core) machine in real time.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");
static ONE_FLIGHT_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Bound on Test A's swing settling time (below 2° after the payload leaves the box), s.
/// Measured 9.4-13.4 s over seeds 1-3 in fast mode and 9.6-10.5 s for seed 1 in real time; the bound
/// leaves room for a loaded machine.
const TEST_A_SETTLING_BOUND_S: f64 = 15.0;

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("taut-sim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Runs `taut sim ARGS --out DIR` and returns (exit success, summary).
fn fly(args: &[&str], out: &Path) -> (bool, Value) {
    let output = Command::new(TAUT)
        .arg("sim")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("start taut sim");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    eprintln!("--- taut sim {args:?}\n{stdout}{stderr}");
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap_or_else(|e| {
        panic!(
            "no summary.json in {}: {e}\n{stdout}{stderr}",
            out.display()
        )
    });
    (
        output.status.success(),
        serde_json::from_str(&text).unwrap(),
    )
}

fn f(v: &Value, path: &[&str]) -> f64 {
    let mut x = v;
    for p in path {
        x = &x[*p];
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("{path:?} is not a number in {v:#}"))
}

fn drone(v: &Value, k: usize, key: &str) -> f64 {
    v["drones"][k][key]
        .as_f64()
        .unwrap_or_else(|| panic!("drones[{k}].{key} is not a number in {v:#}"))
}

/// Test A's acceptance: lift-off, the swing settles below 2° within the bound, both drones end
/// within 0.3 m, no failsafe, exit 0.
fn check_test_a(ok: bool, s: &Value) {
    assert!(ok, "taut sim test-a failed: {s:#}");
    assert_eq!(s["success"], true);
    assert_eq!(s["failsafe_fired"], false);
    assert_eq!(s["crashed"], false);
    assert!(
        f(s, &["payload", "lifted_at_s"]) > 0.0,
        "the payload never left the box"
    );
    let settle = f(s, &["payload", "settling_time_s"]);
    assert!(
        settle <= TEST_A_SETTLING_BOUND_S,
        "swing settled after {settle} s (bound {TEST_A_SETTLING_BOUND_S} s)"
    );
    for k in 0..2 {
        let e = drone(s, k, "final_position_error_m");
        assert!(e < 0.3, "drone {k} ends {e} m from its setpoint");
        assert_eq!(s["drones"][k]["failsafe_count"], 0);
    }
}

const CHECK_RECORDING: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/check_recording.py");

/// The acceptance test of the recorder: the PyPI `mcap` reader opens the real-time
/// flight's recording, lists every channel with its schema, decodes every message, and finds
/// per topic exactly what the services published minus the recorded drops (zero drops expected:
/// each of the recorder's subscribers buffers 256 samples). Then the Rust reader: both drones,
/// the truth, and their configs.
fn check_recording(out: &Path) {
    let output = Command::new("python3")
        .arg(CHECK_RECORDING)
        .arg(out)
        .output()
        .expect("python3 (run scripts/setup.sh for the mcap package)");
    let stdout = String::from_utf8_lossy(&output.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&output.stderr));
    assert!(output.status.success(), "check_recording.py failed");
    let result: Value = serde_json::from_str(
        stdout
            .lines()
            .last()
            .and_then(|l| l.strip_prefix("RESULT "))
            .expect("a RESULT line"),
    )
    .unwrap();
    assert_eq!(result["drops"], 0, "{result}");
    // Per drone at least: raw ADC, tension, vehicle state, IMU, motor speeds, mission and
    // attitude setpoints; plus the truth.
    const AT_LEAST: u64 = 2 * 7 + 1;
    let channels = result["channels"].as_u64().unwrap();
    assert!(channels >= AT_LEAST, "{channels} channels: {result}");
    let rec = recorder::Recording::open(&out.join("recording.mcap")).unwrap();
    assert!(!rec.truncated);
    let mut uavs = rec.uavs();
    uavs.sort();
    assert_eq!(uavs, ["uav1", "uav2"]);
    for uav in ["uav1", "uav2"] {
        let sp = rec
            .samples::<shared_types::AttitudeSetpoint>(uav, shared_types::names::ATTITUDE_SETPOINT)
            .unwrap();
        assert!(sp.len() > 1000, "{uav}: {} setpoints", sp.len());
        assert!(rec.attachments.contains_key(&format!("config/{uav}.toml")));
    }
    let truth = rec
        .samples::<shared_types::PlantTruth>(shared_types::names::PLANT, shared_types::names::TRUTH)
        .unwrap();
    assert!(truth.len() > 1000, "{} truth samples", truth.len());
}

/// `taut replay` runs each drone's controller library again on the recorded inputs: every
/// recorded attitude setpoint must come out bit for bit.
fn check_replay(out: &Path) {
    let output = Command::new(TAUT)
        .arg("replay")
        .arg(out.join("recording.mcap"))
        .output()
        .expect("start taut replay");
    let stdout = String::from_utf8_lossy(&output.stdout);
    eprintln!(
        "--- taut replay\n{stdout}{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(output.status.success(), "replay differs: {stdout}");
    for uav in ["uav1", "uav2"] {
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&format!("{uav}: ")))
            .unwrap_or_else(|| panic!("no replay line for {uav}: {stdout}"));
        assert!(
            line.ends_with("setpoints replayed, all bit for bit"),
            "{line}"
        );
        let n: u64 = line[uav.len() + 2..]
            .split(' ')
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or(0);
        assert!(n > 1000, "{line}");
    }
}

/// `taut sim` wrote the report of its recording: every figure and the markdown.
fn check_report(out: &Path) {
    let dir = out.join("report");
    for f in [
        "report.md",
        "positions_uav1.png",
        "positions_uav2.png",
        "forces_uav1.png",
        "forces_uav2.png",
        "payload.png",
        "latency_uav1.png",
        "latency_uav2.png",
    ] {
        let len = std::fs::metadata(dir.join(f)).map_or(0, |m| m.len());
        assert!(len > 1000, "{}: {len} bytes", dir.join(f).display());
    }
}

#[test]
fn test_a_real_time_then_fast_agree() {
    let _one = ONE_FLIGHT_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let rt_out = out_dir("a-rt");
    let (ok, rt) = fly(&["test-a", "--seed", "1"], &rt_out);
    check_test_a(ok, &rt);
    check_recording(&rt_out);
    check_replay(&rt_out);
    check_report(&rt_out);
    // Real-time latency was measured (tension sample to attitude setpoint, both drones).
    for span in ["uav1_tension_to_setpoint", "uav2_tension_to_setpoint"] {
        let p99 = f(&rt, &["latency_us", span, "p99"]);
        assert!(p99 > 0.0 && p99 < 50_000.0, "{span} p99 = {p99} µs");
    }

    let fast_out = out_dir("a-fast");
    let (ok, fast) = fly(&["test-a", "--seed", "1", "--fast"], &fast_out);
    check_test_a(ok, &fast);
    check_replay(&fast_out);
    // The simulation's own speed, without writing the recording (JSON + zstd of ~190 000
    // samples costs about 0.5 s of the 0.7 s a recorded fast Test A takes).
    let bare_out = out_dir("a-fast-bare");
    let (ok, bare) = fly(
        &["test-a", "--seed", "1", "--fast", "--no-recording"],
        &bare_out,
    );
    check_test_a(ok, &bare);
    assert!(
        f(&bare, &["sim_s"]) / f(&bare, &["wall_s"]) >= 100.0,
        "fast mode below 100x"
    );
    let _ = std::fs::remove_dir_all(&bare_out);

    // Comparable: same phases in the same order, and the metrics within tolerances that cover
    // what differs (scheduling delays of 0.1-5 ms, sensor read at nominal instants, the real
    // run's timing noise changing the perturbation's realisation relative to the trajectory).
    // Phase timing relative to the take-off (the real-time services take about a second longer
    // to start than the in-process ones, so absolute times are offset).
    let start = |s: &Value, i: usize| s["phases"][i]["start_s"][0].as_f64().unwrap();
    for i in 1..rt["phases"].as_array().unwrap().len() {
        let a = start(&rt, i) - start(&rt, 0);
        let b = start(&fast, i) - start(&fast, 0);
        assert!(
            (a - b).abs() < 2.0,
            "phase {i} starts {a} s vs {b} s after take-off"
        );
    }
    let close = |what: &str, a: f64, b: f64, abs: f64, rel: f64| {
        assert!(
            (a - b).abs() <= abs + rel * a.abs().max(b.abs()),
            "{what}: real time {a} vs fast {b} (tolerance {abs} + {rel} relative)"
        );
    };
    close(
        "max cable force",
        f(&rt, &["max_cable_force_n"]),
        f(&fast, &["max_cable_force_n"]),
        1.0,
        0.25,
    );
    close(
        "swing RMS",
        f(&rt, &["payload", "swing_rms_deg"]),
        f(&fast, &["payload", "swing_rms_deg"]),
        1.0,
        0.3,
    );
    close(
        "swing settling time",
        f(&rt, &["payload", "settling_time_s"]),
        f(&fast, &["payload", "settling_time_s"]),
        3.0,
        0.3,
    );
    for k in 0..2 {
        close(
            "position RMSE",
            drone(&rt, k, "position_rmse_m"),
            drone(&fast, k, "position_rmse_m"),
            0.05,
            0.25,
        );
        close(
            "tension RMSE",
            drone(&rt, k, "tension_rmse_n"),
            drone(&fast, k, "tension_rmse_n"),
            0.3,
            0.3,
        );
        close(
            "z steady-state error",
            drone(&rt, k, "z_steady_state_error_m"),
            drone(&fast, k, "z_steady_state_error_m"),
            0.05,
            0.0,
        );
    }
    let _ = std::fs::remove_dir_all(&rt_out);
    let _ = std::fs::remove_dir_all(&fast_out);
}

#[test]
fn test_b_round_trip_in_real_time() {
    let _one = ONE_FLIGHT_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let out = out_dir("b-rt");
    let (ok, s) = fly(&["test-b", "--seed", "1"], &out);
    assert!(ok, "taut sim test-b failed: {s:#}");
    assert_eq!(s["failsafe_fired"], false);
    assert_eq!(s["crashed"], false);
    let phases = s["phases"].as_array().unwrap();
    assert_eq!(phases.len(), 4);
    for p in phases {
        assert!(
            p["start_s"][0].is_number(),
            "phase {} never started",
            p["name"]
        );
    }
    // Every phase ended by the phase rule (within 0.3 m for 1 s, on each drone's own estimate),
    // which `success` and exit 0 already say; the last phase's end is the round trip's end.
    assert_eq!(s["success"], true);
    assert!(f(&s, &["sim_s"]) > phases[3]["start_s"][0].as_f64().unwrap() + 5.0);
    check_report(&out);
    let _ = std::fs::remove_dir_all(&out);
}
