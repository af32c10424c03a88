//! `taut launch`: supervision of the real service processes, restart after a crash, clean stop
//! on SIGTERM with no iceoryx2 resources left behind.

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;
use std::io::Read;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const TAUT: &str = env!("CARGO_BIN_EXE_taut");

/// Pids of the direct children of `parent` whose command line contains `needle`.
fn children(parent: u32, needle: &str) -> Vec<u32> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        let ppid = stat
            .rsplit(')')
            .next()
            .and_then(|r| r.split_whitespace().nth(1));
        if ppid != Some(&parent.to_string()) {
            continue;
        }
        let cmd = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
        if String::from_utf8_lossy(&cmd).contains(needle) {
            out.push(pid);
        }
    }
    out
}

/// iceoryx2 nodes of a running drone: one per service, two for the bridge.
const NODES: usize = 7;

/// A free TCP/UDP port number on loopback (probed by binding).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn wait_for(what: &str, timeout: Duration, mut f: impl FnMut() -> bool) {
    let end = Instant::now() + timeout;
    while !f() {
        assert!(Instant::now() < end, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// iceoryx2 nodes (alive or dead) whose name starts with `prefix`.
fn nodes_named(prefix: &str) -> usize {
    let mut n = 0;
    Node::<ipc::Service>::list(Config::global_config(), |state| {
        let name = match &state {
            NodeState::Alive(v) => v.details().as_ref().map(|d| d.name().to_string()),
            NodeState::Dead(v) => v.details().as_ref().map(|d| d.name().to_string()),
            _ => None,
        };
        if name.is_some_and(|s| s.starts_with(prefix)) {
            n += 1;
        }
        CallbackProgression::Continue
    })
    .unwrap();
    n
}

fn kill(pid: u32, sig: i32) {
    unsafe { libc_kill(pid as i32, sig) };
}
extern "C" {
    #[link_name = "kill"]
    fn libc_kill(pid: i32, sig: i32) -> i32;
}

#[test]
fn launch_restarts_a_crashed_service_and_stops_cleanly() {
    let id = std::process::id();
    let dir = std::env::temp_dir().join(format!("taut-launch-{id}"));
    std::fs::create_dir_all(&dir).unwrap();
    let socket = dir.join("i2c.sock");
    let uav = format!("launch{id}");
    let cfg = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/sim-uav1.toml"
    ))
    .unwrap()
    .replace("uav = \"uav1\"", &format!("uav = \"{uav}\""))
    .replace(
        "sim:/tmp/taut-uav1-i2c.sock",
        &format!("sim:{}", socket.display()),
    )
    .replace("backoff_initial_s = 0.1", "backoff_initial_s = 0.2")
    // The whole flight stack starts; with no PX4 and no peer it waits in Idle. Its own ports.
    .replace("drone = \"\"", "drone = \"uav1\"")
    .replace(
        "udpin:127.0.0.1:14540",
        &format!("udpin:127.0.0.1:{}", free_port()),
    )
    .replace(
        "tcp/127.0.0.1:7447",
        &format!("tcp/127.0.0.1:{}", free_port()),
    )
    .replace(
        "tcp/127.0.0.1:7448",
        &format!("tcp/127.0.0.1:{}", free_port()),
    );
    let cfg_path = dir.join("drone.toml");
    std::fs::write(&cfg_path, cfg).unwrap();

    let mut sensor: Child = Command::new(TAUT)
        .args(["svc", "sim-sensor", "--load", "0,0,9.81", "--socket"])
        .arg(&socket)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for("emulator socket", Duration::from_secs(5), || {
        socket.exists()
    });

    let mut launch = Command::new(TAUT)
        .args(["launch", "--config"])
        .arg(&cfg_path)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let lp = launch.id();
    wait_for("all six services", Duration::from_secs(10), || {
        [
            "adc-sampler",
            "tension",
            "px4-bridge",
            "force-estimator",
            "controller",
            "mission",
        ]
        .iter()
        .all(|s| !children(lp, s).is_empty())
    });
    // One node per service, two for the bridge (receive and send threads).
    wait_for("their nodes", Duration::from_secs(10), || {
        nodes_named(&uav) == NODES
    });

    // A crash: SIGKILL leaves the sampler's iceoryx2 node behind; the restart cleans it up.
    let first = children(lp, "adc-sampler")[0];
    kill(first, 9);
    wait_for("the restarted sampler", Duration::from_secs(10), || {
        children(lp, "adc-sampler").iter().any(|&p| p != first)
    });
    wait_for("dead node cleanup", Duration::from_secs(10), || {
        nodes_named(&uav) == NODES
    });

    kill(lp, 15);
    let end = Instant::now() + Duration::from_secs(10);
    let status = loop {
        if let Some(s) = launch.try_wait().unwrap() {
            break s;
        }
        assert!(Instant::now() < end, "launch did not stop on SIGTERM");
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut log = String::new();
    launch
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut log)
        .unwrap();
    assert!(status.success(), "launch exit {status}: {log}");
    assert!(log.contains("service adc-sampler exited"), "{log}");
    assert!(log.contains("restarting adc-sampler"), "{log}");
    assert!(log.contains("stopped cleanly"), "{log}");
    assert_eq!(nodes_named(&uav), 0, "iceoryx2 nodes left behind: {log}");

    kill(sensor.id(), 15);
    sensor.wait().unwrap();
    assert!(!socket.exists(), "the emulator removes its socket");
    std::fs::remove_dir_all(&dir).unwrap();
}
