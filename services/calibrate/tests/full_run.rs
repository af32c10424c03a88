//! The full synthetic procedure (3000 samples per step, 10 cycles): prints the report table.
//! Run with `cargo test --release -p calibrate --test full_run -- --ignored --nocapture`.

use calibrate::{run, CalibrateOptions, SyntheticOptions};
use rt_config::Config;

#[test]
#[ignore = "full 3000-sample run: seconds in release, slow in debug"]
fn full_synthetic_run() {
    let out = std::env::var("CALIBRATE_OUT")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| std::env::temp_dir().join("taut-calibrate-full"));
    let samples = std::env::var("CALIBRATE_SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3000);
    let t = std::time::Instant::now();
    let outcome = run(&CalibrateOptions::synthetic(
        SyntheticOptions {
            samples_per_step: samples,
            ..SyntheticOptions::default()
        },
        Config::embedded_sim(),
        out.clone(),
    ))
    .expect("synthetic calibration runs");
    println!("{}", outcome.report.markdown());
    println!("files in {}: {:?}", out.display(), outcome.files);
    println!("font: {:?}; took {:.2?}", outcome.font, t.elapsed());
}
