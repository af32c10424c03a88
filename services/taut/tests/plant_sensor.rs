//! The plant's true anchor force drives each drone's emulated force sensor: the real sampler
//! and tension processes, reading the bus that `taut plant` serves, measure the force that the
//! plant's ground-truth topic reports.

use serde_json::Value;
use shared_types::{names, PlantTruth};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use taut_ipc::Ipc;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");
/// 1 %FS of the z axis (5.5 kg-force), N.
const ONE_PERCENT_FS: f64 = 0.01 * 5.5 * 9.80665;

struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .map(|a| a.port())
        .expect("a free UDP port")
}

#[test]
fn each_sensor_reads_its_drones_true_anchor_force() {
    let id = std::process::id();
    let dir = std::env::temp_dir().join(format!("taut-plant-sensor-{id}"));
    std::fs::create_dir_all(&dir).unwrap();
    let root = format!("test-plant-sensor-{id}");
    // Test B starts in hover with the payload hanging: a steady, known pull on both drones.
    let (remote, local) = (free_udp_port(), free_udp_port());
    let _plant = Killed(
        Command::new(TAUT)
            .args([
                "plant",
                "--scenario",
                "test-b",
                "--duration",
                "30",
                "--no-noise",
            ])
            .args(["--remote-port", &remote.to_string()])
            .args(["--local-port", &local.to_string()])
            .arg("--socket-dir")
            .arg(&dir)
            .args(["--ipc-root", &root])
            .stdout(Stdio::null())
            .spawn()
            .expect("start taut plant"),
    );
    let socket = |uav: &str| dir.join(format!("taut-{uav}-i2c.sock"));
    let t0 = Instant::now();
    while !(socket("uav1").exists() && socket("uav2").exists()) {
        assert!(
            t0.elapsed() < Duration::from_secs(10),
            "the plant never served its sensors"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let ipc = Ipc::new(&format!("plant-sensor-test-{id}"), &root, names::PLANT).unwrap();
    let truth_sub = ipc.subscriber::<PlantTruth>(names::TRUTH).unwrap();

    for (k, uav) in ["uav1", "uav2"].iter().enumerate() {
        let cfg: PathBuf = dir.join(format!("{uav}.toml"));
        let base = include_str!("../../../configs/sim-uav1.toml")
            .replace("uav = \"uav1\"", &format!("uav = \"{uav}\""))
            .replace(
                "bus = \"sim:/tmp/taut-uav1-i2c.sock\"",
                &format!("bus = \"sim:{}\"", socket(uav).display()),
            );
        std::fs::write(&cfg, base).unwrap();
        // Truth over the same window as the sensor's measurement.
        let mut truth_sum = [0.0; 3];
        let mut truth_n = 0.0;
        let sensor = std::thread::scope(|s| {
            let h = s.spawn(|| {
                Command::new(TAUT)
                    .args(["sensor", "--json", "--duration", "3", "--config"])
                    .arg(&cfg)
                    .output()
                    .expect("run taut sensor")
            });
            while !h.is_finished() {
                let _ = truth_sub.wait_and_drain(Duration::from_millis(100), |t| {
                    for (i, v) in t.drones[k].anchor_force_frd_n.iter().enumerate() {
                        truth_sum[i] += v;
                    }
                    truth_n += 1.0;
                });
            }
            h.join().unwrap()
        });
        let stderr = String::from_utf8_lossy(&sensor.stderr);
        assert!(sensor.status.success(), "taut sensor on {uav}: {stderr}");
        let v: Value = serde_json::from_slice(&sensor.stdout).unwrap();
        let m = v["mean_force_n"].as_array().unwrap();
        assert!(truth_n > 100.0, "too few truth samples: {truth_n}");
        let truth = truth_sum.map(|s| s / truth_n);
        // Without the perturbation the formation is symmetric: each cable carries half the
        // payload's weight.
        assert!(
            (truth[2] - 0.5 * 9.81).abs() < 0.3,
            "{uav}: truth {truth:?}"
        );
        for (i, t) in truth.iter().enumerate() {
            let measured = m[i].as_f64().unwrap();
            assert!(
                (measured - t).abs() < ONE_PERCENT_FS,
                "{uav} axis {i}: sensor {measured:.3} N vs truth {t:.3} N"
            );
        }
        println!("{uav}: sensor {m:?} N, truth {truth:?} N");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
