//! The entry point behind `taut calibrate`: recording (or synthetic bench) in, calibration,
//! report and plots out.

use crate::fit::{self, FitError, FitOptions};
use crate::plots::{self, PlotError, PlotOptions};
use crate::recording::{Recording, RecordingError};
use crate::report::Report;
use crate::synthetic::{self, SyntheticOptions};
use rt_config::{CalibrationConfig, Config};
use std::path::{Path, PathBuf};

/// What to calibrate and where to write the results. Exactly one of `recording` and
/// `synthetic` must be set.
#[derive(Debug, Clone)]
pub struct CalibrateOptions {
    /// A bench recording in the format of [`crate::recording`].
    pub recording: Option<PathBuf>,
    /// Generate the bench session on the emulated sensor instead.
    pub synthetic: Option<SyntheticOptions>,
    /// The drone's config: nominal cell constants and geometry (its `[calibration]` is ignored).
    pub config: Config,
    /// Created if missing; files in it are overwritten.
    pub out_dir: PathBuf,
    pub fit: FitOptions,
    pub plots: PlotOptions,
}

impl CalibrateOptions {
    /// Calibrate a recording with default fit and plot options.
    pub fn from_recording(path: PathBuf, config: Config, out_dir: PathBuf) -> Self {
        Self {
            recording: Some(path),
            synthetic: None,
            config,
            out_dir,
            fit: FitOptions::default(),
            plots: PlotOptions::default(),
        }
    }

    /// Calibrate the emulated sensor with default fit and plot options.
    pub fn synthetic(opts: SyntheticOptions, config: Config, out_dir: PathBuf) -> Self {
        Self {
            recording: None,
            synthetic: Some(opts),
            ..Self::from_recording(PathBuf::new(), config, out_dir)
        }
    }
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct CalibrateOutcome {
    pub calibration: CalibrationConfig,
    pub report: Report,
    /// Every file written, in order.
    pub files: Vec<PathBuf>,
    /// The font the plots were labelled with; None: plots without text (or no plots).
    pub font: Option<PathBuf>,
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    #[error("options: {0}")]
    Options(String),
    #[error(transparent)]
    Recording(#[from] RecordingError),
    #[error("synthetic bench: {0}")]
    Synthetic(String),
    #[error("fit: {0}")]
    Fit(#[from] FitError),
    #[error("the fitted calibration does not pass the config checks: {0}")]
    Config(String),
    #[error("cannot write {path}: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// `calibration.toml`: a `[calibration]` table to paste into (or merge with) a drone config.
/// Written by hand rather than by `toml` so each coefficient vector sits on one line; floats
/// use Rust's shortest round-trip form, so reading it back gives the same bits.
pub fn calibration_toml(cal: &CalibrationConfig) -> String {
    let v = |x: &[f64]| {
        let items: Vec<String> = x.iter().map(|f| format!("{f:?}")).collect();
        format!("[{}]", items.join(", "))
    };
    let rows: Vec<String> = cal
        .crossload
        .iter()
        .map(|r| format!("    {},\n", v(r)))
        .collect();
    format!(
        "# Written by `taut calibrate`: paste into the drone's config, replacing its \
         [calibration] table.\n\
         [calibration]\n\
         # gamma_j = raw / true force of cells 1..4; the stage divides by it.\n\
         cell_gain = {}\n\
         # Per-axis correction of the equilibrium force in S, N: c0 + c1 T + c2 T^2 + c3 T^3.\n\
         poly_x = {}\n\
         poly_y = {}\n\
         poly_z = {}\n\
         # Crossload compensation, row-major: T'' = C T'.\n\
         crossload = [\n{}]\n",
        v(&cal.cell_gain),
        v(&cal.poly_x),
        v(&cal.poly_y),
        v(&cal.poly_z),
        rows.concat()
    )
}

/// The whole config `cfg` with `cal` as its calibration, as TOML that
/// `rt_config::Config::from_toml_str` accepts (the config without a calibration, then
/// [`calibration_toml`]).
pub fn write_config_with_calibration(cfg: &Config, cal: &CalibrationConfig) -> String {
    let mut bare = cfg.clone();
    bare.calibration = None;
    format!(
        "# taut config of {}, with a calibration written by `taut calibrate`.\n{}\n{}",
        cfg.uav,
        bare.to_toml(),
        calibration_toml(cal)
    )
}

const ONE_SOURCE: &str = "give exactly one of a recording path and synthetic options";

fn write(path: &Path, text: &str, files: &mut Vec<PathBuf>) -> Result<(), CalibrateError> {
    std::fs::write(path, text).map_err(|source| CalibrateError::Write {
        path: path.display().to_string(),
        source,
    })?;
    files.push(path.to_path_buf());
    Ok(())
}

/// Runs a calibration: loads or generates the recording, fits, checks the result against the
/// config rules, writes `calibration.toml`, `config-calibrated.toml` (the whole config),
/// `report.md`, `report.json`, the PNGs and, for a synthetic run, `recording.csv`.
pub fn run(opts: &CalibrateOptions) -> Result<CalibrateOutcome, CalibrateError> {
    if opts.recording.is_some() == opts.synthetic.is_some() {
        // Checked before anything is written.
        return Err(CalibrateError::Options(ONE_SOURCE.into()));
    }
    let out = &opts.out_dir;
    std::fs::create_dir_all(out).map_err(|source| CalibrateError::Write {
        path: out.display().to_string(),
        source,
    })?;
    let mut files = vec![];
    let mut notes = vec![];
    let (recording, source) = match (&opts.recording, &opts.synthetic) {
        (Some(path), None) => (Recording::load(path)?, path.display().to_string()),
        (None, Some(syn)) => {
            let s = synthetic::generate(&opts.config, syn).map_err(CalibrateError::Synthetic)?;
            let path = out.join("recording.csv");
            s.recording.save(&path)?;
            files.push(path);
            notes.push(format!(
                "synthetic: lateral full scale {} kg; injected gain_error {:?}, crossload {:?}, \
                 nonlinearity {:?}, hysteresis {:?}",
                s.lateral_max_weight_kg,
                s.params.gain_error,
                s.params.crossload,
                s.params.nonlinearity,
                s.params.hysteresis
            ));
            let source = format!(
                "synthetic bench, seed {}, {} samples per step, {} cycles",
                syn.seed, syn.samples_per_step, syn.cycles
            );
            (s.recording, source)
        }
        _ => return Err(CalibrateError::Options(ONE_SOURCE.into())),
    };
    let cal = fit::fit(&recording, &opts.config, &opts.fit)?;
    let whole = write_config_with_calibration(&opts.config, &cal);
    Config::from_toml_str(&whole, "<calibrated config>")
        .map_err(|e| CalibrateError::Config(e.to_string()))?;

    let mut report = Report::build(&recording, &opts.config, &cal, source);
    report.notes.extend(notes);
    write(
        &out.join("calibration.toml"),
        &calibration_toml(&cal),
        &mut files,
    )?;
    write(&out.join("config-calibrated.toml"), &whole, &mut files)?;
    write(&out.join("report.md"), &report.markdown(), &mut files)?;
    write(&out.join("report.json"), &report.to_json(), &mut files)?;
    let mut font = None;
    if opts.plots.enabled {
        font = plots::ensure_font(opts.plots.font_path.as_deref());
        files.extend(plots::draw_all(&report, out, font.is_some())?);
    }
    Ok(CalibrateOutcome {
        calibration: cal,
        report,
        files,
        font,
    })
}
