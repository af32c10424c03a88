//! Shared by the bridge's integration tests: child processes cleaned up on every path, the
//! bridge started on a temporary config, and this test playing the controller over iceoryx2.

#![allow(dead_code)] // each test file uses a part

use rt_config::periodic::{now_ns, sleep_until_ns};
use rt_config::Config;
use serde_json::Value;
use shared_types::{names, setpoint_flags, AttitudeSetpoint};
use shared_types::{ImuSample, MotorSpeeds, VehicleState};
use std::io::Read;
use std::net::UdpSocket;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};
use taut_ipc::Ipc;

pub const TAUT: &str = env!("CARGO_BIN_EXE_taut");
pub const THRUST_N: f64 = 15.0;
/// Not normalised on purpose; the bridge normalises.
pub const Q: [f64; 4] = [0.9, 0.1, -0.2, 0.3];

/// A child stopped (SIGTERM, then SIGKILL after 3 s) and reaped on every path; its stdout and
/// stderr collected by reader threads.
pub struct ChildGuard {
    pub child: Child,
    out: Option<JoinHandle<String>>,
    err: Option<JoinHandle<String>>,
}

pub fn read_all(mut r: impl Read + Send + 'static) -> JoinHandle<String> {
    thread::spawn(move || {
        let mut s = String::new();
        let _ = r.read_to_string(&mut s);
        s
    })
}

impl ChildGuard {
    pub fn spawn(cmd: &mut Command) -> Self {
        let mut child = cmd
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {cmd:?}: {e}"));
        let (out, err) = (child.stdout.take(), child.stderr.take());
        ChildGuard {
            child,
            out: out.map(read_all),
            err: err.map(read_all),
        }
    }

    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// SIGTERM, wait up to 3 s (SIGKILL after), then stdout and stderr; true if it exited 0.
    pub fn stop(&mut self) -> (bool, String, String) {
        // SAFETY: kill(2) on our own child, not reaped yet.
        unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGTERM) };
        let end = Instant::now() + Duration::from_secs(3);
        let mut ok = false;
        loop {
            match self.child.try_wait() {
                Ok(Some(s)) => {
                    ok = s.success();
                    break;
                }
                Ok(None) if Instant::now() < end => thread::sleep(Duration::from_millis(20)),
                _ => {
                    let _ = self.child.kill();
                    let _ = self.child.wait();
                    break;
                }
            }
        }
        let take = |h: &mut Option<JoinHandle<String>>| {
            h.take()
                .map(|h| h.join().unwrap_or_default())
                .unwrap_or_default()
        };
        (ok, take(&mut self.out), take(&mut self.err))
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if self.running() {
            self.stop();
        }
    }
}

pub struct TempFile(pub PathBuf);
impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// A free UDP port on 127.0.0.1 (free when asked).
pub fn free_udp_port() -> u16 {
    let s = UdpSocket::bind("127.0.0.1:0").expect("bind a UDP port");
    s.local_addr().expect("local address").port()
}

/// Starts the bridge on `link` (`udpin:127.0.0.1:PORT`, `serial:…`) with a unique ipc_root;
/// the config file is removed on drop.
pub fn start_bridge(tag: &str, link: &str) -> (Config, ChildGuard, TempFile) {
    let tag = format!("{}-{tag}", std::process::id());
    let mut cfg = Config::embedded_sim();
    cfg.ipc_root = format!("test-bridge-{tag}");
    cfg.px4.link = link.to_string();
    cfg.px4.link_timeout_s = 1.0;
    let file = TempFile(std::env::temp_dir().join(format!("taut-bridge-{tag}.toml")));
    std::fs::write(&file.0, cfg.to_toml()).expect("write the config");
    let mut cmd = Command::new(TAUT);
    cmd.args(["svc", "px4-bridge", "--config"]).arg(&file.0);
    (cfg, ChildGuard::spawn(&mut cmd), file)
}

/// Starts the bridge and the pymavlink peer playing `scenario` against it.
pub fn start(scenario: &str) -> (Config, ChildGuard, ChildGuard, TempFile) {
    let out = Command::new("python3")
        .args(["-c", "import pymavlink"])
        .output();
    assert!(
        out.as_ref().is_ok_and(|o| o.status.success()),
        "python3 with pymavlink is required for this test: {out:?}"
    );
    let port = free_udp_port();
    let (cfg, bridge, file) = start_bridge(scenario, &format!("udpin:127.0.0.1:{port}"));
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../px4-bridge/tests/py/px4_peer.py"
    );
    let peer = ChildGuard::spawn(Command::new("python3").arg(script).args([
        "--port",
        &port.to_string(),
        "--scenario",
        scenario,
    ]));
    (cfg, bridge, peer, file)
}

#[derive(Default)]
pub struct Observed {
    pub states: Vec<VehicleState>,
    pub imu: Vec<ImuSample>,
    pub motors: Vec<MotorSpeeds>,
}

/// The setpoint [`fly`] publishes: [`Q`], [`THRUST_N`], ARM_REQUEST.
pub fn test_setpoint() -> AttitudeSetpoint {
    AttitudeSetpoint {
        attitude_wxyz: Q,
        thrust_n: THRUST_N,
        flags: setpoint_flags::ARM_REQUEST,
        ..AttitudeSetpoint::default()
    }
}

/// Plays the controller: publishes `sp` at 100 Hz and records what the bridge publishes, while
/// `go(&observed)` holds (at most `limit`).
pub fn fly(
    cfg: &Config,
    sp: AttitudeSetpoint,
    mut go: impl FnMut(&Observed) -> bool,
    limit: Duration,
) -> Observed {
    let ipc = Ipc::new(
        &format!("test-ctl-{}", std::process::id()),
        &cfg.ipc_root,
        &cfg.uav,
    )
    .unwrap();
    let mut setpoints = ipc
        .publisher::<AttitudeSetpoint>(names::ATTITUDE_SETPOINT)
        .unwrap();
    let states = ipc
        .subscriber::<VehicleState>(names::VEHICLE_STATE)
        .unwrap();
    let imu = ipc.subscriber::<ImuSample>(names::IMU).unwrap();
    let motors = ipc.subscriber::<MotorSpeeds>(names::MOTOR_SPEEDS).unwrap();
    let mut o = Observed::default();
    let end = Instant::now() + limit;
    let mut next = now_ns();
    let mut sp = sp;
    while go(&o) && Instant::now() < end {
        sp.header.t_origin_ns = now_ns();
        setpoints.publish(sp).unwrap();
        states.drain(&mut |s| o.states.push(s)).unwrap();
        imu.drain(&mut |s| o.imu.push(s)).unwrap();
        motors.drain(&mut |s| o.motors.push(s)).unwrap();
        next += 10_000_000;
        sleep_until_ns(next);
    }
    o
}

pub fn stop_both(bridge: &mut ChildGuard, peer: &mut ChildGuard) -> (Value, String) {
    let (_, peer_out, peer_err) = peer.stop();
    let (ok, _, bridge_err) = bridge.stop();
    assert!(
        ok,
        "the bridge did not exit cleanly on SIGTERM:\n{bridge_err}"
    );
    let rec: Value = serde_json::from_str(peer_out.trim()).unwrap_or_else(|e| {
        panic!("peer output is not JSON ({e}):\n{peer_out}\n{peer_err}\n{bridge_err}")
    });
    assert!(
        rec.get("error").is_none(),
        "peer: {}\nbridge:\n{bridge_err}",
        rec["error"]
    );
    (rec, bridge_err)
}

/// `key=value` of the bridge's final counters line.
pub fn counter(stderr: &str, key: &str) -> u64 {
    let line = stderr
        .lines()
        .find(|l| l.contains("stopped:"))
        .expect("counters line");
    line.split_whitespace()
        .find_map(|kv| kv.strip_prefix(&format!("{key}=")))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key} in {line}"))
}

pub fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// (time, params, confirmation) of the commands `id` the peer received.
pub fn commands(rec: &Value, id: u64) -> Vec<(f64, Vec<f64>, u64)> {
    let all = rec["commands"].as_array().unwrap();
    all.iter()
        .filter(|c| c["command"] == id)
        .map(|c| {
            let p = c["params"].as_array().unwrap().iter().map(f).collect();
            (f(&c["t"]), p, c["confirmation"].as_u64().unwrap())
        })
        .collect()
}

pub fn secs(ns: u64) -> f64 {
    ns as f64 * 1e-9
}
