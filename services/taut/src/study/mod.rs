//! `taut study [--seeds N]`: the paper's comparison in fast mode. Flies Test A for every
//! controller law × tension source × seed, with the position perturbation on, and writes
//! `study.md` / `study.csv` (mean ± sample sd over seeds), `runs.csv` (every flight) and
//! `fig9.png` (the force used against truth, estimator flight vs sensor flight, seed 1).
//! Each flight's own folder (`runs/<law>-<source>-seed<N>/`) keeps its summary and recording.

mod fig9;
mod table;

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use clap::Parser;
use recorder::Recording;
pub use table::RunMetrics;

use crate::sim::{self, summary::Summary, SimArgs};

#[derive(clap::Args, Debug)]
pub struct StudyArgs {
    /// Seeds per configuration (1..=N).
    #[arg(long, default_value_t = 5)]
    pub seeds: u64,
    /// Output folder.
    #[arg(long, default_value = "study-out")]
    pub out: PathBuf,
    /// Scenario (the paper's comparison is Test A).
    #[arg(long, default_value = "test-a")]
    pub scenario: String,
}

/// The laws and sources compared, in table order.
pub const LAWS: [&str; 2] = ["proposed", "geometric"];
pub const SOURCES: [&str; 3] = ["sensor", "estimator", "truth"];

/// `taut sim`'s arguments for one study flight.
fn sim_args(
    scenario: &str,
    law: &str,
    source: &str,
    seed: u64,
    out: &Path,
    record: bool,
) -> SimArgs {
    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        sim: SimArgs,
    }
    let seed = seed.to_string();
    let out = out.display().to_string();
    let argv = [
        "sim",
        scenario,
        "--fast",
        "--seed",
        &seed,
        "--law",
        law,
        "--tension-source",
        source,
        "--out",
        &out,
        "--quiet",
    ];
    let mut argv = argv.to_vec();
    if !record {
        argv.push("--no-recording");
    }
    Wrap::try_parse_from(argv)
        .expect("the study's sim arguments are valid")
        .sim
}

/// A progress bar on stderr (a line per flight when stderr is not a terminal).
struct Progress {
    total: usize,
    done: usize,
    tty: bool,
}

impl Progress {
    fn show(&mut self, what: &str) {
        let width = 30;
        let filled = width * self.done / self.total.max(1);
        let bar = format!("{}{}", "#".repeat(filled), ".".repeat(width - filled));
        if self.tty {
            eprint!("\r[{bar}] {}/{} {what:<40}", self.done, self.total);
            let _ = std::io::stderr().flush();
        } else {
            eprintln!("[{bar}] {}/{} {what}", self.done, self.total);
        }
    }
}

/// The study's numbers from one flight's summary.
pub fn run_metrics(law: &str, source: &str, seed: u64, s: &Summary) -> RunMetrics {
    let m = &s.metrics;
    let mean = |f: &dyn Fn(&sim::metrics::DroneMetrics) -> Option<f64>| {
        let v: Vec<f64> = m.drones.iter().filter_map(f).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    RunMetrics {
        law: law.into(),
        source: source.into(),
        seed,
        swing_rms_deg: m.payload.swing_rms_deg,
        settling_s: m.payload.settling_time_s,
        z_steady_state_m: mean(&|d| d.z_steady_state_error_m.map(f64::abs)),
        position_rmse_m: mean(&|d| d.position_rmse_m),
        force_rmse_n: match source {
            "sensor" => mean(&|d| d.force_rmse.sensor_frd_n.as_ref().map(|e| e.norm)),
            "estimator" => mean(&|d| d.force_rmse.estimator_frd_n.as_ref().map(|e| e.norm)),
            _ => Some(0.0),
        },
        used_force_rmse_n: mean(&|d| d.force_rmse.used_ned_n.as_ref().map(|e| e.norm)),
        max_cable_force_n: Some(m.max_cable_force_n),
        crashed: m.crashed,
        completed: s.success,
    }
}

pub fn run(args: &StudyArgs) -> Result<(), String> {
    if args.seeds == 0 {
        return Err("--seeds must be at least 1".into());
    }
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let mut progress = Progress {
        total: LAWS.len() * SOURCES.len() * args.seeds as usize,
        done: 0,
        tty: std::io::stderr().is_terminal(),
    };
    let started = std::time::Instant::now();
    let mut runs = Vec::new();
    for law in LAWS {
        for source in SOURCES {
            for seed in 1..=args.seeds {
                let what = format!("{law} / {source} / seed {seed}");
                progress.show(&what);
                let dir = run_dir(&args.out, law, source, seed);
                // Fig. 9 needs the proposed law's seed-1 flights; the others keep their summary.
                let record = law == "proposed" && seed == 1;
                let (summary, _) =
                    sim::fly(&sim_args(&args.scenario, law, source, seed, &dir, record))
                        .map_err(|e| format!("{what}: {e}"))?;
                runs.push(run_metrics(law, source, seed, &summary));
                progress.done += 1;
            }
        }
    }
    progress.show("done");
    if progress.tty {
        eprintln!();
    }
    let md = format!(
        "# Study: Test A, fast mode, position noise on, seeds 1..={}\n\n\
         Cells: mean ± sample standard deviation over seeds; (k/N): only k of N flights had a \
         value (e.g. settled). Per-drone metrics are the mean of the two drones.\n\n{}",
        args.seeds,
        table::markdown(&runs)
    );
    let write = |name: &str, text: &str| {
        let p = args.out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("study.md", &md)?;
    write("study.csv", &table::csv(&runs))?;
    write("runs.csv", &table::runs_csv(&runs))?;
    draw_fig9(args)?;
    print!("{md}");
    println!(
        "[study] {} flights in {:.1} s; wrote {}/{{study.md,study.csv,runs.csv,fig9.png}}",
        runs.len(),
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

fn run_dir(out: &Path, law: &str, source: &str, seed: u64) -> PathBuf {
    out.join("runs").join(format!("{law}-{source}-seed{seed}"))
}

/// Fig. 9 from the proposed controller's seed-1 flights with the estimator and with the sensor.
fn draw_fig9(args: &StudyArgs) -> Result<(), String> {
    let open = |source: &str| {
        let p = run_dir(&args.out, "proposed", source, 1).join("recording.mcap");
        Recording::open(&p).map_err(|e| e.to_string())
    };
    let estimator = open("estimator")?;
    let sensor = open("sensor")?;
    let text = calibrate::plots::ensure_font(None).is_some();
    fig9::draw(
        &args.out.join("fig9.png"),
        &[
            (&estimator, fig9::Used::Estimator),
            (&sensor, fig9::Used::Sensor),
        ],
        text,
    )
}
