//! `taut study --seeds 1`: six fast Test A flights (proposed | geometric × sensor | estimator |
//! truth), the table in markdown and CSV, every run in runs.csv, and Fig. 9.

use std::process::Command;

const TAUT: &str = env!("CARGO_BIN_EXE_taut");

#[test]
fn study_writes_the_table_the_runs_and_fig9() {
    let out = std::env::temp_dir().join(format!("taut-study-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let output = Command::new(TAUT)
        .args(["study", "--seeds", "1", "--out"])
        .arg(&out)
        .output()
        .expect("start taut study");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    eprintln!("{stdout}{stderr}");
    assert!(output.status.success(), "taut study failed");
    // The progress bar went to stderr and reached the end.
    assert!(stderr.contains("6/6"), "{stderr}");

    let md = std::fs::read_to_string(out.join("study.md")).expect("study.md");
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| ")).collect();
    // Header + 6 configurations.
    assert_eq!(rows.len(), 7, "{md}");
    for law in ["proposed", "geometric"] {
        for source in ["sensor", "estimator", "truth"] {
            assert!(
                rows.iter()
                    .any(|r| r.starts_with(&format!("| {law} | {source} | 1 |"))),
                "no row for {law}/{source}: {md}"
            );
        }
    }
    let csv = std::fs::read_to_string(out.join("study.csv")).expect("study.csv");
    assert_eq!(csv.lines().count(), 7, "{csv}");
    let runs = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv");
    assert_eq!(runs.lines().count(), 7, "{runs}");
    // No flight crashed, and the paper's controller with its sensor completed Test A.
    for line in runs.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        assert_eq!(cols[cols.len() - 2], "false", "crashed: {line}");
        if line.starts_with("proposed,sensor,") {
            assert_eq!(cols[cols.len() - 1], "true", "did not complete: {line}");
        }
    }
    let png = std::fs::read(out.join("fig9.png")).expect("fig9.png");
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "{} bytes",
        png.len()
    );
    let _ = std::fs::remove_dir_all(&out);
}
