//! `taut report` on synthetic recordings written here with `mcap::Writer` exactly as
//! `recorder::format` lays them out: two drones and the plant's truth for 5 s at 100 Hz with
//! known latencies and a known payload swing; then a recording with most channels missing; then
//! a file that is not MCAP.

use recorder::format::{
    channel_topic, schema_json, schema_name, Recordable, CHANNEL_TOPIC, CHANNEL_TYPE, CHANNEL_UAV,
    MESSAGE_ENCODING, META_DROPS, META_RECORDING, SCHEMA_ENCODING,
};
use shared_types::{
    mission_flags, names, setpoint_flags, AttitudeSetpoint, ContactKind, ImuSample, MissionPhase,
    MissionSetpoint, MotorSpeeds, PlantTruth, RawAdcFrame, TensionSample, VehicleState,
};
use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::process::Command;
use taut_ipc::Stamped;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");
const BASE_NS: u64 = 1_000_000_000;
const STEP_NS: u64 = 10_000_000;
const STEPS: u64 = 500;
/// Recorder transport: log time − publish time of every sample, ns.
const TRANSPORT_NS: u64 = 50_000;
/// Swing amplitude, degrees, and frequency, Hz.
const SWING_DEG: f64 = 10.0;
const SWING_HZ: f64 = 0.5;

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("taut-report-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

struct Synth {
    w: mcap::Writer<BufWriter<std::fs::File>>,
    channels: BTreeMap<String, u16>,
}

impl Synth {
    fn new(path: &Path) -> Self {
        let file = BufWriter::new(std::fs::File::create(path).unwrap());
        let mut w = mcap::Writer::new(file).unwrap();
        let meta = BTreeMap::from([
            ("clock".to_string(), "CLOCK_MONOTONIC".to_string()),
            ("mode".to_string(), "realtime".to_string()),
            ("uavs".to_string(), "uav1,uav2".to_string()),
        ]);
        w.write_metadata(&mcap::records::Metadata {
            name: META_RECORDING.into(),
            metadata: meta,
        })
        .unwrap();
        Synth {
            w,
            channels: BTreeMap::new(),
        }
    }

    /// Writes `s` on `/<uav>/<topic>`, published at its header's time, logged 50 µs later.
    fn put<T: Recordable>(&mut self, uav: &str, topic: &str, s: &T) {
        let name = channel_topic(uav, topic);
        let id = match self.channels.get(&name) {
            Some(id) => *id,
            None => {
                let schema = self
                    .w
                    .add_schema(&schema_name::<T>(), SCHEMA_ENCODING, &schema_json::<T>())
                    .unwrap();
                let meta = BTreeMap::from([
                    (CHANNEL_UAV.to_string(), uav.to_string()),
                    (CHANNEL_TOPIC.to_string(), topic.to_string()),
                    (CHANNEL_TYPE.to_string(), T::TYPE_NAME.to_string()),
                ]);
                let id = self
                    .w
                    .add_channel(schema, &name, MESSAGE_ENCODING, &meta)
                    .unwrap();
                self.channels.insert(name, id);
                id
            }
        };
        let h = s.header();
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: h.sequence as u32,
            log_time: h.t_publish_ns + TRANSPORT_NS,
            publish_time: h.t_publish_ns,
        };
        self.w
            .write_to_known_channel(&header, &serde_json::to_vec(s).unwrap())
            .unwrap();
    }

    fn finish(mut self, configs: bool) {
        if configs {
            let toml = rt_config::Config::embedded_sim().to_toml();
            for uav in ["uav1", "uav2"] {
                self.w
                    .attach(&mcap::Attachment {
                        log_time: 0,
                        create_time: 0,
                        name: format!("config/{uav}.toml"),
                        media_type: "application/toml".into(),
                        data: toml.as_bytes().into(),
                    })
                    .unwrap();
            }
        }
        let drops = self.channels.keys().map(|k| (k.clone(), "0".to_string()));
        self.w
            .write_metadata(&mcap::records::Metadata {
                name: META_DROPS.into(),
                metadata: drops.collect(),
            })
            .unwrap();
        self.w.finish().unwrap();
    }
}

fn stamp<T: Stamped>(mut s: T, seq: u64, origin: u64, publish: u64) -> T {
    let h = s.header_mut();
    h.sequence = seq;
    h.t_origin_ns = origin;
    h.t_publish_ns = publish;
    s
}

/// Phase at `t_s` of the synthetic mission (Test A's phases: takeoff, move, hold).
fn phase(t_s: f64) -> (MissionPhase, u32, f64) {
    match t_s {
        t if t < 1.0 => (MissionPhase::Idle, 0, 0.0),
        t if t < 2.0 => (MissionPhase::Takeoff, 0, 1.0),
        t if t < 4.0 => (MissionPhase::Move, 1, 2.0),
        _ => (MissionPhase::Hold, 2, 4.0),
    }
}

/// Raw ADC latency of step `i`: three of four at 250 µs, one at 900 µs.
fn adc_latency_ns(i: u64) -> u64 {
    if i % 4 == 3 {
        900_000
    } else {
        250_000
    }
}

fn write_full(path: &Path, drones: &[&str], with_truth: bool, full: bool) {
    let mut s = Synth::new(path);
    for i in 0..STEPS {
        let t = BASE_NS + i * STEP_NS;
        let t_s = (i * STEP_NS) as f64 * 1e-9;
        let y = [-0.8, 0.8];
        if with_truth {
            let mut truth = stamp(PlantTruth::default(), i, t, t + 20_000);
            truth.sim_time_ns = i * STEP_NS;
            truth.payload_contact = ContactKind::Free;
            for (d, y) in truth.drones.iter_mut().zip(y) {
                d.body.position_ned_m = [0.0, y, -2.1];
                d.body.attitude_wxyz = [1.0, 0.0, 0.0, 0.0];
                d.anchor_force_frd_n = [0.0, 0.0, 5.0];
            }
            let th = (SWING_DEG * (2.0 * std::f64::consts::PI * SWING_HZ * t_s).sin()).to_radians();
            truth.payload.position_ned_m = [1.2 * th.sin(), 0.0, -2.1 + 0.08 + 1.2 * th.cos()];
            s.put(names::PLANT, names::TRUTH, &truth);
        }
        for (k, uav) in drones.iter().enumerate() {
            let (ph, index, start_s) = phase(t_s);
            let flying = ph != MissionPhase::Idle;
            let mut m = stamp(MissionSetpoint::default(), i, t, t + 50_000);
            m.phase = ph;
            m.phase_index = index;
            m.phase_start_ns = BASE_NS + (start_s * 1e9) as u64;
            m.position_ned_m = [0.0, y[k], -2.1];
            if ph == MissionPhase::Move || ph == MissionPhase::Hold {
                m.flags = mission_flags::TENSION_ENABLED;
            }
            s.put(uav, names::MISSION_SETPOINT, &m);
            let mut v = stamp(VehicleState::default(), i, t, t + 400_000);
            v.position_ned_m = [0.01, y[k], -2.1];
            v.attitude_wxyz = [1.0, 0.0, 0.0, 0.0];
            s.put(uav, names::VEHICLE_STATE, &v);
            let mut a = stamp(AttitudeSetpoint::default(), i, t + 200_000, t + 2_200_000);
            a.step_ns = t + 2_000_000;
            a.tension_origin_ns = t + 200_000;
            a.odometry_origin_ns = t + 1_200_000;
            a.flags = if flying { 0 } else { setpoint_flags::IDLE };
            a.phase = ph;
            a.tension_desired_ned_n = [0.0, 0.0, -5.0];
            a.shifted_position_ned_m = [0.0, y[k], -2.15];
            s.put(uav, names::ATTITUDE_SETPOINT, &a);
            if !full {
                continue;
            }
            s.put(
                uav,
                names::RAW_ADC,
                &stamp(RawAdcFrame::default(), i, t, t + adc_latency_ns(i)),
            );
            let mut ts = stamp(TensionSample::default(), i, t, t + 1_500_000);
            ts.force_body_n = [0.0, 0.0, 5.0];
            s.put(uav, names::TENSION, &ts);
            let mut te = stamp(TensionSample::default(), i, t, t + 3_000_000);
            te.force_body_n = [0.2, 0.0, 4.8];
            s.put(uav, names::TENSION_ESTIMATE, &te);
            s.put(uav, names::TENSION_TRUTH, &stamp(ts, i, t, t + 100_000));
            s.put(
                uav,
                names::IMU,
                &stamp(ImuSample::default(), i, t, t + 300_000),
            );
            s.put(
                uav,
                names::MOTOR_SPEEDS,
                &stamp(MotorSpeeds::default(), i, t, t + 300_000),
            );
        }
    }
    s.finish(full);
}

fn report(recording: &Path, out: &Path) -> (bool, String) {
    let o = Command::new(TAUT)
        .arg("report")
        .arg(recording)
        .arg("--out")
        .arg(out)
        .output()
        .expect("start taut report");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    (o.status.success(), text)
}

/// (width, height) of a PNG, from its IHDR; panics if not a PNG.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(b.len() > 1000, "{}: {} bytes", path.display(), b.len());
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&b[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
    (be(16), be(20))
}

/// The numeric cells of the latency table row of `drone`/`span`: n, p50, p90, p99, p99.9, max.
fn latency_row(md: &str, drone: &str, span: &str) -> Vec<f64> {
    let prefix = format!("| {drone} | {span} |");
    let line = md
        .lines()
        .find(|l| l.starts_with(&prefix))
        .unwrap_or_else(|| panic!("no latency row {prefix} in\n{md}"));
    line.split('|')
        .skip(3)
        .filter_map(|c| c.trim().parse().ok())
        .collect()
}

/// The value of `| key | value |` rows under the section starting with `section`.
fn value_after(md: &str, section: &str, key: &str) -> f64 {
    let at = md
        .find(section)
        .unwrap_or_else(|| panic!("no {section} in\n{md}"));
    let prefix = format!("| {key} |");
    let line = md[at..]
        .lines()
        .find(|l| l.starts_with(&prefix))
        .unwrap_or_else(|| panic!("no {key} after {section}"));
    line.split('|').nth(2).unwrap().trim().parse().unwrap()
}

#[test]
fn a_full_recording_gives_every_figure_the_latency_table_and_the_metrics() {
    let dir = out_dir("full");
    let rec = dir.join("recording.mcap");
    write_full(&rec, &["uav1", "uav2"], true, true);
    std::fs::write(
        dir.join("summary.json"),
        r#"{"scenario": "synthetic-scenario", "success": true, "drones": [{"id": "uav1", "future_force_rmse_n": 0.25}]}"#,
    )
    .unwrap();
    let out = dir.join("report");
    let (ok, log) = report(&rec, &out);
    assert!(ok, "{log}");
    // Figure sizes: 1600 wide; 60 px title + 320 px per time panel; 60 + 340 per latency row.
    for uav in ["uav1", "uav2"] {
        assert_eq!(
            png_size(&out.join(format!("positions_{uav}.png"))),
            (1600, 1020)
        );
        assert_eq!(
            png_size(&out.join(format!("forces_{uav}.png"))),
            (1600, 1020)
        );
        assert_eq!(
            png_size(&out.join(format!("latency_{uav}.png"))),
            (1600, 1420)
        );
    }
    assert_eq!(png_size(&out.join("payload.png")), (1600, 1340));
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for fig in [
        "positions_uav1.png",
        "forces_uav2.png",
        "payload.png",
        "latency_uav2.png",
    ] {
        assert!(md.contains(&format!("]({fig})")), "{fig} not embedded");
    }
    // Latencies, ms, within the histograms' 3 significant digits (0.1 %).
    let near = |got: f64, want: f64| (got - want).abs() <= want * 1e-3 + 1e-6;
    let adc = latency_row(&md, "uav1", "sampler");
    assert_eq!(adc[0], 500.0, "{adc:?}");
    assert!(
        near(adc[1], 0.25) && near(adc[2], 0.9) && near(adc[5], 0.9),
        "{adc:?}"
    );
    let tension = latency_row(&md, "uav2", "tension stage");
    assert!(near(tension[1], 1.5), "{tension:?}");
    assert!(near(latency_row(&md, "uav1", "estimator")[1], 3.0));
    // Controller spans from flight steps only: 400 of the 500 (the first second is Idle).
    let ctl = latency_row(&md, "uav1", "controller from tension");
    assert_eq!(ctl[0], 400.0, "{ctl:?}");
    assert!(near(ctl[1], 2.0), "{ctl:?}");
    assert!(near(
        latency_row(&md, "uav1", "controller from odometry")[1],
        1.0
    ));
    assert!(near(latency_row(&md, "uav2", "bridge")[1], 0.4));
    let transport = latency_row(&md, "uav1", "recorder transport");
    assert_eq!(transport[0], 9.0 * 500.0);
    assert!(
        near(transport[1], 0.05) && near(transport[5], 0.05),
        "{transport:?}"
    );
    // Metrics from the recording: swing from the first Move (2 s), 10° at 2.5 s.
    let metrics = "## Flight metrics";
    let max = value_after(&md, metrics, "swing_max_deg");
    assert!((max - SWING_DEG).abs() < 0.01, "swing max {max}");
    let rms = value_after(&md, metrics, "swing_rms_deg");
    assert!(
        (rms - SWING_DEG / 2f64.sqrt()).abs() < 0.1,
        "swing RMS {rms}"
    );
    assert!((value_after(&md, metrics, "swing_from_s") - 2.0).abs() < 1e-6);
    // The scenario's phase names come from the recorded config (test-a).
    assert!(md.contains("| move | 1 |"), "{md}");
    // summary.json rendered generically, unknown fields included.
    assert!(md.contains("| scenario | synthetic-scenario |"), "{md}");
    assert!(md.contains("future_force_rmse_n"), "{md}");
    assert!(
        !md.contains("not recorded"),
        "every channel was recorded:\n{md}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_channels_are_reported_not_fatal() {
    let dir = out_dir("partial");
    let rec = dir.join("flight.mcap");
    write_full(&rec, &["uav1"], false, false);
    let out = dir.join("out");
    let (ok, log) = report(&rec, &out);
    assert!(ok, "{log}");
    assert_eq!(png_size(&out.join("positions_uav1.png")), (1600, 1020));
    assert_eq!(png_size(&out.join("forces_uav1.png")), (1600, 1020));
    assert_eq!(png_size(&out.join("latency_uav1.png")), (1600, 1420));
    assert!(!out.join("payload.png").exists());
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for absent in [
        "/uav1/raw_adc: not recorded",
        "/uav1/tension_estimate: not recorded",
        "/plant/truth: not recorded",
        "no /plant/truth: no payload figure",
        "no recorded config",
    ] {
        assert!(md.contains(absent), "{absent:?} not in\n{md}");
    }
    // The controller spans are still measured.
    assert_eq!(
        latency_row(&md, "uav1", "controller from odometry")[0],
        400.0
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_that_is_not_mcap_is_an_error_naming_it() {
    let dir = out_dir("bad");
    let rec = dir.join("nonsense.mcap");
    std::fs::write(&rec, b"not an mcap file at all").unwrap();
    let (ok, log) = report(&rec, &dir.join("out"));
    assert!(!ok, "{log}");
    assert!(log.contains("nonsense.mcap"), "{log}");
    let _ = std::fs::remove_dir_all(&dir);
}
