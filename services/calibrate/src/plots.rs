//! Box plots like the paper's Fig. 5: one PNG per metric, one panel per axis test (rows) and
//! before/after (columns, each with its own scale so the small "after" boxes stay readable).
//! Box: Q1..Q3; line: median; whiskers: min..max, per applied weight.
//!
//! Text needs a TrueType font (plotters' `ab_glyph` backend loads no system fonts). We load
//! DejaVuSans.ttf (Debian/Ubuntu package `fonts-dejavu-core`) at run time, or the file given
//! in [`PlotOptions::font_path`]; without one the plots are drawn without any text.

use crate::metrics::{quantile, Metric, MetricKind, Metrics};
use crate::recording::Axis;
use crate::report::Report;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Where the default font is looked for, in order.
pub const FONT_CANDIDATES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// Plot settings.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotOptions {
    pub enabled: bool,
    /// A TTF to label the plots with; None = the first of [`FONT_CANDIDATES`] that exists.
    pub font_path: Option<PathBuf>,
}

impl Default for PlotOptions {
    fn default() -> Self {
        Self {
            enabled: true,
            font_path: None,
        }
    }
}

/// Failure to draw or write a PNG.
#[derive(Debug, thiserror::Error)]
#[error("cannot draw {path}: {message}")]
pub struct PlotError {
    pub path: String,
    pub message: String,
}

/// Registers the font once per process (plotters keeps fonts in a global table and wants
/// `'static` bytes, so the file is leaked once). The first call decides for the whole process.
/// Returns the font used, None if none loads.
pub fn ensure_font(path: Option<&Path>) -> Option<PathBuf> {
    static FONT: OnceLock<Option<PathBuf>> = OnceLock::new();
    FONT.get_or_init(|| {
        let candidates: Vec<PathBuf> = match path {
            Some(p) => vec![p.to_path_buf()],
            None => FONT_CANDIDATES.iter().map(PathBuf::from).collect(),
        };
        candidates.into_iter().find(|p| {
            let Ok(bytes) = std::fs::read(p) else {
                return false;
            };
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
        })
    })
    .clone()
}

/// The PNG name of a metric.
pub fn file_name(kind: MetricKind) -> &'static str {
    match kind {
        MetricKind::Hysteresis => "hysteresis.png",
        MetricKind::NonLinearity => "nonlinearity.png",
        MetricKind::Repeatability => "repeatability.png",
        MetricKind::Crossload => "crossload.png",
        MetricKind::Error => "error.png",
    }
}

/// Draws one PNG per metric into `dir`; returns the files written.
pub fn draw_all(report: &Report, dir: &Path, text: bool) -> Result<Vec<PathBuf>, PlotError> {
    MetricKind::ALL
        .iter()
        .map(|&kind| {
            let path = dir.join(file_name(kind));
            draw_metric(report, kind, &path, text).map_err(|message| PlotError {
                path: path.display().to_string(),
                message,
            })?;
            Ok(path)
        })
        .collect()
}

const BEFORE: RGBColor = RGBColor(196, 78, 52);
const AFTER: RGBColor = RGBColor(44, 102, 190);

fn draw_metric(report: &Report, kind: MetricKind, path: &Path, text: bool) -> Result<(), String> {
    let root = BitMapBackend::new(path, (1400, 1250)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let body = if text {
        let title = format!(
            "{} (%FS) per applied weight: before | after calibration",
            kind.title()
        );
        root.titled(&title, ("sans-serif", 26))
            .map_err(|e| e.to_string())?
    } else {
        root.clone()
    };
    let panels = body.split_evenly((3, 2));
    for (i, panel) in panels.iter().enumerate() {
        let axis = Axis::ALL[i / 2];
        let (metrics, label, color): (&Metrics, &str, RGBColor) = if i % 2 == 0 {
            (&report.before, "before", BEFORE)
        } else {
            (&report.after, "after", AFTER)
        };
        let Some(m) = metrics.axis(axis) else {
            continue;
        };
        let caption = format!("{axis} test, {label} (FS {:.1} N)", m.full_scale_n);
        draw_panel(panel, m.get(kind), &caption, color, text)?;
    }
    root.present().map_err(|e| e.to_string())
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn draw_panel(
    area: &Area<'_>,
    metric: &Metric,
    caption: &str,
    color: RGBColor,
    text: bool,
) -> Result<(), String> {
    let n = metric.per_weight.len().max(1);
    let top = metric
        .per_weight
        .iter()
        .flat_map(|w| w.values.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let y_max = if top > 0.0 { top * 1.15 } else { 0.01 };
    let x_range = -0.6f64..(n as f64 - 0.4);
    let mut builder = ChartBuilder::on(area);
    builder.margin(12);
    if text {
        builder
            .caption(caption, ("sans-serif", 20))
            .x_label_area_size(40)
            .y_label_area_size(60);
    }
    let mut chart = builder
        .build_cartesian_2d(x_range, 0f64..y_max)
        .map_err(msg)?;
    let weights: Vec<f64> = metric.per_weight.iter().map(|w| w.weight_kg).collect();
    if text {
        let label = |x: &f64| {
            let i = x.round();
            match weights.get(i as usize) {
                Some(w) if (x - i).abs() < 1e-6 && i >= 0.0 => format!("{w}"),
                _ => String::new(),
            }
        };
        chart
            .configure_mesh()
            .x_labels(n + 1)
            .x_label_formatter(&label)
            .disable_x_mesh()
            .y_labels(6)
            .y_label_formatter(&|v| format!("{v:.3}"))
            .x_desc("applied weight, kg")
            .y_desc("%FS")
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(msg)?;
    } else {
        // Frame and five grid lines, no labels.
        let grid = ShapeStyle::from(&BLACK.mix(0.15)).stroke_width(1);
        for k in 0..=5 {
            let y = y_max * k as f64 / 5.0;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(-0.6, y), (n as f64 - 0.4, y)],
                    grid,
                )))
                .map_err(msg)?;
        }
    }
    let line = ShapeStyle::from(&color).stroke_width(2);
    let fill = ShapeStyle::from(&color.mix(0.3)).filled();
    for (i, w) in metric.per_weight.iter().enumerate() {
        let mut v: Vec<f64> = w.values.iter().copied().filter(|v| v.is_finite()).collect();
        if v.is_empty() {
            continue;
        }
        v.sort_by(f64::total_cmp);
        let x = i as f64;
        let (lo, q1, med, q3, hi) = (
            v[0],
            quantile(&v, 0.25),
            quantile(&v, 0.5),
            quantile(&v, 0.75),
            v[v.len() - 1],
        );
        let hw = 0.3;
        chart
            .draw_series([
                Rectangle::new([(x - hw, q1), (x + hw, q3)], fill),
                Rectangle::new([(x - hw, q1), (x + hw, q3)], line),
            ])
            .map_err(msg)?;
        chart
            .draw_series([
                PathElement::new(vec![(x - hw, med), (x + hw, med)], line.stroke_width(3)),
                PathElement::new(vec![(x, q3), (x, hi)], line),
                PathElement::new(vec![(x, q1), (x, lo)], line),
                PathElement::new(vec![(x - hw / 2.0, hi), (x + hw / 2.0, hi)], line),
                PathElement::new(vec![(x - hw / 2.0, lo), (x + hw / 2.0, lo)], line),
            ])
            .map_err(msg)?;
    }
    Ok(())
}

fn msg<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}
