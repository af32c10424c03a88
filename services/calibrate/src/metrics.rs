//! Performance indexes of a recording read through the tension stage, in %FS, per applied
//! weight (the data of the paper's Fig. 5 box plots).
//!
//! FS of an axis is the heaviest weight of that axis's test times g (5.5 kg on z; the lateral
//! full scale on x and y, see [`crate::synthetic`]). Every metric is computed from step means
//! of the stage's output (`force_sensor_n`), the main-axis output being the loaded axis's:
//!
//! - **hysteresis**: per cycle, |loading - unloading| at the same weight;
//! - **non-linearity** (independent, best-fit line): per cycle, the mean of the loading and
//!   unloading outputs at each weight, a least-squares straight line through them over all
//!   weights, and the deviation from it at each weight. Note that any linear correction leaves
//!   this number unchanged (it only rescales by c1), so only the cubic x/y regression lowers it;
//! - **repeatability**: per weight and direction, max - min over cycles;
//! - **crossload**: per cycle and direction, |output| on each unloaded axis, in %FS of the
//!   *loaded* axis (spurious output per full-scale load);
//! - **error** (not in the paper, but what a controller feels): per cycle and direction,
//!   |output - applied| on the loaded axis.

use crate::recording::{Axis, Direction, Recording, G};
use rt_config::{CalibrationConfig, Config};
use serde::Serialize;
use shared_types::{tension_flags, Header, RawAdcFrame};
use std::collections::BTreeMap;
use tension::{Calibration, TensionStage, TensionStageConfig};

/// The stage's mean output over one step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutput {
    pub axis: Axis,
    pub weight_kg: f64,
    pub cycle: u32,
    pub direction: Direction,
    /// Mean `force_sensor_n`, N.
    pub force_n: [f64; 3],
}

/// Runs every frame through a `TensionStage` built from `cfg` with calibration `cal` (None:
/// nominal constants, "before") and a filter window of 1 (static data: averaging happens per
/// step here), and returns the step means and the number of saturated frames.
pub fn step_outputs(
    rec: &Recording,
    cfg: &Config,
    cal: Option<&CalibrationConfig>,
) -> (Vec<StepOutput>, usize) {
    let mut stage_cfg = TensionStageConfig::from_config(cfg);
    stage_cfg.calibration = Calibration::new(cal);
    stage_cfg.window = 1;
    let mut stage = TensionStage::new(stage_cfg);
    let mut sequence = 0u64;
    let mut saturated = 0;
    let outputs = rec
        .steps
        .iter()
        .map(|s| {
            let mut sum = [0.0; 3];
            for codes in &s.codes {
                let frame = RawAdcFrame {
                    header: Header {
                        sequence,
                        ..Header::default()
                    },
                    codes: *codes,
                    ..RawAdcFrame::default()
                };
                sequence += 1;
                let out = stage.process(&frame);
                if out.flags & tension_flags::SATURATED != 0 {
                    saturated += 1;
                }
                for (acc, f) in sum.iter_mut().zip(out.force_sensor_n) {
                    *acc += f;
                }
            }
            let n = s.codes.len().max(1) as f64;
            StepOutput {
                axis: s.axis,
                weight_kg: s.weight_kg,
                cycle: s.cycle,
                direction: s.direction,
                force_n: sum.map(|v| v / n),
            }
        })
        .collect();
    (outputs, saturated)
}

/// Which performance index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetricKind {
    Hysteresis,
    NonLinearity,
    Repeatability,
    Crossload,
    Error,
}

impl MetricKind {
    pub const ALL: [MetricKind; 5] = [
        MetricKind::Hysteresis,
        MetricKind::NonLinearity,
        MetricKind::Repeatability,
        MetricKind::Crossload,
        MetricKind::Error,
    ];

    pub fn title(self) -> &'static str {
        match self {
            MetricKind::Hysteresis => "Hysteresis",
            MetricKind::NonLinearity => "Non-linearity",
            MetricKind::Repeatability => "Repeatability",
            MetricKind::Crossload => "Crossload",
            MetricKind::Error => "Error vs reference",
        }
    }
}

/// The values of one metric at one applied weight (one box of a box plot), %FS.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WeightValues {
    pub weight_kg: f64,
    pub values: Vec<f64>,
}

/// One metric of one axis test: summary and per-weight values, %FS. NaN (null in JSON) when
/// the recording has no data for it (e.g. a single cycle has no repeatability).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metric {
    pub max: f64,
    pub median: f64,
    pub per_weight: Vec<WeightValues>,
}

impl Metric {
    fn new(per_weight: Vec<WeightValues>) -> Self {
        let mut all: Vec<f64> = per_weight.iter().flat_map(|w| w.values.clone()).collect();
        all.sort_by(f64::total_cmp);
        Self {
            max: all.last().copied().unwrap_or(f64::NAN),
            median: quantile(&all, 0.5),
            per_weight,
        }
    }
}

/// Linear-interpolated quantile of sorted values (NaN if empty).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// All metrics of one axis test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisMetrics {
    pub axis: Axis,
    pub full_scale_n: f64,
    pub hysteresis: Metric,
    pub nonlinearity: Metric,
    pub repeatability: Metric,
    pub crossload: Metric,
    pub error: Metric,
}

impl AxisMetrics {
    pub fn get(&self, kind: MetricKind) -> &Metric {
        match kind {
            MetricKind::Hysteresis => &self.hysteresis,
            MetricKind::NonLinearity => &self.nonlinearity,
            MetricKind::Repeatability => &self.repeatability,
            MetricKind::Crossload => &self.crossload,
            MetricKind::Error => &self.error,
        }
    }
}

/// Metrics of every axis test present, in x, y, z order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metrics {
    pub axes: Vec<AxisMetrics>,
    /// Frames with a code at a rail: the metrics of their steps are clipped.
    pub saturated_frames: usize,
}

impl Metrics {
    pub fn axis(&self, axis: Axis) -> Option<&AxisMetrics> {
        self.axes.iter().find(|m| m.axis == axis)
    }
}

/// Weight in micrograms: an exact key for "the same weight".
fn wkey(kg: f64) -> i64 {
    (kg * 1e9).round() as i64
}

/// Computes the metrics from step outputs.
pub fn compute(outputs: &[StepOutput], saturated_frames: usize) -> Metrics {
    let axes = Axis::ALL
        .iter()
        .filter_map(|&a| axis_metrics(outputs, a))
        .collect();
    Metrics {
        axes,
        saturated_frames,
    }
}

fn axis_metrics(outputs: &[StepOutput], axis: Axis) -> Option<AxisMetrics> {
    let a = axis.index();
    // (weight, cycle, direction) -> mean output; repeated steps are averaged.
    let mut acc: BTreeMap<(i64, u32, Direction), ([f64; 3], usize)> = BTreeMap::new();
    for o in outputs.iter().filter(|o| o.axis == axis) {
        let e = acc
            .entry((wkey(o.weight_kg), o.cycle, o.direction))
            .or_insert(([0.0; 3], 0));
        for k in 0..3 {
            e.0[k] += o.force_n[k];
        }
        e.1 += 1;
    }
    let cell: BTreeMap<(i64, u32, Direction), [f64; 3]> = acc
        .into_iter()
        .map(|(k, (s, n))| (k, s.map(|v| v / n as f64)))
        .collect();
    let mut weights: Vec<i64> = cell.keys().map(|k| k.0).collect();
    weights.dedup();
    let fs = *weights.last()? as f64 * 1e-9 * G;
    if fs <= 0.0 {
        return None;
    }
    let pct = |v: f64| 100.0 * v / fs;
    let mut cycles: Vec<u32> = cell.keys().map(|k| k.1).collect();
    cycles.sort_unstable();
    cycles.dedup();
    let get = |w: i64, c: u32, d: Direction| cell.get(&(w, c, d));
    let newton = |w: i64| w as f64 * 1e-9 * G;

    // Per cycle: mean of both branches at each weight, and its best-fit line.
    let mut nl_dev: BTreeMap<(i64, u32), f64> = BTreeMap::new();
    for &c in &cycles {
        let pts: Vec<(f64, f64, i64)> = weights
            .iter()
            .filter_map(|&w| {
                let vals: Vec<f64> = [Direction::Up, Direction::Down]
                    .iter()
                    .filter_map(|&d| get(w, c, d).map(|o| o[a]))
                    .collect();
                (!vals.is_empty())
                    .then(|| (newton(w), vals.iter().sum::<f64>() / vals.len() as f64, w))
            })
            .collect();
        if let Some((k0, k1)) = line_fit(&pts) {
            for (x, y, w) in pts {
                nl_dev.insert((w, c), pct((y - (k0 + k1 * x)).abs()));
            }
        }
    }

    let mut hyst = Vec::new();
    let mut nonlin = Vec::new();
    let mut repeat = Vec::new();
    let mut cross = Vec::new();
    let mut error = Vec::new();
    for &w in &weights {
        let weight_kg = w as f64 * 1e-9;
        let (mut h, mut nl, mut r, mut x, mut e) = (vec![], vec![], vec![], vec![], vec![]);
        for &c in &cycles {
            if let (Some(up), Some(down)) = (get(w, c, Direction::Up), get(w, c, Direction::Down)) {
                h.push(pct((up[a] - down[a]).abs()));
            }
            if let Some(v) = nl_dev.get(&(w, c)) {
                nl.push(*v);
            }
            for d in [Direction::Up, Direction::Down] {
                if let Some(o) = get(w, c, d) {
                    e.push(pct((o[a] - newton(w)).abs()));
                    for b in (0..3).filter(|&b| b != a) {
                        x.push(pct(o[b].abs()));
                    }
                }
            }
        }
        for d in [Direction::Up, Direction::Down] {
            let vals: Vec<f64> = cycles
                .iter()
                .filter_map(|&c| get(w, c, d))
                .map(|o| o[a])
                .collect();
            if vals.len() >= 2 {
                let max = vals.iter().copied().fold(f64::MIN, f64::max);
                let min = vals.iter().copied().fold(f64::MAX, f64::min);
                r.push(pct(max - min));
            }
        }
        for (list, values) in [
            (&mut hyst, h),
            (&mut nonlin, nl),
            (&mut repeat, r),
            (&mut cross, x),
            (&mut error, e),
        ] {
            list.push(WeightValues { weight_kg, values });
        }
    }
    Some(AxisMetrics {
        axis,
        full_scale_n: fs,
        hysteresis: Metric::new(hyst),
        nonlinearity: Metric::new(nonlin),
        repeatability: Metric::new(repeat),
        crossload: Metric::new(cross),
        error: Metric::new(error),
    })
}

/// Least-squares line y = k0 + k1 x through (x, y, _); None with fewer than 2 distinct x.
fn line_fit(pts: &[(f64, f64, i64)]) -> Option<(f64, f64)> {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let k1 = sxy / sxx;
    Some((my - k1 * mx, k1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn out(axis: Axis, w: f64, c: u32, d: Direction, f: [f64; 3]) -> StepOutput {
        StepOutput {
            axis,
            weight_kg: w,
            cycle: c,
            direction: d,
            force_n: f,
        }
    }

    #[test]
    fn metrics_by_hand() {
        // z test, FS = 2 kg: outputs in N chosen so each metric is easy to check.
        let g = G;
        let mut o = vec![];
        for c in 0..2 {
            let rep = 0.01 * c as f64 * 2.0 * g; // cycle 1 reads +1 %FS everywhere
            for (w, bend) in [(0.0, 0.0), (1.0, 0.02 * 2.0 * g), (2.0, 0.0)] {
                let base = w * g + bend + rep;
                o.push(out(
                    Axis::Z,
                    w,
                    c,
                    Direction::Up,
                    [0.0, 0.0, base - 0.01 * g],
                ));
                o.push(out(
                    Axis::Z,
                    w,
                    c,
                    Direction::Down,
                    [0.03 * 2.0 * g, 0.0, base + 0.01 * g],
                ));
            }
        }
        let m = compute(&o, 0);
        let z = m.axis(Axis::Z).unwrap();
        assert!((z.full_scale_n - 2.0 * g).abs() < 1e-12);
        // |up - down| = 0.02 g = 1 %FS.
        assert!((z.hysteresis.max - 1.0).abs() < 1e-9 && (z.hysteresis.median - 1.0).abs() < 1e-9);
        // A 2 %FS bump in the middle of three points: the line sits 2/3 of it below the bump.
        assert!(
            (z.nonlinearity.max - 4.0 / 3.0).abs() < 1e-9,
            "{}",
            z.nonlinearity.max
        );
        assert!((z.repeatability.max - 1.0).abs() < 1e-9);
        // Crossload: x reads 3 %FS while unloading; y reads 0.
        assert!((z.crossload.max - 3.0).abs() < 1e-9 && z.crossload.median == 0.0);
        assert!((z.error.max - 3.5).abs() < 1e-9, "{}", z.error.max);
        assert!(m.axis(Axis::X).is_none());
    }

    #[test]
    fn quantiles() {
        assert_eq!(quantile(&[1.0, 2.0, 3.0, 4.0], 0.5), 2.5);
        assert_eq!(quantile(&[1.0, 2.0, 3.0, 4.0, 5.0], 0.25), 2.0);
        assert!(quantile(&[], 0.5).is_nan());
    }
}
