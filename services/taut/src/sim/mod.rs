//! `taut sim test-a | test-b`: the main job. The plant in real time and two complete drone
//! service sets as separate processes (`--fast`: the same controller, tension, mission and
//! bridge code in one process, in simulated time), then a summary of the flight in
//! `<out>/summary.json`. Exits 0 only if every phase ended without a crash, a PX4 failsafe or
//! a dead service.

pub mod fast;
mod fast_record;
pub mod force_metrics;
pub mod metrics;
mod realtime;
mod setup;
pub mod summary;
mod swing;
mod trace;

use clap::Args;
use metrics::MetricsRecorder;
use shared_types::{MissionSetpoint, PlantTruth};
use sim_plant::scenario::{PhaseKind, Scenario};
use std::path::PathBuf;
use summary::Summary;

#[derive(Args, Debug, Clone)]
pub struct SimArgs {
    /// `test-a`, `test-b`, or a scenario TOML file.
    pub scenario: String,
    /// Seed of every random process (position perturbation, IMU and sensor noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Folder for summary.json, the drones' configs and the services' logs
    /// (default: `sim-out/<scenario>-seed<N>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Switch the motion-capture position perturbation off.
    #[arg(long)]
    pub no_noise: bool,
    /// In one process, in simulated time, as fast as the CPU allows.
    #[arg(long)]
    pub fast: bool,
    /// Give up after this long (real time: wall clock; fast: simulated), s
    /// (default: the scenario's phase timeouts plus 30 s).
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// What wakes the controller (default: the embedded config's, `odometry`).
    #[arg(long, value_enum)]
    pub controller_trigger: Option<Trigger>,
    /// Fast mode: do not write `<out>/recording.mcap` (nor the report).
    #[arg(long)]
    pub no_recording: bool,
    /// Print only the summary (fast mode: no per-phase lines).
    #[arg(long)]
    pub quiet: bool,
    /// Fast mode: write every controller step of both drones to this CSV (for plots).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Control law of both drones (default: the config's, `proposed`).
    #[arg(long, value_enum)]
    pub law: Option<Law>,
    /// Where both drones' controllers take the cable force from (default: the config's,
    /// `sensor`).
    #[arg(long, value_enum)]
    pub tension_source: Option<Source>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Law {
    Proposed,
    Geometric,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Source {
    Sensor,
    Estimator,
    Truth,
}

/// Writes `--law` / `--tension-source` into a drone's config (so the effective config the sim
/// writes carries them to the real-time services).
pub fn apply_baselines(args: &SimArgs, cfg: &mut rt_config::Config) {
    use rt_config::{ControllerLaw, TensionSource};
    if let Some(l) = args.law {
        cfg.controller.law = match l {
            Law::Proposed => ControllerLaw::Proposed,
            Law::Geometric => ControllerLaw::Geometric,
        };
    }
    if let Some(s) = args.tension_source {
        cfg.controller.tension_source = match s {
            Source::Sensor => TensionSource::Sensor,
            Source::Estimator => TensionSource::Estimator,
            Source::Truth => TensionSource::Truth,
        };
    }
}

/// The law and tension source both drones fly with: the embedded config's, overridden.
fn baselines(args: &SimArgs) -> (&'static str, &'static str) {
    let mut cfg = rt_config::Config::embedded_sim();
    apply_baselines(args, &mut cfg);
    (
        cfg.controller.law.as_str(),
        cfg.controller.tension_source.as_str(),
    )
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Trigger {
    Odometry,
    Timer,
}

impl SimArgs {
    pub fn time_limit_s(&self, scenario: &Scenario) -> f64 {
        self.time_limit
            .unwrap_or_else(|| scenario.phases.iter().map(|p| p.timeout_s).sum::<f64>() + 30.0)
    }
}

pub fn run(args: &SimArgs) -> Result<(), String> {
    let (summary, out) = fly(args)?;
    print!("{summary}");
    println!("[sim] wrote {}", out.join("summary.json").display());
    write_report_if_recorded(&out);
    match &summary.failure {
        None => Ok(()),
        Some(why) => Err(format!("the flight failed: {why}")),
    }
}

/// Flies `args`, writes `<out>/summary.json` (and the recording unless `--no-recording`),
/// returns the summary whatever the verdict, and the output folder. `Err` only if the flight
/// could not be flown at all.
pub fn fly(args: &SimArgs) -> Result<(Summary, PathBuf), String> {
    let scenario = Scenario::load(&args.scenario).map_err(|e| e.to_string())?;
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from("sim-out").join(format!("{}-seed{}", scenario.name, args.seed))
    });
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    taut_ipc::install_stop_handler();
    if !args.quiet {
        let (law, source) = baselines(args);
        println!(
            "[sim] {} seed {} ({}), noise {}, law {}, tension source {}, output in {}",
            scenario.name,
            args.seed,
            if args.fast { "fast" } else { "real time" },
            if args.no_noise { "off" } else { "on" },
            law,
            source,
            out.display()
        );
    }
    let recording = out.join("recording.mcap");
    let summary = if args.fast {
        fast::run(args, &scenario, (!args.no_recording).then_some(&*recording))?
    } else {
        realtime::run(args, &scenario, &out)?
    };
    summary.write(&out)?;
    Ok((summary, out))
}

/// The report of `<out>/recording.mcap` into `<out>/report/`, if recorded; a failure is
/// printed, it does not change the flight's verdict.
fn write_report_if_recorded(out: &std::path::Path) {
    let recording = out.join("recording.mcap");
    if !recording.exists() {
        return;
    }
    match crate::report::write_report(&recording, &out.join("report")) {
        Ok(r) => println!("[sim] wrote {}", r.markdown.display()),
        Err(e) => eprintln!("[sim] no report: {e}"),
    }
}

/// A recorder for `scenario`'s drones and phases.
pub fn new_recorder(scenario: &Scenario) -> MetricsRecorder {
    let vehicle = rt_config::VehicleConfig::default();
    MetricsRecorder::new(
        [scenario.drones[0].id.clone(), scenario.drones[1].id.clone()],
        scenario.phases.iter().map(|p| p.name.clone()).collect(),
        scenario
            .phases
            .iter()
            .map(|p| p.kind == PhaseKind::Move)
            .collect(),
        vehicle.anchor_offset_frd_m,
    )
}

/// How a flight is going: the first failure, and when both missions were done.
#[derive(Debug, Default)]
pub struct Outcome {
    pub failure: Option<String>,
    /// Simulated time of the newest truth sample, s.
    pub sim_s: f64,
    pub done_at_s: Option<f64>,
}

impl Outcome {
    /// Keeps the first failure.
    pub fn fail(&mut self, why: String) {
        self.failure.get_or_insert(why);
    }

    pub fn observe_truth(&mut self, t: &PlantTruth) {
        for (k, d) in t.drones.iter().enumerate() {
            if d.crash_flags != 0 {
                self.fail(format!(
                    "drone {} crashed (crash flags {:#x})",
                    k + 1,
                    d.crash_flags
                ));
            }
            if d.failsafe_count > 0 {
                self.fail(format!("PX4 failsafe fired on drone {}", k + 1));
            }
        }
    }

    pub fn observe_missions(&mut self, m: &[Option<MissionSetpoint>; 2]) {
        for s in m.iter().flatten() {
            if realtime::timed_out(s) {
                self.fail(format!("phase {} timed out", s.phase_index));
            }
        }
        if self.done_at_s.is_none() && realtime::both_done(m) {
            self.done_at_s = Some(self.sim_s);
        }
    }

    pub fn summary(
        &self,
        args: &SimArgs,
        scenario: &Scenario,
        mode: &'static str,
        rec: &MetricsRecorder,
        wall_s: f64,
    ) -> Summary {
        let failure = self.failure.clone().or_else(|| {
            self.done_at_s
                .is_none()
                .then(|| "the scenario did not complete".to_string())
        });
        let (law, tension_source) = baselines(args);
        Summary {
            scenario: scenario.name.clone(),
            seed: args.seed,
            noise: !args.no_noise,
            mode,
            law,
            tension_source,
            success: failure.is_none(),
            failure,
            sim_s: self.sim_s,
            wall_s,
            metrics: rec.finish(),
        }
    }
}
