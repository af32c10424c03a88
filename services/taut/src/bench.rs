//! `taut bench sensor`: the filter-budget benchmark. The emulator applies a triangle wave
//! whose timing it knows; the lag of the tension output behind the true force is a histogram.

use crate::sensor::{self, ModeArg, SensorArgs};
use clap::{Args, Subcommand};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub which: BenchKind,
}

#[derive(Subcommand, Debug)]
pub enum BenchKind {
    /// Lag of the tension output behind a known force ramp, and every hop's latency.
    Sensor {
        #[arg(long, default_value_t = 20.0)]
        duration: f64,
        #[arg(long)]
        mode: Option<ModeArg>,
        /// Write the summary JSON here too.
        #[arg(long)]
        out: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
}

pub fn run(args: &BenchArgs) -> Result<(), String> {
    let BenchKind::Sensor {
        duration,
        mode,
        out,
        json,
    } = &args.which;
    // 5 N -> 45 N on z and back, 0.4 s per edge: 100 N/s, so one LSB of one cell (0.06 N)
    // is 0.6 ms of lag resolution before averaging.
    let tri =
        latency_tests::triangle_wave([0.0, 0.0, 5.0], [0.0, 0.0, 45.0], 0.4, 0.5, duration + 20.0);
    let dir = std::env::temp_dir().join(format!("taut-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let profile = dir.join("triangle.csv");
    let csv: String = tri
        .iter()
        .map(|(t, f)| format!("{t},{},{},{}\n", f[0], f[1], f[2]))
        .collect();
    std::fs::write(&profile, format!("t,fx,fy,fz\n{csv}")).map_err(|e| e.to_string())?;
    let sensor_args = SensorArgs {
        sim: true,
        config: None,
        duration: *duration,
        json: true,
        mode: *mode,
        display_hz: 1.0,
        emulator: crate::svc::SimSensorArgs {
            profile: Some(profile),
            ..Default::default()
        },
    };
    let summary = sensor::measure(&sensor_args, &mut |_| {});
    let _ = std::fs::remove_dir_all(&dir);
    let summary = summary?;
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    if let Some(p) = out {
        std::fs::write(p, &text).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    if *json {
        println!("{text}");
    } else {
        println!(
            "mode {}, {} samples at {:.2} Hz",
            summary.mode, summary.samples, summary.rate_hz
        );
        sensor::print_spans(&summary);
    }
    Ok(())
}
