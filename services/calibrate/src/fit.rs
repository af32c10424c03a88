//! Fitting a [`CalibrationConfig`] to a recording (paper III.C), in the order the tension stage
//! applies it: cell gains, equilibrium, per-axis polynomials, crossload matrix.
//!
//! Everything is fitted on **step means** (the mean of all frames of one held load). Cell
//! forces and the equilibrium are linear, so a step mean of them is exact; the per-axis
//! polynomials are applied to the mean instead of per frame, which differs by `c2 var + 3 c3 T
//! var` (var = per-frame noise variance of T): below 1e-5 %FS here.
//!
//! # Cell gains
//!
//! The paper sets `gamma_j = f_j,calib / f_truth` with `f_truth/4` the ideal share of each cell
//! under a z load. That ratio cannot tell a cell's gain error from crossload: a z load whose
//! pull leaks 3 % into x really does load cell 1 more than cell 3, and a z-only ratio folds
//! that 3 % (times h/(2 d0) per cell) into the gains. We use all three axis tests instead:
//!
//! 1. Per cell j and axis a, the tangent slope `R[a][j]` at zero load of the cell's raw force
//!    against the applied force, by least squares over the steps of that axis with regressors
//!    `1, T, T^2` (the cell's own non-linearity, so the slope is not biased by it) and `+-1` for
//!    loading/unloading (hysteresis). "Held" steps (same weight as the step before: the sensor
//!    is still on the previous branch of its hysteresis loop) are left out.
//! 2. Whatever reaches the cells is a pull on the anchor, so the true cell forces always satisfy
//!    the symmetric split `f1 - f2 + f3 - f4 = 0` (the mode the equilibrium ignores; see
//!    `Geometry::cells_from_force`). Gain errors are the only thing that make the raw cells
//!    violate it: `sum_j s_j R[a][j] / gamma_j = 0` for a = x, y, z with `s = (1,-1,1,-1)`.
//!    Three equations in four unknowns `1/gamma_j`: one solution up to scale (SVD null space).
//! 3. The common scale is chosen so the gain-corrected cells read the z test with unit slope
//!    (`-sum_j R[z][j] / gamma_j = 1`); the per-axis polynomials absorb what is left.
//!
//! With a crossload-free sensor and linear cells this reduces to the paper's ratio (a slope
//! through the tared z steps).
//!
//! # Per-axis polynomials (measured -> true)
//!
//! On the main-axis steps of each test, the gain-corrected equilibrium force against the
//! applied force: z linear (`c0 + c1 T`, the paper's linear regression); x and y cubic (the
//! paper: "x/y axes needed higher-order regression"). By default the lateral cubic is **odd**
//! about the zero-load reading t0: `b0 + b1 (T - t0) + b3 (T - t0)^3`, expanded into
//! `c0..c3`. Only +x and +y are loaded on the bench, but in flight the cable also pulls -x and
//! -y; a full cubic fitted on one side extrapolates with the wrong curvature to the other (the
//! two halves of the cross are mirror images, so the true response is odd). `LateralPoly::Full`
//! fits all four coefficients for a sensor known to be asymmetric.
//!
//! # Crossload matrix
//!
//! `C` (3x3) by least squares, row by row, so that `C poly(T_measured) ~ T_true` over the
//! steps of all three tests.

use crate::lsq;
use crate::recording::{Axis, Direction, Recording, G};
use rt_config::{CalibrationConfig, CellConfig, Config};
use tension::{cells::VOLTS_PER_LSB, Calibration, CellConversion, Geometry};

/// Shape of the x and y polynomials.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LateralPoly {
    /// `b0 + b1 u + b3 u^3`, `u = T - t0`: safe to extrapolate to the unloaded side.
    #[default]
    Odd,
    /// `c0 + c1 T + c2 T^2 + c3 T^3`: best on the tested side only.
    Full,
}

/// Choices of the fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FitOptions {
    pub lateral_poly: LateralPoly,
}

/// Why a recording cannot be fitted.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("the recording has no {0}-axis steps; the fit needs tests on x, y and z")]
    MissingAxis(Axis),
    #[error("the {axis}-axis test has {have} distinct weights; {what} needs at least {need}")]
    TooFewWeights {
        axis: Axis,
        have: usize,
        need: usize,
        what: &'static str,
    },
    #[error("cannot fit {0}: the recorded loads do not determine it (rank deficient)")]
    Degenerate(&'static str),
    #[error("fitted {what} = {value} is implausible ({why}); check the recording")]
    OutOfRange {
        what: String,
        value: f64,
        why: &'static str,
    },
}

/// One held load reduced to its mean: the fit's and the metrics' unit of data.
#[derive(Debug, Clone, PartialEq)]
pub struct StepMean {
    pub axis: Axis,
    pub weight_kg: f64,
    pub cycle: u32,
    pub direction: Direction,
    /// Same axis and weight as the step recorded just before (a turning point).
    pub held: bool,
    /// Mean raw cell forces with the nominal conversion, N (negative = tension).
    pub raw_cells: [f64; 4],
}

impl StepMean {
    pub fn applied_force(&self) -> [f64; 3] {
        self.axis.force(self.weight_kg)
    }
}

/// Step means of a recording, nominal cell constants.
pub fn step_means(rec: &Recording, cell: &CellConfig) -> Vec<StepMean> {
    let conv = CellConversion::new(cell);
    let mut out: Vec<StepMean> = Vec::with_capacity(rec.steps.len());
    for s in &rec.steps {
        let n = s.codes.len().max(1) as f64;
        let mut raw = [0.0; 4];
        for (j, r) in raw.iter_mut().enumerate() {
            let sum: i64 = s.codes.iter().map(|c| c[j] as i64).sum();
            *r = conv.force_from_volts(sum as f64 / n * VOLTS_PER_LSB);
        }
        let held = out
            .last()
            .is_some_and(|p| p.axis == s.axis && p.weight_kg == s.weight_kg);
        out.push(StepMean {
            axis: s.axis,
            weight_kg: s.weight_kg,
            cycle: s.cycle,
            direction: s.direction,
            held,
            raw_cells: raw,
        });
    }
    out
}

/// Fits the calibration of the sensor recorded in `rec`, whose nominal constants and geometry
/// are in `cfg`.
pub fn fit(
    rec: &Recording,
    cfg: &Config,
    opts: &FitOptions,
) -> Result<CalibrationConfig, FitError> {
    let means = step_means(rec, &cfg.sensor.cell);
    for axis in Axis::ALL {
        if !means.iter().any(|m| m.axis == axis) {
            return Err(FitError::MissingAxis(axis));
        }
    }
    let cell_gain = fit_cell_gains(&means)?;
    let geometry = Geometry {
        d0_m: cfg.sensor.d0_m,
        h_m: cfg.sensor.h_m,
    };
    let gains_only = Calibration::new(Some(&CalibrationConfig {
        cell_gain,
        ..CalibrationConfig::identity()
    }));
    let t_eq: Vec<[f64; 3]> = means
        .iter()
        .map(|m| geometry.force_from_cells(&gains_only.correct_cells(&m.raw_cells)))
        .collect();

    let poly_z = fit_axis_poly(&means, &t_eq, Axis::Z, PolyShape::Linear)?;
    let lateral = match opts.lateral_poly {
        LateralPoly::Odd => PolyShape::OddCubic,
        LateralPoly::Full => PolyShape::Cubic,
    };
    let poly_x = fit_axis_poly(&means, &t_eq, Axis::X, lateral)?;
    let poly_y = fit_axis_poly(&means, &t_eq, Axis::Y, lateral)?;
    let polys = [poly_x, poly_y, poly_z];

    let p: Vec<Vec<f64>> = t_eq
        .iter()
        .map(|t| {
            (0..3)
                .map(|k| tension::calibration::poly3(&polys[k], t[k]))
                .collect()
        })
        .collect();
    let mut crossload = [[0.0; 3]; 3];
    for (r, row) in crossload.iter_mut().enumerate() {
        let target: Vec<f64> = means.iter().map(|m| m.applied_force()[r]).collect();
        let c = lsq::solve(&p, &target).ok_or(FitError::Degenerate("the crossload matrix"))?;
        row.copy_from_slice(&c);
    }
    for (r, row) in crossload.iter().enumerate() {
        if !(0.5..=2.0).contains(&row[r]) {
            return Err(FitError::OutOfRange {
                what: format!("crossload[{r}][{r}]"),
                value: row[r],
                why: "a diagonal term must lie in 0.5..=2",
            });
        }
    }
    Ok(CalibrationConfig {
        cell_gain,
        poly_x,
        poly_y,
        poly_z,
        crossload,
    })
}

/// Distinct weights of the given steps, sorted.
fn distinct_weights<'a>(steps: impl Iterator<Item = &'a StepMean>) -> Vec<f64> {
    let mut w: Vec<f64> = steps.map(|m| m.weight_kg).collect();
    w.sort_by(f64::total_cmp);
    w.dedup();
    w
}

/// Tangent slope at zero load of each cell's raw force against the force applied on `axis`
/// (see the module docs), `[cell]`.
pub fn cell_slopes(means: &[StepMean], axis: Axis) -> Result<[f64; 4], FitError> {
    let steps: Vec<&StepMean> = means.iter().filter(|m| m.axis == axis && !m.held).collect();
    let weights = distinct_weights(steps.iter().copied());
    if weights.len() < 2 {
        return Err(FitError::TooFewWeights {
            axis,
            have: weights.len(),
            need: 2,
            what: "the cell gains",
        });
    }
    let fs = weights[weights.len() - 1] * G;
    let quadratic = weights.len() >= 4;
    let both_directions = steps.iter().any(|m| m.direction == Direction::Up)
        && steps.iter().any(|m| m.direction == Direction::Down);
    let rows: Vec<Vec<f64>> = steps
        .iter()
        .map(|m| {
            let tau = m.weight_kg * G / fs;
            let mut r = vec![1.0, tau];
            if quadratic {
                r.push(tau * tau);
            }
            if both_directions {
                r.push(if m.direction == Direction::Up {
                    1.0
                } else {
                    -1.0
                });
            }
            r
        })
        .collect();
    let mut out = [0.0; 4];
    for (j, slope) in out.iter_mut().enumerate() {
        let b: Vec<f64> = steps.iter().map(|m| m.raw_cells[j]).collect();
        let c = lsq::solve(&rows, &b).ok_or(FitError::Degenerate("the per-cell slopes"))?;
        *slope = c[1] / fs;
    }
    Ok(out)
}

/// The per-cell gains gamma_j (module docs, "Cell gains").
pub fn fit_cell_gains(means: &[StepMean]) -> Result<[f64; 4], FitError> {
    const TWIST: [f64; 4] = [1.0, -1.0, 1.0, -1.0];
    let r = [
        cell_slopes(means, Axis::X)?,
        cell_slopes(means, Axis::Y)?,
        cell_slopes(means, Axis::Z)?,
    ];
    let a: [[f64; 4]; 3] = std::array::from_fn(|k| std::array::from_fn(|j| TWIST[j] * r[k][j]));
    let (w, conditioning) = lsq::null_vector_3x4(&a);
    if !(conditioning.is_finite() && conditioning > 1e-4) {
        return Err(FitError::Degenerate("the cell gains"));
    }
    let c: f64 = -(0..4).map(|j| r[2][j] * w[j]).sum::<f64>();
    let gains: [f64; 4] = std::array::from_fn(|j| c / w[j]);
    for (j, g) in gains.iter().enumerate() {
        if !(g.is_finite() && (0.5..=2.0).contains(g)) {
            return Err(FitError::OutOfRange {
                what: format!("cell_gain[{j}]"),
                value: *g,
                why: "a cell gain must lie in 0.5..=2",
            });
        }
    }
    Ok(gains)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PolyShape {
    Linear,
    OddCubic,
    Cubic,
}

/// Fits `T_true = poly(T_eq[axis])` on the main-axis steps of `axis`, as `[c0, c1, c2, c3]`.
fn fit_axis_poly(
    means: &[StepMean],
    t_eq: &[[f64; 3]],
    axis: Axis,
    shape: PolyShape,
) -> Result<[f64; 4], FitError> {
    let k = axis.index();
    let pairs: Vec<(f64, f64)> = means
        .iter()
        .zip(t_eq)
        .filter(|(m, _)| m.axis == axis)
        .map(|(m, t)| (t[k], m.weight_kg * G))
        .collect();
    let weights = distinct_weights(means.iter().filter(|m| m.axis == axis));
    let need = match shape {
        PolyShape::Linear => 2,
        PolyShape::OddCubic => 3,
        PolyShape::Cubic => 4,
    };
    if weights.len() < need {
        return Err(FitError::TooFewWeights {
            axis,
            have: weights.len(),
            need,
            what: "the axis polynomial",
        });
    }
    let fs = weights[weights.len() - 1] * G;
    let y: Vec<f64> = pairs.iter().map(|p| p.1).collect();
    let degenerate = FitError::Degenerate("an axis polynomial");
    let rows = |f: &dyn Fn(f64) -> Vec<f64>| pairs.iter().map(|p| f(p.0)).collect::<Vec<_>>();
    let c = match shape {
        PolyShape::Linear => {
            let b = lsq::solve(&rows(&|x| vec![1.0, x / fs]), &y).ok_or(degenerate)?;
            [b[0], b[1] / fs, 0.0, 0.0]
        }
        PolyShape::Cubic => {
            let b = lsq::solve(&rows(&|x| (0..4).map(|e| (x / fs).powi(e)).collect()), &y)
                .ok_or(degenerate)?;
            [b[0], b[1] / fs, b[2] / fs.powi(2), b[3] / fs.powi(3)]
        }
        PolyShape::OddCubic => {
            // The zero-load reading: where the straight-line fit crosses T_true = 0.
            let line = lsq::solve(&rows(&|x| vec![1.0, x / fs]), &y)
                .ok_or(FitError::Degenerate("an axis polynomial"))?;
            let t0 = -line[0] / (line[1] / fs);
            let b = lsq::solve(
                &rows(&|x| {
                    let u = (x - t0) / fs;
                    vec![1.0, u, u * u * u]
                }),
                &y,
            )
            .ok_or(FitError::Degenerate("an axis polynomial"))?;
            let (b1, b3) = (b[1] / fs, b[2] / fs.powi(3));
            [
                b[0] - b1 * t0 - b3 * t0.powi(3),
                b1 + 3.0 * b3 * t0 * t0,
                -3.0 * b3 * t0,
                b3,
            ]
        }
    };
    if !c.iter().all(|v| v.is_finite()) || !(0.5..=2.0).contains(&c[1]) {
        return Err(FitError::OutOfRange {
            what: format!("poly_{axis}[1]"),
            value: c[1],
            why: "the linear term must lie in 0.5..=2",
        });
    }
    Ok(c)
}
