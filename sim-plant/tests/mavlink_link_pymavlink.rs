//! Real-peer test: the endpoint, stepped with a fake vehicle at 1 kHz on the real clock, against
//! pymavlink (`tests/py/mavlink_link_peer.py`). Needs python3 with pymavlink; fails (does not
//! skip) without them.

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use nalgebra::{UnitQuaternion, Vector3};
use sim_plant::mavlink_link::{
    px4_custom_mode, Inbound, LinkConfig, LinkCounters, MavResult, MavlinkEndpoint, Telemetry,
    MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MAV_MODE_FLAG_SAFETY_ARMED, PX4_MAIN_MODE_POSCTL,
};

/// What the vehicle thread saw, returned when it stops.
struct VehicleLog {
    counters: LinkCounters,
    attitude_targets: Vec<Inbound>,
    commands: Vec<(u16, [f32; 7])>,
    peer_heartbeats: u32,
}

/// A hovering quadrotor circling slowly: z = -1.5 m, yaw rate 0.5 rad/s, rotors 770..773 rad/s.
fn fake_telemetry(t_ns: u64, base_mode: u8, custom_mode: u32) -> Telemetry {
    let t = t_ns as f64 * 1e-9;
    let yaw = 0.5 * t;
    Telemetry {
        time_boot_ns: t_ns,
        base_mode,
        custom_mode,
        system_status: if base_mode & MAV_MODE_FLAG_SAFETY_ARMED != 0 {
            4
        } else {
            3
        },
        position_ned_m: Vector3::new(0.5 * yaw.cos(), 0.5 * yaw.sin(), -1.5),
        velocity_ned_m_s: Vector3::new(-0.25 * yaw.sin(), 0.25 * yaw.cos(), 0.0),
        attitude_body_to_ned: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        body_rates_frd_rad_s: Vector3::new(0.0, 0.0, 0.5),
        specific_force_frd_m_s2: Vector3::new(0.0, 0.0, -9.81),
        gyro_frd_rad_s: Vector3::new(0.0, 0.0, 0.5),
        rotor_speeds_rad_s: [770.0, 771.0, 772.0, 773.0],
        position_variance_ned_m2: [1e-4; 3],
        velocity_variance_ned_m2_s2: [1e-3; 3],
        ..Telemetry::default()
    }
}

/// Runs the endpoint until `stop`: poll, apply mode/arm commands, send due streams, 1 ms steps.
fn run_vehicle(mut ep: MavlinkEndpoint, stop: Arc<AtomicBool>) -> VehicleLog {
    let start = Instant::now();
    let mut base_mode = MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    let mut custom_mode = px4_custom_mode(PX4_MAIN_MODE_POSCTL, 0);
    let mut log = VehicleLog {
        counters: LinkCounters::default(),
        attitude_targets: Vec::new(),
        commands: Vec::new(),
        peer_heartbeats: 0,
    };
    let mut next = start;
    while !stop.load(Ordering::Relaxed) {
        let t_ns = start.elapsed().as_nanos() as u64;
        let mut handler = |inbound: Inbound| match inbound {
            Inbound::Command {
                command, params, ..
            } => {
                log.commands.push((command, params));
                match command {
                    176 if params[0] == 1.0 => {
                        custom_mode = px4_custom_mode(params[1] as u8, 0);
                        Some(MavResult::MAV_RESULT_ACCEPTED)
                    }
                    400 => {
                        base_mode = if params[0] > 0.5 {
                            base_mode | MAV_MODE_FLAG_SAFETY_ARMED
                        } else {
                            base_mode & !MAV_MODE_FLAG_SAFETY_ARMED
                        };
                        Some(MavResult::MAV_RESULT_ACCEPTED)
                    }
                    _ => None,
                }
            }
            Inbound::AttitudeTarget { .. } => {
                log.attitude_targets.push(inbound);
                None
            }
            Inbound::Heartbeat { .. } => {
                log.peer_heartbeats += 1;
                None
            }
        };
        ep.poll(t_ns, &mut handler);
        ep.send_due(t_ns, &fake_telemetry(t_ns, base_mode, custom_mode));
        next += Duration::from_millis(1);
        let now = Instant::now();
        if next > now {
            thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    log.counters = ep.counters();
    log
}

fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("reserve a UDP port")
        .port()
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

#[test]
fn pymavlink_peer_flies_the_endpoint_like_px4_sitl() {
    require_pymavlink();
    let script: PathBuf = [
        env!("CARGO_MANIFEST_DIR"),
        "tests",
        "py",
        "mavlink_link_peer.py",
    ]
    .iter()
    .collect();
    let peer_port = free_udp_port();
    let config = LinkConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        remote: SocketAddr::from(([127, 0, 0, 1], peer_port)),
        ..LinkConfig::px4_sitl(0)
    };
    let ep = MavlinkEndpoint::open(config).expect("open endpoint");
    let endpoint_port = ep.local_addr().port();
    let stop = Arc::new(AtomicBool::new(false));
    let vehicle = {
        let stop = stop.clone();
        thread::spawn(move || run_vehicle(ep, stop))
    };

    let mut child = Command::new("python3")
        .arg(&script)
        .args(["--local", &peer_port.to_string()])
        .args(["--remote", &endpoint_port.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start python3 peer script");
    let deadline = Instant::now() + Duration::from_secs(120);
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for peer") {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            stop.store(true, Ordering::Relaxed);
            panic!("pymavlink peer did not finish within 120 s");
        }
        thread::sleep(Duration::from_millis(20));
    };
    let output = child.wait_with_output().expect("peer output");
    // Let the last datagrams reach the endpoint before stopping it.
    thread::sleep(Duration::from_millis(50));
    stop.store(true, Ordering::Relaxed);
    let log = vehicle.join().expect("vehicle thread");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    println!("peer summary: {stdout}");
    println!("endpoint counters: {:?}", log.counters);
    assert!(
        status.success(),
        "pymavlink peer failed ({status}):\n{stderr}\n{stdout}"
    );

    // Attitude setpoints: the good ones intact, the misaddressed and corrupted ones never.
    let times: Vec<u32> = log
        .attitude_targets
        .iter()
        .map(|a| match a {
            Inbound::AttitudeTarget { time_boot_ms, .. } => *time_boot_ms,
            _ => unreachable!(),
        })
        .collect();
    assert_eq!(times, [123_456, 888], "attitude targets delivered");
    assert_eq!(
        log.attitude_targets[0],
        Inbound::AttitudeTarget {
            time_boot_ms: 123_456,
            q: [0.5, 0.5, -0.5, 0.5],
            body_rates: [0.125, -0.25, 0.5],
            thrust: 0.625,
            type_mask: 7,
            thrust_body: [0.0625, 0.125, -0.75],
        }
    );
    let ids: Vec<u16> = log.commands.iter().map(|c| c.0).collect();
    assert_eq!(
        ids,
        [176, 400, 60000, 400, 400],
        "commands reaching the vehicle"
    );
    assert_eq!(log.commands[0].1[..2], [1.0, 6.0]);
    assert!(log.peer_heartbeats >= 1);

    let c = log.counters;
    assert!(c.rx_bad_crc >= 1, "bad CRC not counted: {c:?}");
    assert!(c.rx_truncated >= 1, "truncated frame not counted: {c:?}");
    assert!(c.rx_unknown_message >= 1, "unknown id not counted: {c:?}");
    assert!(c.rx_garbage_bytes >= 5, "garbage not counted: {c:?}");
    assert_eq!(
        c.rx_not_for_us, 2,
        "system-0 command and system-99 setpoint"
    );
    assert_eq!(c.unknown_commands, 1, "command 60000");
    assert_eq!(c.tx_errors, 0);
}
