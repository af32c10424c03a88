//! Acceptance tests of the calibration on the emulated sensor. They use 200 samples per step
//! (the paper: 3000) to keep the debug test run short; the statistics of step means are still
//! far finer than the tolerances (noise 0.6 LSB / sqrt(200) per cell).

use calibrate::metrics::MetricKind;
use calibrate::synthetic::{self, Synthetic, SyntheticOptions};
use calibrate::{fit, write_config_with_calibration, Axis, FitOptions, LateralPoly, Report};
use rt_config::{CalibrationConfig, Config};
use shared_types::{Header, RawAdcFrame};
use std::sync::OnceLock;
use tension::{TensionStage, TensionStageConfig};

const SAMPLES: usize = 200;

fn options(seed: u64) -> SyntheticOptions {
    SyntheticOptions {
        seed,
        samples_per_step: SAMPLES,
        ..SyntheticOptions::default()
    }
}

/// The seed-1 bench session, its fitted calibration and report (computed once).
fn calibrated() -> &'static (Synthetic, CalibrationConfig, Report) {
    static CELL: OnceLock<(Synthetic, CalibrationConfig, Report)> = OnceLock::new();
    CELL.get_or_init(|| {
        let cfg = Config::embedded_sim();
        let syn = synthetic::generate(&cfg, &options(1)).expect("synthetic bench");
        let cal = fit(&syn.recording, &cfg, &FitOptions::default()).expect("fit");
        let report = Report::build(&syn.recording, &cfg, &cal, "seed 1".into());
        (syn, cal, report)
    })
}

fn worst(report: &Report, after: bool, kind: MetricKind) -> f64 {
    let m = if after { &report.after } else { &report.before };
    m.axes
        .iter()
        .map(|a| a.get(kind).max)
        .fold(f64::MIN, f64::max)
}

#[test]
fn injected_cell_gains_are_recovered_within_0_2_percent() {
    let (syn, cal, _) = calibrated();
    for j in 0..4 {
        let injected = syn.params.gain_error[j];
        let rel = (cal.cell_gain[j] / injected - 1.0).abs();
        println!(
            "cell {}: gamma {:.5} injected {injected} ({:.3} %)",
            j + 1,
            cal.cell_gain[j],
            100.0 * rel
        );
        assert!(
            rel < 0.002,
            "cell {}: gamma {} vs injected {injected}",
            j + 1,
            cal.cell_gain[j]
        );
    }
}

#[test]
fn crossload_drops_from_about_3_8_to_at_most_0_6_percent_fs() {
    let (_, _, report) = calibrated();
    let before = worst(report, false, MetricKind::Crossload);
    let after = worst(report, true, MetricKind::Crossload);
    println!("crossload before {before:.3} %FS, after {after:.3} %FS");
    assert!((3.0..=5.0).contains(&before), "before {before}");
    assert!(after <= 0.6, "after {after}");
}

#[test]
fn nonlinearity_about_1_percent_before_and_at_most_0_5_after() {
    let (_, _, report) = calibrated();
    for axis in Axis::ALL {
        let b = report.before.axis(axis).unwrap().nonlinearity.max;
        let a = report.after.axis(axis).unwrap().nonlinearity.max;
        println!("non-linearity {axis}: before {b:.3} %FS, after {a:.3} %FS");
        assert!(a <= 0.5, "{axis}: after {a}");
    }
    let before = worst(report, false, MetricKind::NonLinearity);
    assert!((0.7..=1.5).contains(&before), "before {before}");
}

/// Mean stage output per step of a recording, through the stage built from `cfg` as-is
/// (window 4: the first 3 frames of each step still hold the previous load and are skipped).
fn read_through_stage(syn: &Synthetic, cfg: &Config) -> Vec<([f64; 3], [f64; 3])> {
    let mut stage = TensionStage::new(TensionStageConfig::from_config(cfg));
    let skip = cfg.filter.window - 1;
    let mut seq = 0;
    let mut out = vec![];
    for step in &syn.recording.steps {
        let mut sum = [0.0; 3];
        for (i, codes) in step.codes.iter().enumerate() {
            let frame = RawAdcFrame {
                header: Header {
                    sequence: seq,
                    ..Header::default()
                },
                codes: *codes,
                ..RawAdcFrame::default()
            };
            seq += 1;
            let t = stage.process(&frame);
            if i >= skip {
                (0..3).for_each(|k| sum[k] += t.force_sensor_n[k]);
            }
        }
        let n = (step.codes.len() - skip) as f64;
        out.push((sum.map(|v| v / n), step.applied_force()));
    }
    out
}

/// Worst |output - applied| per output axis, %FS of that axis.
fn worst_error(cal: Option<&CalibrationConfig>) -> [f64; 3] {
    let base = Config::embedded_sim();
    let cfg = match cal {
        Some(cal) => Config::from_toml_str(&write_config_with_calibration(&base, cal), "written")
            .expect("the written config loads"),
        None => base.clone(),
    };
    // A fresh bench session with another seed: reference loads the fit has not seen.
    let fresh = synthetic::generate(&base, &options(7)).unwrap();
    let g = calibrate::recording::G;
    let fs = [
        fresh.lateral_max_weight_kg * g,
        fresh.lateral_max_weight_kg * g,
        5.5 * g,
    ];
    let mut worst = [0.0f64; 3];
    for (out, applied) in read_through_stage(&fresh, &cfg) {
        for k in 0..3 {
            worst[k] = worst[k].max(100.0 * (out[k] - applied[k]).abs() / fs[k]);
        }
    }
    worst
}

#[test]
fn written_calibration_reads_fresh_reference_loads_within_0_5_percent_fs() {
    let (_, cal, _) = calibrated();
    let worst = worst_error(Some(cal));
    println!("worst error after, x y z: {worst:.3?} %FS");
    assert!(worst.iter().all(|&e| e <= 0.5), "{worst:?}");
}

#[test]
fn the_embedded_identity_calibration_fails_the_same_check() {
    // The control: the same check on the uncalibrated sensor must fail, or it tests nothing.
    let worst = worst_error(None);
    println!("worst error with the embedded identity calibration: {worst:.3?} %FS");
    assert!(worst.iter().any(|&e| e > 2.0), "{worst:?}");
}

#[test]
fn odd_lateral_cubic_extrapolates_to_the_untested_side() {
    // The bench loads only +x; in flight the cable also pulls -x. Read -4 kg on x.
    let (syn, odd, _) = calibrated();
    let cfg = Config::embedded_sim();
    let full = fit(
        &syn.recording,
        &cfg,
        &FitOptions {
            lateral_poly: LateralPoly::Full,
        },
    )
    .unwrap();
    let mut model = sim_plant::sensor::SensorModel::new(syn.params.clone()).unwrap();
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(3);
    let applied = -4.0 * calibrate::recording::G;
    let codes: Vec<[i16; 4]> = (0..SAMPLES)
        .map(|_| {
            model
                .adc_volts([applied, 0.0, 0.0], &mut rng)
                .map(synthetic::quantise)
        })
        .collect();
    let read = |cal: &CalibrationConfig| {
        let (out, _) = calibrate::metrics::step_outputs(
            &calibrate::Recording {
                steps: vec![calibrate::Step {
                    axis: Axis::X,
                    weight_kg: 4.0,
                    cycle: 0,
                    direction: calibrate::Direction::Up,
                    step: 0,
                    codes: codes.clone(),
                }],
            },
            &cfg,
            Some(cal),
        );
        100.0 * (out[0].force_n[0] - applied).abs() / (5.0 * calibrate::recording::G)
    };
    let (e_odd, e_full) = (read(odd), read(&full));
    println!("-4 kg on x: error odd cubic {e_odd:.3} %FS, full cubic {e_full:.3} %FS");
    assert!(e_odd < 0.6, "{e_odd}");
    assert!(e_full > 2.0, "{e_full}");
}
