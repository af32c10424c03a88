//! The calibration report: metrics before (nominal constants) and after (fitted calibration),
//! as JSON and as a markdown table.

use crate::metrics::{self, MetricKind, Metrics};
use crate::recording::{Axis, Recording};
use rt_config::{CalibrationConfig, Config};
use serde::Serialize;
use std::fmt::Write as _;

/// Everything `report.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// Where the data came from (a path, or the synthetic seed and sample count).
    pub source: String,
    pub steps: usize,
    pub frames: usize,
    pub calibration: CalibrationConfig,
    /// Nominal constants, no calibration.
    pub before: Metrics,
    /// With `calibration`, applied by the tension stage.
    pub after: Metrics,
    /// Extra facts worth reading (synthetic truth, saturation warnings).
    pub notes: Vec<String>,
}

impl Report {
    /// Reads `rec` through the tension stage without and with `cal` and computes both metric
    /// sets.
    pub fn build(rec: &Recording, cfg: &Config, cal: &CalibrationConfig, source: String) -> Self {
        let (before, sat_b) = metrics::step_outputs(rec, cfg, None);
        let (after, sat_a) = metrics::step_outputs(rec, cfg, Some(cal));
        let mut notes = vec![];
        if sat_b > 0 {
            notes.push(format!(
                "{sat_b} frames have a code at a rail (-2048/2047): those steps are clipped"
            ));
        }
        Self {
            source,
            steps: rec.steps.len(),
            frames: rec.frames(),
            calibration: cal.clone(),
            before: metrics::compute(&before, sat_b),
            after: metrics::compute(&after, sat_a),
            notes,
        }
    }

    /// Pretty JSON (NaN as null).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// The report as markdown: the metric table and the calibration.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Force sensor calibration report\n");
        let _ = writeln!(
            s,
            "Source: {}. {} steps, {} frames.\n",
            self.source, self.steps, self.frames
        );
        let _ = writeln!(
            s,
            "Values in %FS, FS = heaviest weight of the axis test x g. *max*: over all cycles \
             and weights; *median*: of all per-cycle values. Before: nominal constants, no \
             calibration; after: the calibration below, applied by the tension stage. Crossload \
             is the output of the unloaded axes in %FS of the loaded axis. Non-linearity is \
             against the best-fit line of each cycle, so a linear correction does not change \
             it.\n"
        );
        s.push_str(&self.table());
        let _ = writeln!(s, "\n## Calibration\n");
        let c = &self.calibration;
        let _ = writeln!(
            s,
            "- cell_gain (gamma_j, raw / true): {}",
            fmt_vec(&c.cell_gain)
        );
        let _ = writeln!(s, "- poly_x: {}", fmt_vec(&c.poly_x));
        let _ = writeln!(s, "- poly_y: {}", fmt_vec(&c.poly_y));
        let _ = writeln!(s, "- poly_z: {}", fmt_vec(&c.poly_z));
        for (r, row) in c.crossload.iter().enumerate() {
            let _ = writeln!(s, "- crossload row {r}: {}", fmt_vec(row));
        }
        if !self.notes.is_empty() {
            let _ = writeln!(s, "\n## Notes\n");
            for n in &self.notes {
                let _ = writeln!(s, "- {n}");
            }
        }
        s
    }

    /// The metric table alone (markdown).
    pub fn table(&self) -> String {
        let mut s = String::from(
            "| axis test | FS (N) | metric | before max | before median | after max | after median |\n\
             |---|---:|---|---:|---:|---:|---:|\n",
        );
        for axis in Axis::ALL {
            let (Some(b), Some(a)) = (self.before.axis(axis), self.after.axis(axis)) else {
                continue;
            };
            for kind in MetricKind::ALL {
                let (mb, ma) = (b.get(kind), a.get(kind));
                let _ = writeln!(
                    s,
                    "| {axis} | {:.2} | {} | {} | {} | {} | {} |",
                    b.full_scale_n,
                    kind.title(),
                    pct(mb.max),
                    pct(mb.median),
                    pct(ma.max),
                    pct(ma.median)
                );
            }
        }
        s
    }
}

fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "-".into()
    }
}

fn fmt_vec(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:.6e}")).collect();
    format!("[{}]", items.join(", "))
}
