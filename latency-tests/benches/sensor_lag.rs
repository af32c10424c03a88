//! The filter-budget benchmark: runs `taut bench sensor` (release build) for both sampling
//! modes and prints each span's percentiles, `ramp_lag` being the lag of the tension output
//! behind the true force. Build first: `cargo build --release -p taut`.

use std::process::Command;

fn main() {
    let taut = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/release/taut");
    if !std::path::Path::new(taut).exists() {
        eprintln!("{taut} missing: run `cargo build --release -p taut` first");
        std::process::exit(1);
    }
    let duration = std::env::var("TAUT_BENCH_DURATION").unwrap_or_else(|_| "20".into());
    for mode in ["continuous", "synchronous"] {
        println!("== taut bench sensor --mode {mode} --duration {duration}");
        let status = Command::new(taut)
            .args(["bench", "sensor", "--mode", mode, "--duration", &duration])
            .status()
            .expect("run taut");
        assert!(status.success(), "taut bench sensor failed");
    }
}
