//! End to end: the real `taut` processes (emulated sensor, sampler, tension) on this machine.

use serde_json::Value;
use std::process::Command;
use std::sync::Mutex;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");
/// Full scale on z: 5.5 kg-force (the paper's tested range).
const FS_Z: f64 = 5.5 * 9.80665;

/// The chains measure rate and latency, and the embedded config pins every service to core 1
/// at SCHED_FIFO: run one chain at a time so tests do not measure each other.
static ONE_CHAIN_AT_A_TIME: Mutex<()> = Mutex::new(());

fn sensor(args: &[&str]) -> Value {
    let _one = ONE_CHAIN_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let out = Command::new(TAUT)
        .args(["sensor", "--sim", "--json"])
        .args(args)
        .output()
        .expect("run taut");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "taut sensor failed: {stderr}");
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("bad JSON ({e}): {stderr}"))
}

fn mean(v: &Value) -> [f64; 3] {
    let m = v["mean_force_n"].as_array().unwrap();
    [0, 1, 2].map(|k| m[k].as_f64().unwrap())
}

#[test]
fn hanging_load_reads_within_one_percent_fs_at_240_hz() {
    let v = sensor(&["--load", "0,0,9.81", "--duration", "5"]);
    let m = mean(&v);
    for (k, want) in [0.0, 0.0, 9.81].iter().enumerate() {
        assert!(
            (m[k] - want).abs() < 0.01 * FS_Z,
            "axis {k}: {} vs {want}: {v}",
            m[k]
        );
    }
    let rate = v["rate_hz"].as_f64().unwrap();
    assert!((rate - 240.0).abs() < 2.4, "rate {rate}");
    assert!(v["samples"].as_u64().unwrap() > 1000);
    // A loaded machine may delay a poll past a frame deadline now and then: flagged, rare.
    let samples = v["samples"].as_u64().unwrap();
    assert!(v["flagged"].as_u64().unwrap() * 50 < samples, "{v}");
    for span in [
        "adc",
        "raw_to_tension",
        "sample_to_tension",
        "tension_to_monitor",
    ] {
        for p in ["p50", "p99", "p999", "max"] {
            assert!(
                v["latency_us"][span][p].as_f64().unwrap() > 0.0,
                "{span}.{p}: {v}"
            );
        }
    }
}

#[test]
fn lateral_load_is_read_on_every_axis() {
    let v = sensor(&["--load", "4,-3,12", "--duration", "3"]);
    let m = mean(&v);
    for (k, want) in [4.0, -3.0, 12.0].iter().enumerate() {
        assert!(
            (m[k] - want).abs() < 0.01 * FS_Z,
            "axis {k}: {} vs {want}: {v}",
            m[k]
        );
    }
}

#[test]
fn a_silent_chip_is_flagged_and_the_chain_keeps_its_rate() {
    let v = sensor(&[
        "--load",
        "0,0,9.81",
        "--duration",
        "2",
        "--fault",
        "silent:2",
    ]);
    assert!(v["flags"]["stale_input"].as_u64().unwrap() > 100, "{v}");
    assert!(v["bus_errors"].as_u64().unwrap() > 100, "{v}");
    let rate = v["rate_hz"].as_f64().unwrap();
    assert!((rate - 240.0).abs() < 2.4, "rate {rate}");
}

#[test]
fn synchronous_mode_has_no_skew() {
    let v = sensor(&[
        "--load",
        "0,0,9.81",
        "--duration",
        "2",
        "--mode",
        "synchronous",
    ]);
    assert!(v["skew_us"]["p50"].as_f64().unwrap() < 50.0, "{v}");
    assert!((v["mean_force_n"][2].as_f64().unwrap() - 9.81).abs() < 0.01 * FS_Z);
}

#[test]
fn config_check_names_the_bad_key() {
    let dir = std::env::temp_dir().join(format!("taut-cfgtest-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("good.toml");
    std::fs::write(&good, rt_config_text()).unwrap();
    let out = Command::new(TAUT)
        .args(["config", "check"])
        .arg(&good)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("window = 4"));
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        rt_config_text().replace("window = 4", "window = 4\nwindow_s = 1"),
    )
    .unwrap();
    let out = Command::new(TAUT)
        .args(["config", "check"])
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("window_s"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn rt_config_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/sim-uav1.toml"
    ))
    .unwrap()
}
