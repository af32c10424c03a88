//! `taut report RUN.mcap --out DIR`: figures like the paper's from a recording, a latency
//! percentile plot per drone, and `report.md` with the latency table and the flight metrics.
//!
//! Files written into DIR:
//! - `positions_<uav>.png`: x, y, z (NED) of PX4's estimate and the truth against the nominal
//!   and the tension-shifted setpoints;
//! - `forces_<uav>.png`: the cable's pull on the drone in NED from the sensor, the estimator
//!   and the truth, and −T_d (see [`series`] for frames and signs);
//! - `payload.png`: payload position (NED) and swing angle (truth; absent without truth);
//! - `latency_<uav>.png`: percentile distribution per span;
//! - `report.md`.
//!
//! What is not recorded is left out and listed under "Absent or degraded"; only an unreadable
//! recording or an unwritable folder is an error.

mod flight_metrics;
mod json_tables;
mod latency;
pub(crate) mod load;
mod markdown;
pub(crate) mod plot;
mod plot_latency;
pub(crate) mod series;

use clap::Args;
use std::path::{Path, PathBuf};

use load::FlightData;
use markdown::{Figure, ReportContent};
use plot::Panel;
use series::Series;

#[derive(Args, Debug, Clone)]
pub struct ReportArgs {
    /// The recording (MCAP) to report on.
    pub recording: PathBuf,
    /// Folder for the figures and report.md (default: `report/` next to the recording).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Why no report could be written; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot read the recording {path}: {message}")]
    Read { path: String, message: String },
    #[error("cannot create the report folder {path}: {message}")]
    CreateDir { path: String, message: String },
    #[error("cannot draw {path}: {message}")]
    Figure { path: String, message: String },
    #[error("cannot write {path}: {message}")]
    Write { path: String, message: String },
}

/// What a report run wrote.
#[derive(Debug, Clone)]
pub struct ReportOutput {
    pub markdown: PathBuf,
    pub figures: Vec<PathBuf>,
    /// Absent channels and fallbacks, as listed in report.md.
    pub notes: Vec<String>,
}

pub fn run(args: &ReportArgs) -> Result<(), String> {
    let out = args.out.clone().unwrap_or_else(|| {
        args.recording
            .parent()
            .unwrap_or(Path::new("."))
            .join("report")
    });
    let r = write_report(&args.recording, &out).map_err(|e| e.to_string())?;
    for f in &r.figures {
        println!("[report] wrote {}", f.display());
    }
    println!(
        "[report] wrote {} ({} notes on absent or degraded data)",
        r.markdown.display(),
        r.notes.len()
    );
    Ok(())
}

/// Reads `recording` and writes the figures and report.md into `out` (created if needed).
pub fn write_report(recording: &Path, out: &Path) -> Result<ReportOutput, ReportError> {
    let flight = FlightData::open(recording)?;
    std::fs::create_dir_all(out).map_err(|e| ReportError::CreateDir {
        path: out.display().to_string(),
        message: e.to_string(),
    })?;
    let text = calibrate::plots::ensure_font(None).is_some();
    let mut notes = flight.notes.clone();
    if !text {
        notes.push("no TrueType font found (fonts-dejavu-core): figures drawn without text".into());
    }
    let setup = flight_metrics::setup(&flight, &mut notes);
    let mut figures: Vec<(Figure, PathBuf)> = Vec::new();
    let mut draw = |fig: Figure, f: &dyn Fn(&Path) -> Result<(), String>| {
        let path = out.join(&fig.file);
        f(&path).map_err(|message| ReportError::Figure {
            path: path.display().to_string(),
            message,
        })?;
        figures.push((fig, path));
        Ok::<(), ReportError>(())
    };

    let pos: Vec<[Vec<Series>; 3]> = flight
        .drones
        .iter()
        .map(|d| series::positions(&flight, d))
        .collect();
    let forces: Vec<[Vec<Series>; 3]> = flight
        .drones
        .iter()
        .map(|d| series::forces(&flight, d, &mut notes))
        .collect();
    let payload = series::payload_position(&flight);
    let swing = series::swing(&flight, setup.anchor_frd_m);
    let all: Vec<&Series> = pos
        .iter()
        .chain(&forces)
        .chain(std::iter::once(&payload))
        .flat_map(|axes| axes.iter().flatten())
        .chain(std::iter::once(&swing))
        .collect();
    let t_end = series::end_s(&all);
    let phases = flight
        .drones
        .first()
        .map(|d| series::phases(&flight, d, t_end))
        .unwrap_or_default();

    for (k, d) in flight.drones.iter().enumerate() {
        let panels = axis_panels(&pos[k], "position", "m");
        draw(
            Figure {
                file: format!("positions_{}.png", d.id),
                title: format!("{}: position, NED", d.id),
                caption: format!(
                    "{}'s position per NED axis, m: PX4's estimate (blue) and the true position \
                     (black) against the mission's nominal setpoint ξ̄_d (green) and the \
                     controller's tension-shifted setpoint ξ_d (purple, flight steps only).",
                    d.id
                ),
            },
            &|p| {
                plot::draw_time_figure(
                    p,
                    &format!("{}: position (NED) against setpoints", d.id),
                    &panels,
                    &phases,
                    t_end,
                    text,
                )
            },
        )?;
        let panels = axis_panels(&forces[k], "cable force", "N");
        draw(
            Figure {
                file: format!("forces_{}.png", d.id),
                title: format!("{}: cable force, NED", d.id),
                caption: format!(
                    "The cable's pull on {} per NED axis, N (+z = down; a hanging load reads \
                     +z): the force sensor (blue) and the model-based estimator (orange), both \
                     rotated from body FRD with PX4's attitude estimate; the truth (black) rotated \
                     with the plant's attitude; −T_d (green), the controller's static tension \
                     expressed as a pull on the drone.",
                    d.id
                ),
            },
            &|p| {
                plot::draw_time_figure(
                    p,
                    &format!("{}: cable pull on the drone (NED)", d.id),
                    &panels,
                    &phases,
                    t_end,
                    text,
                )
            },
        )?;
    }
    if flight.truth.is_empty() {
        notes.push("no /plant/truth: no payload figure".into());
    } else {
        let mut panels = axis_panels(&payload, "payload position", "m");
        panels.push(Panel {
            caption: "payload swing: pendulum angle about the line through the anchors".into(),
            y_label: "swing, deg".into(),
            series: if swing.points.is_empty() {
                vec![]
            } else {
                vec![swing.clone()]
            },
        });
        draw(
            Figure {
                file: "payload.png".into(),
                title: "Payload: position and swing".into(),
                caption: "The payload's true position per NED axis, m, and its swing angle, \
                          degrees: the angle between the anchors-to-payload plane and the \
                          vertical plane through the two cable anchors (as the flight metrics \
                          define it)."
                    .into(),
            },
            &|p| {
                plot::draw_time_figure(
                    p,
                    "Payload: position (NED) and swing",
                    &panels,
                    &phases,
                    t_end,
                    text,
                )
            },
        )?;
    }
    let spans: Vec<latency::SpanLatency> = flight
        .drones
        .iter()
        .flat_map(latency::drone_spans)
        .collect();
    for d in &flight.drones {
        let mine: Vec<latency::SpanLatency> =
            spans.iter().filter(|s| s.drone == d.id).cloned().collect();
        draw(
            Figure {
                file: format!("latency_{}.png", d.id),
                title: format!("{}: latency percentiles", d.id),
                caption: format!(
                    "{}: latency per span (definitions under Latency) against the percentile, \
                     on HdrHistogram's log scale of 1/(1 − p); latency in ms.",
                    d.id
                ),
            },
            &|p| {
                plot_latency::draw_latency_figure(
                    p,
                    &format!("{}: latency percentile distribution per span", d.id),
                    &mine,
                    text,
                )
            },
        )?;
    }

    let metrics = serde_json::to_value(flight_metrics::compute(&flight, &setup)).ok();
    let summary_json = summary_next_to(recording, &mut notes);
    let figs: Vec<Figure> = figures.iter().map(|(f, _)| f.clone()).collect();
    let md = markdown::render_report(&ReportContent {
        flight: &flight,
        figures: &figs,
        spans: &spans,
        metrics,
        summary_json,
        notes: &notes,
    });
    let md_path = out.join("report.md");
    std::fs::write(&md_path, md).map_err(|e| ReportError::Write {
        path: md_path.display().to_string(),
        message: e.to_string(),
    })?;
    Ok(ReportOutput {
        markdown: md_path,
        figures: figures.into_iter().map(|(_, p)| p).collect(),
        notes,
    })
}

/// Three panels (x, y, z) of one quantity.
fn axis_panels(axes: &[Vec<Series>; 3], what: &str, unit: &str) -> Vec<Panel> {
    ["x (north)", "y (east)", "z (down)"]
        .iter()
        .zip(axes)
        .map(|(axis, s)| Panel {
            caption: format!("{what}, {axis}"),
            y_label: format!("{} {what}, {unit}", &axis[..1]),
            series: s.clone(),
        })
        .collect()
}

/// `summary.json` beside the recording, if there is one and it parses.
fn summary_next_to(
    recording: &Path,
    notes: &mut Vec<String>,
) -> Option<(String, serde_json::Value)> {
    let p = recording
        .parent()
        .unwrap_or(Path::new("."))
        .join("summary.json");
    let text = std::fs::read_to_string(&p).ok()?;
    match serde_json::from_str(&text) {
        Ok(v) => Some((p.display().to_string(), v)),
        Err(e) => {
            notes.push(format!("{}: not JSON ({e}): not rendered", p.display()));
            None
        }
    }
}
