//! Real-peer end-to-end test of `taut plant`: pymavlink (`tests/py/plant_offboard.py`) flies
//! drone uav1 of scenario test-a over UDP, like a companion computer against PX4 SITL: mode and
//! arming against the offboard availability rule, a climb and hold on an altitude PD in
//! attitude offboard, attitude + body rates, garbage on the link, and the offboard-loss
//! failsafe (AUTO.LAND, descent, auto-disarm). The plant's JSON report is then checked.
//! Needs python3 with pymavlink; fails (does not skip) without them.

use std::io::Read;
use std::net::UdpSocket;
use std::path::PathBuf;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use serde_json::Value;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");
/// The plant stops by itself after this long if nothing else stops it, s.
const PLANT_DURATION_S: u32 = 40;
/// The script normally needs ~15 s.
const SCRIPT_TIMEOUT: Duration = Duration::from_secs(38);

/// A child process that is stopped (SIGTERM, then SIGKILL) and reaped on every path, with its
/// stdout and stderr collected by reader threads.
struct ChildGuard {
    name: &'static str,
    child: Child,
    stdout: Option<JoinHandle<String>>,
    stderr: Option<JoinHandle<String>>,
}

fn read_all(mut r: impl Read + Send + 'static) -> JoinHandle<String> {
    thread::spawn(move || {
        let mut buf = Vec::new();
        let _ = r.read_to_end(&mut buf);
        String::from_utf8_lossy(&buf).into_owned()
    })
}

impl ChildGuard {
    fn spawn(name: &'static str, cmd: &mut Command) -> Self {
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {name} ({cmd:?}): {e}"));
        let stdout = child.stdout.take().map(read_all);
        let stderr = child.stderr.take().map(read_all);
        ChildGuard {
            name,
            child,
            stdout,
            stderr,
        }
    }

    fn signal(&self, sig: i32) {
        // SAFETY: kill(2) on the pid of our own child, which is not reaped yet.
        unsafe { libc::kill(self.child.id() as libc::pid_t, sig) };
    }

    /// Waits up to `timeout` for the process to exit.
    fn wait_timeout(&mut self, timeout: Duration) -> Option<ExitStatus> {
        let end = Instant::now() + timeout;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => return Some(status),
                Ok(None) if Instant::now() < end => thread::sleep(Duration::from_millis(20)),
                _ => return None,
            }
        }
    }

    /// Stdout and stderr, once the process has exited (or been killed).
    fn output(&mut self) -> (String, String) {
        let take = |h: &mut Option<JoinHandle<String>>| {
            h.take()
                .map(|h| h.join().unwrap_or_default())
                .unwrap_or_default()
        };
        (take(&mut self.stdout), take(&mut self.stderr))
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            // SIGTERM first so the plant releases its iceoryx2 resources, then SIGKILL.
            self.signal(libc::SIGTERM);
            if self.wait_timeout(Duration::from_secs(3)).is_none() {
                eprintln!("{}: no exit 3 s after SIGTERM, killing it", self.name);
                let _ = self.child.kill();
                let _ = self.child.wait();
            }
        }
    }
}

/// A temporary folder removed on every path.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A UDP port `p` such that `p` and `p + 1` are both free on 127.0.0.1 (drone i uses `p + i`)
/// and not in `avoid`.
fn free_udp_port_pair(avoid: &[u16]) -> u16 {
    for _ in 0..100 {
        let a = UdpSocket::bind("127.0.0.1:0").expect("bind a UDP port");
        let p = a.local_addr().expect("local address").port();
        if p == u16::MAX || avoid.iter().any(|&q| q.abs_diff(p) <= 1) {
            continue;
        }
        if UdpSocket::bind(("127.0.0.1", p + 1)).is_ok() {
            return p;
        }
    }
    panic!("no pair of adjacent free UDP ports found in 100 tries");
}

fn require_pymavlink() {
    let out = Command::new("python3")
        .args(["-c", "import pymavlink"])
        .output()
        .unwrap_or_else(|e| {
            panic!("python3 is required for this test and could not be started: {e}")
        });
    assert!(
        out.status.success(),
        "pymavlink is required for this test (pip install pymavlink): {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn u64_at(v: &Value, path: &str) -> u64 {
    v.pointer(path)
        .and_then(Value::as_u64)
        .unwrap_or_else(|| panic!("report has no unsigned integer at {path}: {v}"))
}

fn f64_at(v: &Value, path: &str) -> f64 {
    v.pointer(path)
        .and_then(Value::as_f64)
        .unwrap_or_else(|| panic!("report has no number at {path}: {v}"))
}

#[test]
fn pymavlink_companion_flies_uav1_through_offboard_loss() {
    require_pymavlink();
    let script: PathBuf = [
        env!("CARGO_MANIFEST_DIR"),
        "tests",
        "py",
        "plant_offboard.py",
    ]
    .iter()
    .collect();
    let pid = std::process::id();
    let dir = TempDir(std::env::temp_dir().join(format!("taut-plant-mavlink-{pid}")));
    std::fs::create_dir_all(&dir.0).expect("create the socket folder");
    let remote_port = free_udp_port_pair(&[]);
    let local_port = free_udp_port_pair(&[remote_port]);

    let mut plant = ChildGuard::spawn(
        "taut plant",
        Command::new(TAUT)
            .arg("plant")
            .args([
                "--scenario",
                "test-a",
                "--no-noise",
                "--seed",
                "1",
                "--json",
            ])
            .args(["--duration", &PLANT_DURATION_S.to_string()])
            .args(["--remote-port", &remote_port.to_string()])
            .args(["--local-port", &local_port.to_string()])
            .arg("--socket-dir")
            .arg(&dir.0)
            .args(["--ipc-root", &format!("test-plant-{pid}")]),
    );
    let mut peer = ChildGuard::spawn(
        "plant_offboard.py",
        Command::new("python3").arg(&script).args([
            "--port",
            &remote_port.to_string(),
            "--sysid",
            "1",
        ]),
    );

    let status = peer.wait_timeout(SCRIPT_TIMEOUT);
    if status.is_none() {
        let _ = peer.child.kill();
        let _ = peer.child.wait();
    }
    let (peer_out, peer_err) = peer.output();
    println!("companion summary: {peer_out}");
    let plant_running = matches!(plant.child.try_wait(), Ok(None));
    plant.signal(libc::SIGTERM);
    let plant_status = plant.wait_timeout(Duration::from_secs(10));
    let (report, plant_err) = plant.output();
    let Some(status) = status else {
        panic!(
            "plant_offboard.py did not finish within {SCRIPT_TIMEOUT:?}\n--- stderr:\n{peer_err}\n\
             --- stdout:\n{peer_out}\n--- plant stderr:\n{plant_err}"
        );
    };
    assert!(
        status.success(),
        "plant_offboard.py failed ({status}):\n--- stderr:\n{peer_err}\n--- stdout:\n{peer_out}\n\
         --- plant stderr:\n{plant_err}\n--- plant report:\n{report}"
    );
    assert!(
        plant_running,
        "the plant exited before the script finished:\n{plant_err}\n{report}"
    );
    let plant_status = plant_status.expect("taut plant did not stop within 10 s of SIGTERM");
    assert!(
        plant_status.success(),
        "taut plant failed ({plant_status}):\n{plant_err}\n{report}"
    );

    let r: Value = serde_json::from_str(&report)
        .unwrap_or_else(|e| panic!("plant report is not JSON ({e}):\n{report}\n{plant_err}"));
    let summary: Value = serde_json::from_str(peer_out.trim()).unwrap_or(Value::Null);
    println!(
        "plant: {:.2} s wall, {:.2} s simulated, {} ticks, overruns {}, late ticks {}, \
         max sim lag {:.2} ms",
        f64_at(&r, "/wall_s"),
        f64_at(&r, "/sim_s"),
        u64_at(&r, "/ticks"),
        u64_at(&r, "/overruns"),
        u64_at(&r, "/late_ticks"),
        f64_at(&r, "/max_sim_lag_ms")
    );
    for name in ["jitter_us", "tick_work_us", "step_us"] {
        println!(
            "  {name:<12} count {:>6}  p50 {:8.1}  p99 {:8.1}  p99.9 {:8.1}  max {:8.1} µs",
            u64_at(&r, &format!("/{name}/count")),
            f64_at(&r, &format!("/{name}/p50")),
            f64_at(&r, &format!("/{name}/p99")),
            f64_at(&r, &format!("/{name}/p999")),
            f64_at(&r, &format!("/{name}/max")),
        );
    }
    println!("  link 0: {}", r["links"][0]);
    for key in [
        "failsafe_after_s",
        "descent_vz_mean_mps",
        "hold_max_err_m",
        "disarm_after_touchdown_s",
    ] {
        println!("  companion {key}: {}", summary[key]);
    }

    assert_eq!(r["failsafe_count"], serde_json::json!([1, 0]), "{r}");
    assert_eq!(r["crash_flags"], serde_json::json!([0, 0]), "{r}");
    assert!(
        u64_at(&r, "/links/0/rx_bad_crc") >= 1,
        "corrupted setpoints not counted: {}",
        r["links"][0]
    );
    assert!(
        u64_at(&r, "/links/0/rx_garbage_bytes") > 0,
        "garbage not counted: {}",
        r["links"][0]
    );
    assert!(
        u64_at(&r, "/links/0/rx_truncated") >= 1,
        "truncated frames not counted: {}",
        r["links"][0]
    );
    assert!(
        u64_at(&r, "/links/0/rx_frames_ok") > 100,
        "too few good frames: {}",
        r["links"][0]
    );
    assert_eq!(u64_at(&r, "/links/0/tx_errors"), 0, "{}", r["links"][0]);
    assert_eq!(
        u64_at(&r, "/links/1/rx_datagrams"),
        0,
        "uav2 was not addressed: {}",
        r["links"][1]
    );
    assert!(u64_at(&r, "/jitter_us/count") > 0, "no jitter samples: {r}");
    // The script's timing checks (failsafe 0.95..1.3 s after the last proof of life) assume
    // simulated time keeps up with the wall clock; say so plainly if it did not.
    let lag_ms = f64_at(&r, "/max_sim_lag_ms");
    assert!(
        lag_ms < 250.0,
        "the plant fell {lag_ms:.1} ms behind real time (build it in release?)"
    );
    assert!(r["overruns"].is_u64(), "overruns not reported: {r}");
}
