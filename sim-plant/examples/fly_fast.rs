//! Flies a scenario in fast mode with the plant's pilot and prints the report:
//! `cargo run --release -p sim-plant --example fly_fast -- test-a [seed] [--no-noise]`.
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map(String::as_str).unwrap_or("test-a");
    let scenario = sim_plant::scenario::Scenario::load(name).expect("scenario");
    let cfg = sim_plant::plant::PlantConfig {
        seed: args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1),
        perturbation_enabled: !args.iter().any(|a| a == "--no-noise"),
        ..Default::default()
    };
    let report = sim_plant::fast::run(&scenario, &cfg, None).expect("plant");
    println!("{report}");
}
