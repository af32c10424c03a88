//! The plant's benchmarks: fast mode (Test A and Test B in simulated time, reported as a
//! multiple of real time; the target is 100x) and real time (the physics loop paced by absolute
//! CLOCK_MONOTONIC deadlines at 1 kHz, flying Test A with the plant's pilot: overruns, wake-up
//! jitter and work per tick, as percentiles). Build first: `cargo build --release -p taut`.
//! `TAUT_BENCH_DURATION` sets the real-time run's length (default 60 s).

use std::process::Command;

fn taut() -> &'static str {
    let taut = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/release/taut");
    if !std::path::Path::new(taut).exists() {
        eprintln!("{taut} missing: run `cargo build --release -p taut` first");
        std::process::exit(1);
    }
    taut
}

fn run(args: &[&str]) {
    println!("== taut {}", args.join(" "));
    let status = Command::new(taut()).args(args).status().expect("run taut");
    assert!(status.success(), "taut {} failed", args.join(" "));
}

fn main() {
    // Benchmarks get `--bench` from cargo; no other arguments are used.
    for scenario in ["test-a", "test-b"] {
        for seed in ["1", "2", "3"] {
            run(&["plant", "--fast", "--scenario", scenario, "--seed", seed]);
        }
    }
    let duration = std::env::var("TAUT_BENCH_DURATION").unwrap_or_else(|_| "60".into());
    let dir = std::env::temp_dir().join(format!("taut-bench-plant-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let dir = dir.display().to_string();
    // The pilot flies Test A (about 20 s), then the drones hold until the duration is up.
    run(&[
        "plant",
        "--pilot",
        "--scenario",
        "test-a",
        "--duration",
        &duration,
        "--socket-dir",
        &dir,
        "--ipc-root",
        "bench-plant",
        "--remote-port",
        "24540",
        "--local-port",
        "24580",
    ]);
}
