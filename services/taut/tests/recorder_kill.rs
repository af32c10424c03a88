//! The recorder service (`taut svc recorder --config FILE`) killed with SIGKILL mid-run: the
//! file still reads, with the Rust reader and the PyPI `mcap` reader, and lost no more than its
//! last chunk. A publisher in this test sends tension samples at 1 kHz (and a 50 Hz mission
//! setpoint) on a private iceoryx2 root; the recorder's chunk period is 0.5 s.

use recorder::Recording;
use shared_types::{names, MissionSetpoint, TensionSample};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use taut_ipc::Ipc;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");
const CHECK: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/py/check_recording.py");
const CHUNK_PERIOD_S: f64 = 0.5;
const RATE_HZ: f64 = 1000.0;
/// Besides the open chunk, what the recorder may hold that is not yet written when killed: one
/// poll period (5 ms) and scheduling on a loaded 2-core machine. 100 ms of samples.
const SLACK_S: f64 = 0.1;

fn config(dir: &Path, uav: &str, root: &str) -> PathBuf {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/sim-uav1.toml"
    ))
    .unwrap()
    .replace("uav = \"uav1\"", &format!("uav = \"{uav}\""))
    .replace("ipc_root = \"\"", &format!("ipc_root = \"{root}\""))
    .replace("enabled = false", "enabled = true")
    .replace(
        "dir = \"recordings\"",
        &format!("dir = \"{}\"", dir.join("rec").display()),
    )
    .replace(
        "chunk_period_s = 1.0",
        &format!("chunk_period_s = {CHUNK_PERIOD_S}"),
    );
    let p = dir.join("drone.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn sigkill_loses_at_most_the_last_chunk() {
    let id = std::process::id();
    let dir = std::env::temp_dir().join(format!("taut-reckill-{id}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (uav, root) = (format!("k{id}"), format!("test-{id}-kill"));
    let cfg = config(&dir, &uav, &root);
    let ready = dir.join("ready");
    let mut rec = Command::new(TAUT)
        .args(["svc", "recorder", "--config"])
        .arg(&cfg)
        .arg("--ready")
        .arg(&ready)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let end = Instant::now() + Duration::from_secs(10);
    while !ready.exists() {
        assert!(Instant::now() < end, "the recorder did not subscribe");
        std::thread::sleep(Duration::from_millis(10));
    }

    let ipc = Ipc::new(&format!("reckill-pub-{id}"), &root, &uav).unwrap();
    let mut tension = ipc.publisher::<TensionSample>(names::TENSION).unwrap();
    let mut mission = ipc
        .publisher::<MissionSetpoint>(names::MISSION_SETPOINT)
        .unwrap();
    let period = Duration::from_secs_f64(1.0 / RATE_HZ);
    let start = Instant::now();
    let mut next = start;
    // 2.7 s: five closed chunks, the kill lands inside the sixth.
    while start.elapsed() < Duration::from_millis(2700) {
        let s = TensionSample {
            force_body_n: [0.0, 0.0, tension.published() as f64],
            ..Default::default()
        };
        tension.publish(s).unwrap();
        if tension.published().is_multiple_of(20) {
            mission.publish(MissionSetpoint::default()).unwrap();
        }
        next += period;
        if let Some(d) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(d);
        }
    }
    rec.kill().unwrap(); // SIGKILL
    rec.wait().unwrap();
    let sent = tension.published();
    let sent_mission = mission.published();
    let actual_rate = sent as f64 / start.elapsed().as_secs_f64();

    let files: Vec<_> = std::fs::read_dir(dir.join("rec"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    let file = &files[0];
    let name = file.file_name().unwrap().to_string_lossy().to_string();
    assert!(name.starts_with(&uav) && name.ends_with("Z.mcap"), "{name}");

    // Rust reader: a gap-free prefix of what was sent, flagged truncated, config attached.
    let r = Recording::open(file).unwrap();
    assert!(r.truncated, "a killed file has no footer");
    let got = r.samples::<TensionSample>(&uav, names::TENSION).unwrap();
    for (i, t) in got.iter().enumerate() {
        assert_eq!(t.sample.header.sequence, i as u64, "gap at {i}");
        assert_eq!(t.sample.force_body_n[2], i as f64);
    }
    let lost = sent - got.len() as u64;
    let bound = ((CHUNK_PERIOD_S + SLACK_S) * actual_rate).ceil() as u64;
    eprintln!(
        "sent {sent} tension samples at {actual_rate:.0} Hz, recovered {}, lost {lost} (bound {bound}); mission {} of {sent_mission}",
        got.len(),
        r.samples::<MissionSetpoint>(&uav, names::MISSION_SETPOINT)
            .unwrap()
            .len()
    );
    assert!(
        lost <= bound,
        "lost {lost} > {bound} = one chunk period + slack"
    );
    assert!(got.len() as u64 >= sent / 2, "recovered only {}", got.len());
    let attached = String::from_utf8(r.attachments[&format!("config/{uav}.toml")].clone()).unwrap();
    assert!(attached.contains(&format!("uav = \"{uav}\"")));
    assert_eq!(r.meta("taut.recording", "uavs"), Some(uav.as_str()));

    // The PyPI reader reads the same prefix.
    let out = Command::new("python3")
        .arg(CHECK)
        .arg("--killed")
        .arg(file)
        .output()
        .expect("python3");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "python check failed");
    let result: serde_json::Value = serde_json::from_str(
        stdout
            .lines()
            .last()
            .and_then(|l| l.strip_prefix("RESULT "))
            .expect("a RESULT line"),
    )
    .unwrap();
    let topic = format!("/{uav}/{}", names::TENSION);
    assert_eq!(
        result["counts"][&topic].as_u64(),
        Some(got.len() as u64),
        "{result}"
    );
    drop((tension, mission, ipc));
    // The killed recorder's node and ports.
    taut_ipc::Ipc::cleanup_dead_nodes(&format!("reckill-cleanup-{id}")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
