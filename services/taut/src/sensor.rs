//! `taut sensor`: runs the force-sensing chain (with `--sim`, on the emulated sensor), shows the
//! live force, and ends with a summary: mean force, rate, flags, and latency per span.

use crate::supervisor::{ServiceSpec, Supervisor, Verdict};
use crate::svc::SimSensorArgs;
use clap::{Args, ValueEnum};
use latency_tests::{ramp_lag, SpanHistograms};
use rt_config::{periodic::now_ns, SamplingModeConfig};
use serde::Serialize;
use shared_types::{names, RawAdcFrame, TensionSample};
use sim_plant::sensor::LoadProfile;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;
use taut_ipc::{install_stop_handler, stop_requested, Ipc};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ModeArg {
    Continuous,
    Synchronous,
}

#[derive(Args, Debug, Clone)]
pub struct SensorArgs {
    /// Run the emulated sensor (sim-plant) instead of the I2C bus in the config.
    #[arg(long)]
    pub sim: bool,
    /// Drone config; default: the embedded simulation config.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// How long to measure, s (after the filter has filled).
    #[arg(long, default_value_t = 5.0)]
    pub duration: f64,
    /// Print one JSON object at the end instead of the live view and table.
    #[arg(long)]
    pub json: bool,
    /// Override the config's sampling mode.
    #[arg(long)]
    pub mode: Option<ModeArg>,
    /// Live view refresh rate, Hz.
    #[arg(long, default_value_t = 4.0)]
    pub display_hz: f64,
    #[command(flatten)]
    pub emulator: SimSensorArgs,
}

#[derive(Debug, Serialize)]
pub struct SensorSummary {
    pub mode: String,
    pub duration_s: f64,
    /// Mean force over the run, body FRD, N: the cable's pull on the drone (same as --load).
    pub mean_force_n: [f64; 3],
    pub std_force_n: [f64; 3],
    /// Tension samples per second (from their origin times).
    pub rate_hz: f64,
    pub samples: u64,
    /// Samples with any flag set, and the count per flag.
    pub flagged: u64,
    pub flags: BTreeMap<String, u64>,
    pub raw_frames: u64,
    /// Lost tension samples (sequence gaps seen by this monitor).
    pub lost_samples: u64,
    pub bus_errors: u32,
    pub degraded_frames: u32,
    /// Inter-channel skew of the raw frames, us.
    pub skew_us: Option<latency_tests::Percentiles>,
    /// Per span, us: `adc` conversion midpoint -> raw frame published; `raw_to_tension` raw
    /// published -> tension published; `tension_to_monitor` tension published -> received
    /// here; `sample_to_tension` conversion midpoint -> tension published (end to end);
    /// `ramp_lag` true force -> tension published, when the load is a ramp or series.
    pub latency_us: BTreeMap<String, latency_tests::Percentiles>,
    pub service_deaths: Vec<String>,
}

const FLAG_NAMES: [(u32, &str); 7] = [
    (shared_types::tension_flags::SATURATED, "saturated"),
    (
        shared_types::tension_flags::NEAR_SINGULARITY,
        "near_singularity",
    ),
    (shared_types::tension_flags::STALE_INPUT, "stale_input"),
    (
        shared_types::tension_flags::CALIBRATION_MISSING,
        "calibration_missing",
    ),
    (shared_types::tension_flags::FILTER_WARMUP, "filter_warmup"),
    (shared_types::tension_flags::NON_FINITE, "non_finite"),
    (shared_types::tension_flags::INPUT_GAP, "input_gap"),
];

/// The piecewise-linear truth of a profile (for lag measurement), if it has slopes.
fn profile_vertices(p: &LoadProfile) -> Option<Vec<(f64, [f64; 3])>> {
    match p {
        LoadProfile::Ramp {
            from,
            to,
            start_s,
            duration_s,
        } => Some(vec![
            (0.0, *from),
            (*start_s, *from),
            (start_s + duration_s, *to),
            (start_s + duration_s + 1e6, *to),
        ]),
        LoadProfile::Series(v) => Some(v.clone()),
        _ => None,
    }
}

pub fn run(args: &SensorArgs) -> Result<(), String> {
    let summary = measure(args, &mut |line| {
        if !args.json {
            eprint!("{line}");
        }
    })?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?
        );
    } else {
        print_table(&summary);
    }
    if summary.samples == 0 {
        return Err("no tension samples arrived".into());
    }
    Ok(())
}

fn print_table(s: &SensorSummary) {
    let f = s.mean_force_n;
    println!(
        "\nforce (body FRD, N): x {:8.3}  y {:8.3}  z {:8.3}",
        f[0], f[1], f[2]
    );
    println!(
        "std   (body FRD, N): x {:8.3}  y {:8.3}  z {:8.3}",
        s.std_force_n[0], s.std_force_n[1], s.std_force_n[2]
    );
    println!(
        "rate {:.2} Hz, {} samples, {} flagged {:?}",
        s.rate_hz, s.samples, s.flagged, s.flags
    );
    println!(
        "bus errors {}, degraded frames {}, lost samples {}",
        s.bus_errors, s.degraded_frames, s.lost_samples
    );
    print_spans(s);
}

/// The latency table: one row per span, and the channel skew.
pub fn print_spans(s: &SensorSummary) {
    println!(
        "{:<20} {:>8} {:>9} {:>9} {:>9} {:>9}",
        "span (us)", "count", "p50", "p99", "p99.9", "max"
    );
    let skew = s.skew_us.iter().map(|k| ("channel_skew", k));
    for (name, p) in s
        .latency_us
        .iter()
        .map(|(n, p)| (n.as_str(), p))
        .chain(skew)
    {
        println!(
            "{name:<20} {:>8} {:>9.1} {:>9.1} {:>9.1} {:>9.1}",
            p.count, p.p50, p.p99, p.p999, p.max
        );
    }
}

/// Starts the chain, measures for `args.duration`, stops it, and summarises. `show` gets the
/// live lines.
pub fn measure(args: &SensorArgs, show: &mut dyn FnMut(&str)) -> Result<SensorSummary, String> {
    install_stop_handler();
    let mut cfg = crate::load_config(args.config.as_deref())?;
    if let Some(m) = args.mode {
        cfg.sensor.mode = match m {
            ModeArg::Continuous => SamplingModeConfig::Continuous,
            ModeArg::Synchronous => SamplingModeConfig::Synchronous,
        };
    }
    let run_dir = std::env::temp_dir().join(format!("taut-sensor-{}", std::process::id()));
    std::fs::create_dir_all(&run_dir).map_err(|e| format!("{}: {e}", run_dir.display()))?;
    // A root of our own: parallel runs never see each other's samples.
    cfg.ipc_root = format!("sensor-{}", std::process::id());
    let t0 = now_ns();
    let mut emulator = args.emulator.clone();
    let profile = crate::svc::load_profile(&emulator)?;
    if args.sim {
        let socket = run_dir.join("i2c.sock");
        cfg.sensor.bus = format!("sim:{}", socket.display());
        emulator.socket = Some(socket);
        emulator.t0_ns = Some(t0);
    }
    let cfg_path = run_dir.join("config.toml");
    std::fs::write(&cfg_path, cfg.to_toml()).map_err(|e| format!("{}: {e}", cfg_path.display()))?;

    let mut sup = Supervisor::new(cfg.supervisor)?;
    let result = (|| {
        if args.sim {
            sup.start(ServiceSpec::svc("sim-sensor", sim_args(&emulator)))?;
            wait_for_socket(emulator.socket.as_ref().expect("set above"))?;
        }
        for spec in crate::supervisor::sensor_services(&cfg_path) {
            sup.start(spec)?;
        }
        collect(args, &cfg, &mut sup, profile_vertices(&profile), t0, show)
    })();
    sup.stop_all(Duration::from_secs(2));
    let _ = std::fs::remove_dir_all(&run_dir);
    let mut summary = result?;
    summary.service_deaths = sup.deaths.clone();
    Ok(summary)
}

fn sim_args(e: &SimSensorArgs) -> Vec<String> {
    let mut a = vec![
        "--socket".to_string(),
        e.socket
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        "--seed".into(),
        e.seed.to_string(),
    ];
    if let Some(t0) = e.t0_ns {
        a.extend(["--t0-ns".into(), t0.to_string()]);
    }
    if let Some(l) = &e.load {
        a.extend(["--load".into(), l.clone()]);
    }
    if let Some(p) = &e.profile {
        a.extend(["--profile".into(), p.display().to_string()]);
    }
    if e.ideal_sensor {
        a.push("--ideal-sensor".into());
    }
    for f in &e.faults {
        a.extend(["--fault".into(), f.clone()]);
    }
    a
}

fn wait_for_socket(path: &std::path::Path) -> Result<(), String> {
    for _ in 0..500 {
        if path.exists() {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Err(format!(
        "the emulated sensor did not open {}",
        path.display()
    ))
}

const SPANS: [&str; 6] = [
    "adc",
    "raw_to_tension",
    "tension_to_monitor",
    "sample_to_tension",
    "ramp_lag",
    "channel_skew",
];

fn collect(
    args: &SensorArgs,
    cfg: &rt_config::Config,
    sup: &mut Supervisor,
    truth: Option<Vec<(f64, [f64; 3])>>,
    t0: u64,
    show: &mut dyn FnMut(&str),
) -> Result<SensorSummary, String> {
    let ipc = Ipc::new(
        &format!("sensor-monitor-{}", std::process::id()),
        &cfg.ipc_root,
        &cfg.uav,
    )
    .map_err(|e| e.to_string())?;
    let raw_sub = ipc
        .subscriber::<RawAdcFrame>(names::RAW_ADC)
        .map_err(|e| e.to_string())?;
    let ten_sub = ipc
        .subscriber::<TensionSample>(names::TENSION)
        .map_err(|e| e.to_string())?;
    let mut spans = SpanHistograms::new(&SPANS);
    // Raw publish times by sequence, to time the raw -> tension hop.
    let mut raw_publish = [(u64::MAX, 0u64); 256];
    let mut raw_frames = 0u64;
    let mut last_raw = RawAdcFrame::default();
    let (mut n, mut flagged, mut lost) = (0u64, 0u64, 0u64);
    let mut flag_counts = [0u64; FLAG_NAMES.len()];
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    let (mut first_origin, mut last_origin) = (0u64, 0u64);
    let mut last_seq: Option<u64> = None;
    let mut started: Option<u64> = None;
    let mut next_show = 0u64;
    let show_period = (1e9 / args.display_hz.max(0.1)) as u64;
    let startup_deadline = now_ns() + 10_000_000_000;
    let mut latest = TensionSample::default();

    loop {
        if stop_requested() {
            break;
        }
        if let Verdict::Failed(why) = sup.poll() {
            return Err(why);
        }
        let now = now_ns();
        if started.is_none() && now > startup_deadline {
            return Err("no tension samples within 10 s of start".into());
        }
        if let Some(s) = started {
            if now >= s + (args.duration * 1e9) as u64 {
                break;
            }
        }
        ten_sub
            .wait(Duration::from_millis(20))
            .map_err(|e| e.to_string())?;
        // Raw frames first, so the tension samples below find their frame's publish time.
        raw_sub
            .drain(&mut |f: RawAdcFrame| {
                raw_frames += 1;
                raw_publish[(f.header.sequence % 256) as usize] =
                    (f.header.sequence, f.header.t_publish_ns);
                spans.record_span("adc", f.header.t_origin_ns, f.header.t_publish_ns);
                spans.record_span("channel_skew", 0, f.skew_ns());
                last_raw = f;
            })
            .map_err(|e| e.to_string())?;
        ten_sub
            .drain(&mut |s: TensionSample| {
                let rx = now_ns();
                if let Some(prev) = last_seq {
                    lost += s.header.sequence.saturating_sub(prev + 1);
                }
                last_seq = Some(s.header.sequence);
                latest = s;
                // Measure once the filter is full and the chain has settled.
                if s.flags & shared_types::tension_flags::FILTER_WARMUP != 0 {
                    return;
                }
                let begin = *started.get_or_insert(rx + 300_000_000);
                if rx < begin {
                    return;
                }
                n += 1;
                if n == 1 {
                    first_origin = s.header.t_origin_ns;
                }
                last_origin = s.header.t_origin_ns;
                for k in 0..3 {
                    sum[k] += s.force_body_n[k];
                    sum2[k] += s.force_body_n[k] * s.force_body_n[k];
                }
                if s.flags != 0 {
                    flagged += 1;
                }
                for (i, (bit, _)) in FLAG_NAMES.iter().enumerate() {
                    if s.flags & bit != 0 {
                        flag_counts[i] += 1;
                    }
                }
                let (seq, raw_pub) = raw_publish[(s.raw_sequence % 256) as usize];
                if seq == s.raw_sequence {
                    spans.record_span("raw_to_tension", raw_pub, s.header.t_publish_ns);
                }
                spans.record_span("tension_to_monitor", s.header.t_publish_ns, rx);
                spans.record_span(
                    "sample_to_tension",
                    s.header.t_origin_ns,
                    s.header.t_publish_ns,
                );
                if let Some(v) = &truth {
                    let t_read = (s.header.t_publish_ns as i64 - t0 as i64) as f64 * 1e-9;
                    if let Some(lag) = ramp_lag(v, 2, s.force_body_n[2], t_read, 0.1, 0.03) {
                        spans.record_signed("ramp_lag", (lag * 1e9) as i64);
                    }
                }
            })
            .map_err(|e| e.to_string())?;
        if now >= next_show {
            next_show = now + show_period;
            let f = latest.force_body_n;
            show(&format!(
                "\rforce FRD [N]  x {:8.3}  y {:8.3}  z {:8.3}   flags 0x{:02x}   samples {:6}",
                f[0], f[1], f[2], latest.flags, n
            ));
        }
    }
    show("\n");
    let nf = n.max(1) as f64;
    let mean = sum.map(|s| s / nf);
    let std = [0, 1, 2].map(|k| (sum2[k] / nf - mean[k] * mean[k]).max(0.0).sqrt());
    let span_s = (last_origin.saturating_sub(first_origin)) as f64 * 1e-9;
    let rate_hz = if n > 1 && span_s > 0.0 {
        (n - 1) as f64 / span_s
    } else {
        0.0
    };
    let mut latency_us = spans.summary();
    let skew_us = latency_us.remove("channel_skew");
    Ok(SensorSummary {
        mode: format!("{:?}", cfg.sensor.mode).to_lowercase(),
        duration_s: args.duration,
        mean_force_n: mean,
        std_force_n: std,
        rate_hz,
        samples: n,
        flagged,
        flags: FLAG_NAMES
            .iter()
            .zip(flag_counts)
            .filter(|(_, c)| *c > 0)
            .map(|((_, name), c)| (name.to_string(), c))
            .collect(),
        raw_frames,
        lost_samples: lost,
        bus_errors: last_raw.bus_errors,
        degraded_frames: last_raw.stale_frames,
        skew_us,
        latency_us,
        service_deaths: Vec::new(),
    })
}
