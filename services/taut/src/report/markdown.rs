//! `report.md`: the recording at a glance, the figures, the latency table, the flight metrics
//! computed from the recording, and `summary.json` if one sits next to the recording.

use serde_json::Value;
use std::fmt::Write;

use super::json_tables::{number, render};
use super::latency::{SpanLatency, SPANS};
use super::load::FlightData;

/// A figure written, for the markdown.
#[derive(Debug, Clone)]
pub struct Figure {
    /// File name inside the report folder.
    pub file: String,
    pub title: String,
    /// What it shows, one paragraph.
    pub caption: String,
}

/// Everything report.md is made of.
pub struct ReportContent<'a> {
    pub flight: &'a FlightData,
    pub figures: &'a [Figure],
    pub spans: &'a [SpanLatency],
    /// The metrics computed from the recording, as JSON.
    pub metrics: Option<Value>,
    /// `summary.json` of the flight (its path and content), if found.
    pub summary_json: Option<(String, Value)>,
    pub notes: &'a [String],
}

pub fn render_report(c: &ReportContent<'_>) -> String {
    let f = c.flight;
    let mut md = String::new();
    let name = f.path.file_name().map_or_else(
        || f.path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let _ = writeln!(md, "# Flight report: {name}\n");
    overview(&mut md, f);
    if !c.notes.is_empty() {
        md.push_str("## Absent or degraded\n\n");
        for n in c.notes {
            let _ = writeln!(md, "- {n}");
        }
        md.push('\n');
    }
    md.push_str("## Figures\n\n");
    md.push_str(
        "Time is in seconds since the first recorded sample (each sample at its own time: the \
         physical measurement `t_origin_ns`, the controller's step time for attitude setpoints). \
         Mission phases of the first drone are shaded (Idle/Done grey, Takeoff blue, Move orange, \
         Hold green, Land purple).\n\n",
    );
    for fig in c.figures {
        let _ = writeln!(
            md,
            "### {}\n\n{}\n\n![{}]({})\n",
            fig.title, fig.caption, fig.title, fig.file
        );
    }
    latency_table(&mut md, c.spans, f.mode.as_deref());
    md.push_str("## Flight metrics (computed from the recording)\n\n");
    md.push_str(
        "The recorded truth, mission setpoints and attitude setpoints fed to the simulator's \
         metrics in the order the recorder took them; definitions in `sim/metrics.rs`. Without \
         `/plant/truth` most are absent.\n\n",
    );
    match &c.metrics {
        Some(v) => md.push_str(&render(v, 3)),
        None => md.push_str("Not computed.\n\n"),
    }
    if let Some((path, v)) = &c.summary_json {
        let _ = writeln!(md, "## summary.json of the flight\n\nFrom `{path}`.\n");
        md.push_str(&render(v, 3));
    }
    md
}

fn overview(md: &mut String, f: &FlightData) {
    let _ = writeln!(md, "- Recording: `{}`", f.path.display());
    let _ = writeln!(
        md,
        "- Mode: {}",
        f.mode.as_deref().unwrap_or("not recorded")
    );
    let ids: Vec<&str> = f.drones.iter().map(|d| d.id.as_str()).collect();
    let _ = writeln!(
        md,
        "- Drones: {}",
        if ids.is_empty() {
            "none".into()
        } else {
            ids.join(", ")
        }
    );
    let _ = writeln!(
        md,
        "- Plant truth: {}",
        if f.truth.is_empty() {
            "absent".to_string()
        } else {
            format!("{} samples", f.truth.len())
        }
    );
    let _ = writeln!(
        md,
        "- Complete file: {}",
        if f.truncated { "no (truncated)" } else { "yes" }
    );
    if !f.drops.is_empty() {
        let lost: Vec<String> = f
            .drops
            .iter()
            .filter(|(_, v)| v.as_str() != "0")
            .map(|(k, v)| format!("{k}: {v}"))
            .collect();
        let _ = writeln!(
            md,
            "- Samples lost to sequence gaps: {}",
            if lost.is_empty() {
                "none".into()
            } else {
                lost.join(", ")
            }
        );
    }
    md.push_str("\n| drone | topic | samples |\n|---|---|---|\n");
    for d in &f.drones {
        let counts = [
            ("raw_adc", d.raw_adc.len()),
            ("tension", d.tension.len()),
            ("tension_estimate", d.tension_estimate.len()),
            ("tension_truth", d.tension_truth.len()),
            ("vehicle_state", d.vehicle_state.len()),
            ("imu", d.imu.len()),
            ("motor_speeds", d.motor_speeds.len()),
            ("mission_setpoint", d.mission.len()),
            ("attitude_setpoint", d.attitude.len()),
        ];
        for (t, n) in counts {
            let _ = writeln!(md, "| {} | {t} | {n} |", d.id);
        }
    }
    let _ = writeln!(md, "| plant | truth | {} |\n", f.truth.len());
}

/// The latency table; a row per drone and span with samples.
fn latency_table(md: &mut String, spans: &[SpanLatency], mode: Option<&str>) {
    md.push_str("## Latency\n\n");
    if mode == Some("fast") {
        md.push_str(
            "Fast mode: every time is simulated, so these are the simulation's schedule, not the \
             machine's latencies.\n\n",
        );
    }
    md.push_str(
        "| drone | span | n | p50 ms | p90 ms | p99 ms | p99.9 ms | max ms | negative |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for s in spans.iter().filter(|s| s.count() > 0 || s.negatives > 0) {
        let q = |p: f64| number(s.quantile_ms(p));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            s.drone,
            s.span,
            s.count(),
            q(0.5),
            q(0.9),
            q(0.99),
            q(0.999),
            number(s.max_ms()),
            s.negatives
        );
    }
    md.push_str("\nSpans (HDR histograms, 3 significant digits):\n\n");
    for (name, def) in SPANS {
        let _ = writeln!(md, "- **{name}**: {def}");
    }
    let empty: Vec<String> = spans
        .iter()
        .filter(|s| s.count() == 0 && s.negatives == 0)
        .map(|s| format!("{} {}", s.drone, s.span))
        .collect();
    if !empty.is_empty() {
        let _ = writeln!(md, "\nNo samples: {}.", empty.join(", "));
    }
    md.push('\n');
}
