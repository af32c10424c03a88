//! `taut calibrate`: a calibration from a recorded bench session, or the paper's procedure run
//! on the emulated sensor (`--synthetic`), written as config plus a report with box plots.

use calibrate::{CalibrateOptions, SyntheticOptions};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct CalibrateArgs {
    /// Recorded raw frames with known reference loads (CSV; format in the README).
    #[arg(long, conflicts_with = "synthetic")]
    pub recording: Option<PathBuf>,
    /// Run the paper's procedure on the emulated sensor, offline, faster than real time.
    #[arg(long)]
    pub synthetic: bool,
    /// Frames per held weight in --synthetic (the paper: 3000).
    #[arg(long, default_value_t = 3000)]
    pub samples_per_step: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Nominal config (cell constants, geometry); default: the embedded simulation config.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output folder: calibration.toml, config-calibrated.toml, report.md/json, PNGs.
    #[arg(long, default_value = "calibration")]
    pub out: PathBuf,
}

pub fn run(args: &CalibrateArgs) -> Result<(), String> {
    let config = crate::load_config(args.config.as_deref())?;
    let opts = match (&args.recording, args.synthetic) {
        (Some(path), false) => {
            CalibrateOptions::from_recording(path.clone(), config.clone(), args.out.clone())
        }
        (None, true) => CalibrateOptions::synthetic(
            SyntheticOptions {
                seed: args.seed,
                samples_per_step: args.samples_per_step,
                ..SyntheticOptions::default()
            },
            config,
            args.out.clone(),
        ),
        _ => return Err("give --recording FILE or --synthetic".into()),
    };
    let outcome = calibrate::run(&opts).map_err(|e| e.to_string())?;
    let report = args.out.join("report.md");
    if let Ok(md) = std::fs::read_to_string(&report) {
        println!("{md}");
    }
    for f in &outcome.files {
        eprintln!("wrote {}", f.display());
    }
    if outcome.font.is_none() {
        eprintln!("note: no TTF font found; plots have no text (install fonts-dejavu-core)");
    }
    Ok(())
}
