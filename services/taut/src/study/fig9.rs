//! A figure like the paper's Fig. 9: the cable force each drone's controller used, against the
//! plant's truth, from a flight with the estimator (left column) and one with the force sensor
//! (right column). Rows: x, y, z of uav1 then uav2. Frame: body FRD, the force the cable exerts
//! on the drone (what `TensionSample::force_body_n` holds for all three sources), so the
//! comparison involves no attitude. Drawn with the report's time plots (phases shaded).

use std::path::Path;

use recorder::{Recording, Timed};
use shared_types::{tension_flags, TensionSample};

use crate::report::load::{sample_time_ns, FlightData};
use crate::report::plot::{self, Column, Panel};
use crate::report::series::{self, Series, Source};

/// Whose force a column shows.
#[derive(Clone, Copy)]
pub enum Used {
    Sensor,
    Estimator,
}

/// One axis of a force channel, leaving out samples still warming their filter up (flagged
/// so by their stage: the sensor's first frames, the estimator's first IMU samples).
fn axis(
    f: &FlightData,
    samples: &[Timed<TensionSample>],
    i: usize,
    source: Source,
    label: &str,
) -> Series {
    Series {
        source,
        label: label.into(),
        points: samples
            .iter()
            .filter(|s| s.sample.flags & tension_flags::FILTER_WARMUP == 0)
            .map(|s| (f.secs(sample_time_ns(s)), s.sample.force_body_n[i]))
            .collect(),
    }
}

/// The panels of one column (3 per drone), its phases and time axis end.
fn column(rec: &Recording, used: Used) -> (Vec<Panel>, Vec<series::PhaseSpan>, f64) {
    let f = FlightData::from_recording(rec, Path::new(""));
    let (title, source) = match used {
        Used::Sensor => ("Force sensor", Source::Sensor),
        Used::Estimator => ("Estimator", Source::Estimator),
    };
    let mut panels = Vec::new();
    for d in &f.drones {
        let samples = match used {
            Used::Sensor => &d.tension,
            Used::Estimator => &d.tension_estimate,
        };
        for (i, name) in ["x", "y", "z"].iter().enumerate() {
            panels.push(Panel {
                caption: format!("{title}: {} {name}", d.id),
                y_label: format!("{name} force on the drone (FRD), N"),
                // Truth drawn last, on top.
                series: vec![
                    axis(&f, samples, i, source, "used by the controller"),
                    axis(&f, &d.tension_truth, i, Source::Truth, "truth"),
                ],
            });
        }
    }
    let end = series::end_s(&panels.iter().flat_map(|p| &p.series).collect::<Vec<_>>());
    let phases = f
        .drones
        .first()
        .map(|d| series::phases(&f, d, end))
        .unwrap_or_default();
    (panels, phases, end)
}

/// Draws the figure into `path`: `columns` side by side, each a recording and its source.
pub fn draw(path: &Path, columns: &[(&Recording, Used)], text: bool) -> Result<(), String> {
    let built: Vec<_> = columns.iter().map(|(r, u)| column(r, *u)).collect();
    let grid: Vec<Column> = built
        .iter()
        .map(|(panels, phases, end)| Column {
            panels,
            phases,
            t_end_s: *end,
        })
        .collect();
    plot::draw_time_grid(
        path,
        "Cable force on each drone, body FRD: the force the controller used vs the truth",
        &grid,
        text,
    )
    .map_err(|e| format!("{}: {e}", path.display()))
}
