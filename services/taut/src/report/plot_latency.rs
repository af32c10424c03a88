//! The latency percentile distribution of every span of one drone, one panel per span, as
//! HdrHistogram plots it: x the percentile on a log scale of 1/(1 − p) (0 %, 90 %, 99 %,
//! 99.9 % ... equally spaced), y the latency in ms.

use plotters::prelude::*;
use std::path::Path;

use super::latency::SpanLatency;
use super::plot::{msg, WIDTH};

/// Panels per row.
const COLUMNS: usize = 2;
/// Pixel height of one row of panels.
pub const ROW_HEIGHT: u32 = 340;
const TITLE_HEIGHT: u32 = 60;

/// Height of the figure of `spans` panels.
pub fn latency_figure_height(spans: usize) -> u32 {
    TITLE_HEIGHT + ROW_HEIGHT * spans.div_ceil(COLUMNS) as u32
}

/// `1/(1 − p)` as a percentile label: 1 -> "0%", 10 -> "90%", 1000 -> "99.9%".
pub fn percentile_label(x: f64) -> String {
    if x <= 1.0 {
        return "0%".into();
    }
    let p = 100.0 * (1.0 - 1.0 / x);
    let digits = (x.log10().ceil() as i64 - 2).clamp(0, 6) as usize;
    format!("{p:.digits$}%")
}

/// Draws every span of `spans` (one drone) into `path`.
pub fn draw_latency_figure(
    path: &Path,
    title: &str,
    spans: &[SpanLatency],
    text: bool,
) -> Result<(), String> {
    let size = (WIDTH, latency_figure_height(spans.len()));
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(msg)?;
    let (head, body) = root.split_vertically(TITLE_HEIGHT);
    if text {
        head.titled(title, ("sans-serif", 28)).map_err(msg)?;
    }
    let rows = spans.len().div_ceil(COLUMNS).max(1);
    for (area, span) in body.split_evenly((rows, COLUMNS)).iter().zip(spans) {
        draw_span(area, span, text)?;
    }
    root.present().map_err(msg)
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn draw_span(area: &Area<'_>, span: &SpanLatency, text: bool) -> Result<(), String> {
    let curve = span.curve();
    let x_hi = curve.last().map_or(10.0, |p| p.0).max(10.0);
    let y_hi = curve.iter().map(|p| p.1).fold(0.0f64, f64::max).max(1e-3) * 1.1;
    let mut builder = ChartBuilder::on(area);
    builder.margin(10).margin_right(24);
    if text {
        let caption = if span.count() == 0 {
            format!("{} (no samples)", span.span)
        } else {
            format!(
                "{} (n = {}, p50 {:.3} ms)",
                span.span,
                span.count(),
                span.quantile_ms(0.5)
            )
        };
        builder
            .caption(caption, ("sans-serif", 19))
            .x_label_area_size(42)
            .y_label_area_size(80);
    }
    let mut chart = builder
        .build_cartesian_2d((1f64..x_hi).log_scale(), 0f64..y_hi)
        .map_err(msg)?;
    let mut mesh = chart.configure_mesh();
    mesh.light_line_style(WHITE.mix(0.0));
    if text {
        mesh.x_label_formatter(&|x| percentile_label(*x))
            .x_desc("percentile (log scale of 1/(1 − p))")
            .y_desc("latency, ms")
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 15));
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.draw().map_err(msg)?;
    if curve.is_empty() {
        return Ok(());
    }
    let c = RGBColor(31, 119, 180);
    chart
        .draw_series(LineSeries::new(curve, c.stroke_width(2)))
        .map_err(msg)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_labels_of_the_log_axis() {
        assert_eq!(percentile_label(1.0), "0%");
        assert_eq!(percentile_label(2.0), "50%");
        assert_eq!(percentile_label(10.0), "90%");
        assert_eq!(percentile_label(100.0), "99%");
        assert_eq!(percentile_label(1000.0), "99.9%");
        assert_eq!(percentile_label(10000.0), "99.99%");
    }
}
