//! The recording format round trip, its error messages, and `run` end to end.

use calibrate::recording::HEADER;
use calibrate::synthetic::{self, SyntheticOptions};
use calibrate::{calibration_toml, run, CalibrateError, CalibrateOptions, Recording};
use rt_config::Config;
use std::path::PathBuf;

fn small() -> SyntheticOptions {
    SyntheticOptions {
        seed: 11,
        samples_per_step: 20,
        cycles: 2,
        ..SyntheticOptions::default()
    }
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("taut-calibrate-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn recording_round_trips_through_csv() {
    let rec = synthetic::generate(&Config::embedded_sim(), &small())
        .unwrap()
        .recording;
    let mut bytes = vec![];
    rec.write(&mut bytes).unwrap();
    let text = String::from_utf8(bytes).unwrap();
    assert!(
        text.starts_with(&format!("{HEADER}\nz,0,0,up,0,")),
        "{}",
        &text[..120]
    );
    let back = Recording::parse(text.as_bytes(), "mem").unwrap();
    assert_eq!(back, rec);
}

#[test]
fn a_malformed_line_is_reported_with_its_line_and_column() {
    let text =
        format!("{HEADER}\n# a note\nz,0,0,up,0,500,500,500,500\nz,0,0,up,0,500,500,5OO,500\n");
    let err = Recording::parse(text.as_bytes(), "bench.csv").unwrap_err();
    let msg = err.to_string();
    assert_eq!(
        msg,
        "bench.csv: line 4, column 8 (code3): `5OO` is not a 12-bit code -2048..=2047"
    );
    // Through `run`, from a file.
    let dir = temp_dir("malformed");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bench.csv");
    std::fs::write(&path, &text).unwrap();
    let opts = CalibrateOptions::from_recording(path, Config::embedded_sim(), dir.join("out"));
    match run(&opts) {
        Err(CalibrateError::Recording(e)) => assert!(e.to_string().contains("line 4, column 8")),
        other => panic!("expected a recording error, got {other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_writes_every_output_and_they_load() {
    let dir = temp_dir("run");
    let cfg = Config::embedded_sim();
    let outcome = run(&CalibrateOptions::synthetic(
        small(),
        cfg.clone(),
        dir.clone(),
    ))
    .unwrap();
    for name in [
        "recording.csv",
        "calibration.toml",
        "config-calibrated.toml",
        "report.md",
        "report.json",
        "hysteresis.png",
        "nonlinearity.png",
        "repeatability.png",
        "crossload.png",
    ] {
        let p = dir.join(name);
        assert!(
            std::fs::metadata(&p).map(|m| m.len() > 0).unwrap_or(false),
            "{name}"
        );
        assert!(outcome.files.contains(&p), "{name} not listed");
    }
    // The recording written is the one calibrated, and calibrates the same again from disk.
    let mut again =
        CalibrateOptions::from_recording(dir.join("recording.csv"), cfg.clone(), dir.join("again"));
    again.plots.enabled = false; // PNG encoding is slow in debug builds
    let again = run(&again).unwrap();
    assert!(!again
        .files
        .iter()
        .any(|f| f.extension().is_some_and(|e| e == "png")));
    assert_eq!(again.calibration, outcome.calibration);

    // calibration.toml is a [calibration] table: appended to a config without one, it loads.
    let table = std::fs::read_to_string(dir.join("calibration.toml")).unwrap();
    assert_eq!(table, calibration_toml(&outcome.calibration));
    let mut bare = cfg.clone();
    bare.calibration = None;
    let merged = format!("{}\n{table}", bare.to_toml());
    let loaded = Config::from_toml_str(&merged, "merged").unwrap();
    assert_eq!(loaded.calibration.as_ref(), Some(&outcome.calibration));
    let whole = std::fs::read_to_string(dir.join("config-calibrated.toml")).unwrap();
    let loaded = Config::from_toml_str(&whole, "whole").unwrap();
    assert_eq!(loaded.calibration.as_ref(), Some(&outcome.calibration));

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["after"]["axes"].as_array().map(Vec::len), Some(3));
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("| z | 53.94 | Crossload |"), "{md}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn options_need_exactly_one_source() {
    let mut opts = CalibrateOptions::synthetic(small(), Config::embedded_sim(), temp_dir("opts"));
    opts.recording = Some("x.csv".into());
    assert!(matches!(run(&opts), Err(CalibrateError::Options(_))));
    opts.recording = None;
    opts.synthetic = None;
    assert!(matches!(run(&opts), Err(CalibrateError::Options(_))));
    assert!(!opts.out_dir.exists(), "nothing is written for bad options");
}
