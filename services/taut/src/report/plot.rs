//! PNG time plots: stacked panels sharing one time axis, mission phases shaded behind the
//! lines, one colour per source. Text needs a TrueType font (see `calibrate::plots`); without
//! one the plots are drawn without any text.

use plotters::prelude::*;
use shared_types::MissionPhase;
use std::path::Path;

use super::series::{PhaseSpan, Series, Source};

/// Pixel width of every figure.
pub const WIDTH: u32 = 1600;
/// Pixel height of one time panel.
pub const PANEL_HEIGHT: u32 = 320;
/// Pixel height of the figure title band.
pub const TITLE_HEIGHT: u32 = 60;
/// Points drawn per line at most (min and max per bucket keep spikes visible).
const MAX_BUCKETS: usize = 2000;

/// One panel: a caption, the y axis label with its unit, the lines.
#[derive(Debug, Clone)]
pub struct Panel {
    pub caption: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// Height of a figure of `panels` time panels.
pub fn figure_height(panels: usize) -> u32 {
    TITLE_HEIGHT + PANEL_HEIGHT * panels as u32
}

pub fn color(source: Source) -> RGBColor {
    match source {
        Source::Estimate | Source::Sensor => RGBColor(31, 119, 180),
        Source::Truth => RGBColor(0, 0, 0),
        Source::Nominal | Source::Desired => RGBColor(44, 160, 44),
        Source::Shifted => RGBColor(148, 103, 189),
        Source::Estimator => RGBColor(255, 127, 14),
    }
}

fn phase_color(p: MissionPhase) -> RGBColor {
    match p {
        MissionPhase::Idle | MissionPhase::Done => RGBColor(150, 150, 150),
        MissionPhase::Takeoff => RGBColor(90, 160, 230),
        MissionPhase::Move => RGBColor(250, 170, 60),
        MissionPhase::Hold => RGBColor(100, 200, 100),
        MissionPhase::Land => RGBColor(180, 120, 220),
    }
}

pub fn msg<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// At most `2 * buckets` points: per equal-time bucket its minimum and maximum, in time order.
pub fn decimate(points: &[(f64, f64)], buckets: usize) -> Vec<(f64, f64)> {
    if points.len() <= 2 * buckets || buckets == 0 {
        return points.to_vec();
    }
    let (t_lo, t_hi) = (points[0].0, points[points.len() - 1].0);
    let width = ((t_hi - t_lo) / buckets as f64).max(f64::MIN_POSITIVE);
    let mut out = Vec::with_capacity(2 * buckets + 2);
    let mut i = 0;
    while i < points.len() {
        let bucket = |t: f64| (((t - t_lo) / width).floor() as usize).min(buckets - 1);
        let b = bucket(points[i].0);
        let mut j = i;
        let (mut lo, mut hi) = (i, i);
        while j < points.len() && bucket(points[j].0) == b {
            if points[j].1 < points[lo].1 {
                lo = j;
            }
            if points[j].1 > points[hi].1 {
                hi = j;
            }
            j += 1;
        }
        let (a, c) = (lo.min(hi), lo.max(hi));
        out.push(points[a]);
        if c != a {
            out.push(points[c]);
        }
        i = j.max(i + 1);
    }
    out
}

/// The y range of the lines, padded; a flat or empty one is widened to be visible.
pub fn y_range(series: &[Series]) -> (f64, f64) {
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span < 1e-6 {
        let pad = (lo.abs() * 0.1).max(0.5);
        return (lo - pad, hi + pad);
    }
    (lo - 0.06 * span, hi + 0.06 * span)
}

/// Draws `panels` stacked over a shared time axis `0..t_end_s`, phases shaded, into `path`.
pub fn draw_time_figure(
    path: &Path,
    title: &str,
    panels: &[Panel],
    phases: &[PhaseSpan],
    t_end_s: f64,
    text: bool,
) -> Result<(), String> {
    let column = Column {
        panels,
        phases,
        t_end_s,
    };
    draw_time_grid(path, title, &[column], text)
}

/// One column of a grid figure: its stacked panels, their phases and time axis.
pub struct Column<'a> {
    pub panels: &'a [Panel],
    pub phases: &'a [PhaseSpan],
    pub t_end_s: f64,
}

/// Draws `columns` side by side (each as [`draw_time_figure`] draws one) into `path`,
/// [`WIDTH`] per column.
pub fn draw_time_grid(
    path: &Path,
    title: &str,
    columns: &[Column],
    text: bool,
) -> Result<(), String> {
    let rows = columns.iter().map(|c| c.panels.len()).max().unwrap_or(0);
    let size = (WIDTH * columns.len().max(1) as u32, figure_height(rows));
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(msg)?;
    let (head, body) = root.split_vertically(TITLE_HEIGHT);
    if text {
        head.titled(title, ("sans-serif", 28)).map_err(msg)?;
    }
    for (area, column) in body
        .split_evenly((1, columns.len().max(1)))
        .iter()
        .zip(columns)
    {
        let x_hi = if column.t_end_s > 0.0 {
            column.t_end_s
        } else {
            1.0
        };
        for (i, (cell, panel)) in area
            .split_evenly((rows.max(1), 1))
            .iter()
            .zip(column.panels)
            .enumerate()
        {
            draw_panel(cell, panel, column.phases, x_hi, text, i == 0)?;
        }
    }
    root.present().map_err(msg)
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn draw_panel(
    area: &Area<'_>,
    panel: &Panel,
    phases: &[PhaseSpan],
    x_hi: f64,
    text: bool,
    name_phases: bool,
) -> Result<(), String> {
    let (y_lo, y_hi) = y_range(&panel.series);
    let mut builder = ChartBuilder::on(area);
    builder.margin(8).margin_right(20);
    if text {
        let caption = if panel.series.is_empty() {
            format!("{} (no data)", panel.caption)
        } else {
            panel.caption.clone()
        };
        builder
            .caption(caption, ("sans-serif", 20))
            .x_label_area_size(42)
            .y_label_area_size(80);
    }
    let mut chart = builder
        .build_cartesian_2d(0f64..x_hi, y_lo..y_hi)
        .map_err(msg)?;
    let mut mesh = chart.configure_mesh();
    mesh.light_line_style(WHITE.mix(0.0));
    if text {
        mesh.x_desc("time since the first sample, s")
            .y_desc(panel.y_label.as_str())
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16));
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.draw().map_err(msg)?;
    for p in phases {
        let (a, b) = (p.from_s.max(0.0), p.to_s.min(x_hi));
        if b <= a {
            continue;
        }
        let fill = phase_color(p.phase).mix(0.13).filled();
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(a, y_lo), (b, y_hi)],
                fill,
            )))
            .map_err(msg)?;
        if text && name_phases && b - a > x_hi * 0.02 {
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{:?}", p.phase),
                    (a + x_hi * 0.004, y_hi),
                    ("sans-serif", 14)
                        .into_font()
                        .color(&phase_color(p.phase).mix(0.9)),
                )))
                .map_err(msg)?;
        }
    }
    for s in &panel.series {
        let c = color(s.source);
        let drawn = chart
            .draw_series(LineSeries::new(
                decimate(&s.points, MAX_BUCKETS),
                ShapeStyle::from(&c).stroke_width(2),
            ))
            .map_err(msg)?;
        if text {
            drawn.label(s.label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
            });
        }
    }
    if text && !panel.series.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(msg)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_each_buckets_extremes() {
        let pts: Vec<(f64, f64)> = (0..10_000)
            .map(|i| {
                (
                    i as f64 * 1e-3,
                    if i == 4321 { 50.0 } else { (i % 7) as f64 },
                )
            })
            .collect();
        let d = decimate(&pts, 100);
        assert!(d.len() <= 200, "{}", d.len());
        assert!(d.contains(&(4.321, 50.0)), "the spike survives");
        assert!(d.windows(2).all(|w| w[0].0 <= w[1].0), "in time order");
        assert_eq!(
            decimate(&pts[..150], 100).len(),
            150,
            "short lines untouched"
        );
    }

    #[test]
    fn y_range_pads_and_widens_flat_lines() {
        let s = |pts: Vec<(f64, f64)>| Series {
            source: Source::Truth,
            label: String::new(),
            points: pts,
        };
        let (lo, hi) = y_range(&[s(vec![(0.0, 0.0), (1.0, 10.0)])]);
        assert!(
            (lo + 0.6).abs() < 1e-9 && (hi - 10.6).abs() < 1e-9,
            "{lo} {hi}"
        );
        let (lo, hi) = y_range(&[s(vec![(0.0, 2.0), (1.0, 2.0)])]);
        assert!(lo < 2.0 && hi > 2.0);
        assert_eq!(y_range(&[]), (-1.0, 1.0));
    }
}
