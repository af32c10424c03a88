//! `taut`: the one binary. Verbs for people (`sim`, `study`, `report`, `replay`, `launch`,
//! `sensor`, `calibrate`, `plant`, `record`, `bench`, `config check`) and `svc NAME`, the entry
//! of each service process that `launch` starts as
//! a child of this same executable.

mod bench;
mod calibrate_cmd;
mod plant_cmd;
mod record_cmd;
mod replay;
mod report;
mod sensor;
mod sim;
mod study;
mod supervisor;
mod svc;

use clap::{Parser, Subcommand};
use rt_config::Config;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "taut",
    version,
    about = "Tension-aware UAV transport: companion-computer services"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a config and print the effective config (defaults filled in).
    Config {
        #[command(subcommand)]
        action: ConfigAction,
    },
    /// Start a drone's services with their real-time settings and supervise them.
    Launch {
        #[arg(long)]
        config: PathBuf,
    },
    /// Read the force sensor live (with --sim: the emulated sensor) and summarise.
    Sensor(sensor::SensorArgs),
    /// Compute a calibration from recorded frames, or run the paper's procedure on the emulator.
    Calibrate(calibrate_cmd::CalibrateArgs),
    /// Fly a scenario plant-in-the-loop: the plant and both drones' services (the main job).
    Sim(sim::SimArgs),
    /// Figures, latency percentiles and flight metrics of a recording (MCAP), as report.md.
    Report(report::ReportArgs),
    /// The plant alone: two simulated drones with emulated PX4 (MAVLink) and force sensors.
    Plant(plant_cmd::PlantArgs),
    /// Record drones' topics (and the plant's truth) into one MCAP file until Ctrl-C.
    Record(record_cmd::RecordArgs),
    /// Benchmarks of the running service set.
    Bench(bench::BenchArgs),
    /// Run one service (started by `launch`; not usually typed by hand).
    Svc(svc::SvcArgs),
    /// Run the controller library again on a recording's inputs; check its setpoints bit for bit.
    Replay(replay::ReplayArgs),
    /// The paper's comparison: Test A in fast mode for every controller law x tension source x
    /// seed; a table of mean and spread, and Fig. 9.
    Study(study::StudyArgs),
}

#[derive(Subcommand)]
enum ConfigAction {
    /// Check FILE and print its effective config.
    Check { file: PathBuf },
}

/// Loads `path`, or the embedded simulation config when `None`.
pub fn load_config(path: Option<&Path>) -> Result<Config, String> {
    match path {
        Some(p) => Config::load(p).map_err(|e| e.to_string()),
        None => Ok(Config::embedded_sim()),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Config {
            action: ConfigAction::Check { file },
        } => load_config(Some(&file)).map(|cfg| {
            print!("{}", cfg.to_toml());
            eprintln!("{}: ok", file.display());
        }),
        Command::Launch { config } => supervisor::launch(&config),
        Command::Sensor(args) => sensor::run(&args),
        Command::Calibrate(args) => calibrate_cmd::run(&args),
        Command::Sim(args) => sim::run(&args),
        Command::Plant(args) => plant_cmd::run(&args),
        Command::Report(args) => report::run(&args),
        Command::Record(args) => record_cmd::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Svc(args) => svc::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Study(args) => study::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("taut: {e}");
            ExitCode::FAILURE
        }
    }
}
