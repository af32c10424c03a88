//! A figure like the paper's Fig. 9: the cable force each drone's controller used, against the
//! plant's truth, from a flight with the estimator (left column) and one with the force sensor
//! (right column). Rows: x, y, z of uav1 then uav2. Frame: body FRD, the force the cable exerts
//! on the drone (what `TensionSample::force_body_n` holds for all three sources), so the
//! comparison involves no attitude. Time from the first truth sample; Move and Hold shaded.

use std::path::Path;

use plotters::prelude::*;
use recorder::{Recording, Timed};
use shared_types::{names, tension_flags, MissionPhase, MissionSetpoint, TensionSample};

/// One column: a flight and the topic of the force its controller used.
pub struct Column<'a> {
    pub title: String,
    pub recording: &'a Recording,
    pub topic: &'static str,
}

type Series = Vec<(f64, f64)>;

/// One axis over time; samples still warming their filter up (flagged so by their stage:
/// the sensor's first frames, the estimator's first IMU samples) are left out.
fn series(samples: &[Timed<TensionSample>], t0: u64, axis: usize) -> Series {
    samples
        .iter()
        .filter(|s| s.sample.flags & tension_flags::FILTER_WARMUP == 0)
        .map(|s| {
            (
                s.log_time_ns.saturating_sub(t0) as f64 * 1e-9,
                s.sample.force_body_n[axis],
            )
        })
        .collect()
}

/// Spans (start s, end s, phase) of uav1's mission phases.
fn phase_spans(rec: &Recording, uav: &str, t0: u64) -> Vec<(f64, f64, MissionPhase)> {
    let missions: Vec<Timed<MissionSetpoint>> = rec
        .samples(uav, names::MISSION_SETPOINT)
        .unwrap_or_default();
    let mut spans: Vec<(f64, f64, MissionPhase)> = Vec::new();
    for m in &missions {
        let t = m.log_time_ns.saturating_sub(t0) as f64 * 1e-9;
        match spans.last_mut() {
            Some(last) if last.2 == m.sample.phase => last.1 = t,
            _ => spans.push((t, t, m.sample.phase)),
        }
    }
    spans
}

/// Draws the figure into `path` (1400 × 1500 px).
pub fn draw(path: &Path, uavs: &[String], columns: &[Column]) -> Result<(), String> {
    let err = |e: String| format!("{}: {e}", path.display());
    let root = BitMapBackend::new(path, (1400, 1500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let (title_area, body) = root.split_vertically(40);
    title_area
        .titled(
            "Cable force on each drone (body FRD, N): source used by the controller vs truth",
            ("sans-serif", 22),
        )
        .map_err(|e| err(e.to_string()))?;
    let rows = uavs.len() * 3;
    let cells = body.split_evenly((rows, columns.len()));
    for (ci, col) in columns.iter().enumerate() {
        for (ui, uav) in uavs.iter().enumerate() {
            let used: Vec<Timed<TensionSample>> = col
                .recording
                .samples(uav, col.topic)
                .map_err(|e| err(e.to_string()))?;
            let truth: Vec<Timed<TensionSample>> = col
                .recording
                .samples(uav, names::TENSION_TRUTH)
                .map_err(|e| err(e.to_string()))?;
            let t0 = truth.first().or(used.first()).map_or(0, |s| s.log_time_ns);
            let spans = phase_spans(col.recording, &uavs[0], t0);
            for (axis, name) in ["x", "y", "z"].iter().enumerate() {
                let area = &cells[(ui * 3 + axis) * columns.len() + ci];
                let u = series(&used, t0, axis);
                let tr = series(&truth, t0, axis);
                draw_panel(
                    area,
                    &format!("{} — {uav} {name}", col.title),
                    &u,
                    &tr,
                    &spans,
                )
                .map_err(err)?;
            }
        }
    }
    root.present().map_err(|e| err(e.to_string()))
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    used: &Series,
    truth: &Series,
    spans: &[(f64, f64, MissionPhase)],
) -> Result<(), String> {
    let e = |x: &dyn std::fmt::Display| x.to_string();
    let all = used.iter().chain(truth.iter());
    let t_max = all.clone().map(|p| p.0).fold(1.0_f64, f64::max);
    let (mut lo, mut hi) = all
        .map(|p| p.1)
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)));
    if lo > hi {
        (lo, hi) = (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(0.2);
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 15))
        .margin(6)
        .x_label_area_size(22)
        .y_label_area_size(45)
        .build_cartesian_2d(0.0..t_max, (lo - pad)..(hi + pad))
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_labels(8)
        .y_labels(5)
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|x| e(&x))?;
    for (a, b, phase) in spans {
        let shade = match phase {
            MissionPhase::Move => RGBColor(255, 235, 200),
            MissionPhase::Hold => RGBColor(220, 235, 255),
            MissionPhase::Takeoff => RGBColor(230, 245, 230),
            _ => continue,
        };
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(*a, lo - pad), (*b, hi + pad)],
                shade.filled(),
            )))
            .map_err(|x| e(&x))?;
    }
    chart
        .draw_series(LineSeries::new(
            truth.iter().copied(),
            BLACK.stroke_width(2),
        ))
        .map_err(|x| e(&x))?
        .label("truth")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLACK));
    chart
        .draw_series(LineSeries::new(used.iter().copied(), RED.stroke_width(1)))
        .map_err(|x| e(&x))?
        .label("used by the controller")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], RED));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 11))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|x| e(&x))?;
    Ok(())
}
