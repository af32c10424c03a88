//! `taut plant`: the plant alone, in real time (paced by absolute CLOCK_MONOTONIC deadlines) or
//! fast (in simulated time). In real time it serves, per drone, a MAVLink endpoint on PX4 SITL's
//! ports and the force sensor's emulated I2C bus, and publishes the ground truth (PlantTruth on
//! `plant/truth` at 100 Hz, and each drone's true anchor force as a TensionSample on
//! `<uav>/tension_truth` every [`TRUTH_TENSION_PERIOD_NS`]); any MAVLink
//! client can fly it. `--pilot` flies the scenario itself with PX4's position controller (for
//! benchmarks and for watching the plant alone).

use clap::Args;
use latency_tests::{Percentiles, SpanHistograms};
use rt_config::periodic::{now_ns, PeriodicLoop};
use serde::Serialize;
use shared_types::{names, PlantTruth, TensionSample};
use sim_plant::mavlink_link::{LinkConfig, LinkCounters, MavlinkEndpoint};
use sim_plant::pilot::ScenarioPilot;
use sim_plant::plant::{Plant, PlantConfig};
use sim_plant::scenario::Scenario;
use sim_plant::sensor::{BusConfig, BusServer, LoadProfile, SensorBus, SensorModel, SensorParams};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;
use taut_ipc::{install_stop_handler, stop_requested, Ipc};

/// Period of the true anchor force on TENSION_TRUTH (500 Hz: above the sensor's 240 Hz, so the
/// `truth` tension source is never the slower one), ns.
pub const TRUTH_TENSION_PERIOD_NS: u64 = 2_000_000;

/// Drone `k`'s true anchor force (the cable's pull on it, body FRD) as a TensionSample with
/// `t_origin_ns` = the plant instant it belongs to (the caller's clock).
pub fn truth_tension(plant: &Plant, k: usize, t_origin_ns: u64) -> TensionSample {
    let mut s = TensionSample {
        force_body_n: plant.anchor_force_frd(k),
        ..Default::default()
    };
    s.force_sensor_n = s.force_body_n;
    s.header.t_origin_ns = t_origin_ns;
    s
}

#[derive(Args, Debug, Clone)]
pub struct PlantArgs {
    /// `test-a`, `test-b`, or a scenario TOML file.
    #[arg(long, default_value = "test-a")]
    pub scenario: String,
    /// Seed of every random process (position perturbation, IMU and sensor noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Switch the motion-capture position perturbation off.
    #[arg(long)]
    pub no_noise: bool,
    /// Stop after this many seconds (default: run until SIGINT/SIGTERM).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Fly the scenario with the plant's own pilot (PX4's position controller over offboard).
    #[arg(long)]
    pub pilot: bool,
    /// Run in simulated time, as fast as possible, with the pilot (no endpoints).
    #[arg(long)]
    pub fast: bool,
    /// Companion-side UDP port of drone 0 (PX4 SITL: 14540); drone i uses +i.
    #[arg(long, default_value_t = 14540)]
    pub remote_port: u16,
    /// Plant-side UDP port of drone 0 (PX4 SITL: 14580); drone i uses +i.
    #[arg(long, default_value_t = 14580)]
    pub local_port: u16,
    /// Folder of the emulated I2C sockets `taut-<drone id>-i2c.sock`.
    #[arg(long, default_value = "/tmp")]
    pub socket_dir: PathBuf,
    /// iceoryx2 root of the truth topic (`<root>/taut/plant/truth`).
    #[arg(long, default_value = "")]
    pub ipc_root: String,
    /// Real-time loop period, µs.
    #[arg(long, default_value_t = 1000)]
    pub tick_us: u64,
    /// SCHED_FIFO priority of the plant (1..=99), 0 = SCHED_OTHER. Measured on this 2-core
    /// machine: FIFO 60 on core 0 gives wake-up jitter p50 24 µs / p99 87 µs, SCHED_OTHER
    /// 76 / 379 µs. Without the privilege it warns and runs as SCHED_OTHER.
    #[arg(long, default_value_t = 60)]
    pub priority: u8,
    /// CPU core to pin the plant to (the simulated drones' services use core 1).
    #[arg(long, default_value_t = 0)]
    pub core: usize,
    /// Print one JSON report at the end instead of text.
    #[arg(long)]
    pub json: bool,
}

/// What a real-time run measured.
#[derive(Debug, Serialize)]
pub struct RealTimeReport {
    pub scenario: String,
    pub seed: u64,
    pub noise: bool,
    pub wall_s: f64,
    pub sim_s: f64,
    pub tick_period_us: u64,
    pub ticks: u64,
    /// Whole periods skipped because a wake-up came more than a period late.
    pub overruns: u64,
    /// Ticks whose work ended after the next deadline.
    pub late_ticks: u64,
    /// Wake-up lateness against the absolute deadline, µs.
    pub jitter_us: Percentiles,
    /// Work per tick (physics steps, links, sensors, truth), µs.
    pub tick_work_us: Percentiles,
    /// One physics step (plant.step), µs.
    pub step_us: Percentiles,
    /// Largest lag of simulated time behind the wall clock, ms.
    pub max_sim_lag_ms: f64,
    pub links: [LinkCounters; 2],
    pub failsafe_count: [u32; 2],
    pub crash_flags: [u32; 2],
    pub truth_published: u64,
    /// With --pilot: the phases reached and whether the scenario completed.
    pub phases_completed: usize,
    pub completed: bool,
}

pub fn run(args: &PlantArgs) -> Result<(), String> {
    let scenario = Scenario::load(&args.scenario).map_err(|e| e.to_string())?;
    let cfg = PlantConfig {
        seed: args.seed,
        perturbation_enabled: !args.no_noise,
        ..PlantConfig::default()
    };
    if args.fast {
        let report =
            sim_plant::fast::run(&scenario, &cfg, args.duration).map_err(|e| e.to_string())?;
        if args.json {
            println!(
                "{}",
                serde_json::to_string_pretty(&report).unwrap_or_default()
            );
        } else {
            println!("{report}");
        }
        return if report.completed && report.failsafe_count == [0, 0] {
            Ok(())
        } else {
            Err("the scenario did not complete".into())
        };
    }
    install_stop_handler();
    let rt = rt_config::ServiceRt {
        core: Some(args.core),
        priority: (args.priority > 0).then_some(args.priority),
        policy: rt_config::RtPolicy::Warn,
        lock_memory: true,
    };
    let applied = rt_config::rt::apply(&rt).map_err(|e| format!("plant: {e}"))?;
    eprintln!("[plant] real-time: {applied}");
    let report = run_real_time(args, &scenario, &cfg)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).unwrap_or_default()
        );
    } else {
        print_report(&report);
    }
    Ok(())
}

fn print_report(r: &RealTimeReport) {
    println!(
        "plant {}: {:.1} s wall, {:.1} s simulated, {} ticks of {} µs",
        r.scenario, r.wall_s, r.sim_s, r.ticks, r.tick_period_us
    );
    println!(
        "  overruns {} (skipped periods), late ticks {}, max sim lag {:.2} ms",
        r.overruns, r.late_ticks, r.max_sim_lag_ms
    );
    let p = |name: &str, q: &Percentiles| {
        println!(
            "  {name:<10} p50 {:8.1} µs  p99 {:8.1} µs  p99.9 {:8.1} µs  max {:8.1} µs",
            q.p50, q.p99, q.p999, q.max
        )
    };
    p("jitter", &r.jitter_us);
    p("tick work", &r.tick_work_us);
    p("step", &r.step_us);
    for (i, l) in r.links.iter().enumerate() {
        println!("  link {i}: {l:?}");
    }
    println!(
        "  failsafes {:?}, crash flags {:?}, truth samples {}",
        r.failsafe_count, r.crash_flags, r.truth_published
    );
}

fn link_config(args: &PlantArgs, i: usize) -> LinkConfig {
    let local: SocketAddr = ([127, 0, 0, 1], args.local_port + i as u16).into();
    let remote: SocketAddr = ([127, 0, 0, 1], args.remote_port + i as u16).into();
    LinkConfig {
        bind: local,
        remote,
        ..LinkConfig::px4_sitl(i as u8)
    }
}

/// One emulated force sensor served on a Unix socket, driven by the plant's anchor force.
struct SensorServer {
    bus: Arc<std::sync::Mutex<SensorBus>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl SensorServer {
    fn start(path: PathBuf, seed: u64, t0_ns: u64) -> Result<Self, String> {
        let model = SensorModel::new(SensorParams::default()).map_err(|e| e.to_string())?;
        let bus = SensorBus::new(
            BusConfig::default(),
            model,
            LoadProfile::Constant([0.0; 3]),
            t0_ns,
            seed,
        )
        .map_err(|e| e.to_string())?;
        let server = BusServer::bind(&path, bus)
            .map_err(|e| format!("cannot serve the sensor on {}: {e}", path.display()))?;
        let bus = server.bus();
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let thread = std::thread::Builder::new()
            .name("sensor-bus".into())
            .spawn(move || {
                if let Err(e) = server.serve(&stop2) {
                    eprintln!("[plant] sensor bus on {}: {e}", server.path().display());
                }
            })
            .map_err(|e| e.to_string())?;
        Ok(SensorServer {
            bus,
            stop,
            thread: Some(thread),
        })
    }

    /// Conversions due by `now_ns` see the previous force; from now on the new one (a
    /// zero-order hold at the loop's tick, 1 ms, against a 4.17 ms conversion).
    fn drive(&self, now_ns: u64, force_frd: [f64; 3]) {
        if let Ok(mut bus) = self.bus.lock() {
            bus.advance_to(now_ns);
            let t0 = bus.t0_ns();
            bus.set_profile(LoadProfile::Constant(force_frd), t0);
        }
    }
}

impl Drop for SensorServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn run_real_time(
    args: &PlantArgs,
    scenario: &Scenario,
    cfg: &PlantConfig,
) -> Result<RealTimeReport, String> {
    let mut plant = Plant::new(scenario, cfg).map_err(|e| e.to_string())?;
    let open = |i: usize| {
        MavlinkEndpoint::open(link_config(args, i))
            .map_err(|e| format!("MAVLink endpoint of drone {i}: {e}"))
    };
    let mut links = [open(0)?, open(1)?];
    let t0 = now_ns();
    let sensors = [0, 1].map(|i| {
        let path = args
            .socket_dir
            .join(format!("taut-{}-i2c.sock", scenario.drones[i].id));
        SensorServer::start(path, args.seed.wrapping_mul(2).wrapping_add(i as u64), t0)
    });
    let [s0, s1] = sensors;
    let sensors = [s0?, s1?];
    let ipc = Ipc::new("plant", &args.ipc_root, names::PLANT).map_err(|e| e.to_string())?;
    let mut truth_pub = ipc
        .publisher::<PlantTruth>(names::TRUTH)
        .map_err(|e| e.to_string())?;
    // Each drone's true force under that drone's id, as its tension topics are.
    let drone_ipc = |i: usize| {
        let id = &scenario.drones[i].id;
        Ipc::new(&format!("plant-{id}"), &args.ipc_root, id).map_err(|e| e.to_string())
    };
    let drone_ipcs = [drone_ipc(0)?, drone_ipc(1)?];
    let tension_pub = |i: usize| {
        drone_ipcs[i]
            .publisher::<TensionSample>(names::TENSION_TRUTH)
            .map_err(|e| e.to_string())
    };
    let mut tension_truth_pubs = [tension_pub(0)?, tension_pub(1)?];
    let mut pilot = match args.pilot {
        true => Some(
            ScenarioPilot::new(scenario, &cfg.inner_loops.position).map_err(|e| e.to_string())?,
        ),
        false => None,
    };

    for (i, d) in scenario.drones.iter().enumerate() {
        let c = link_config(args, i);
        eprintln!(
            "[plant] {}: MAVLink udp {} -> {} (connect with udpin:{}), sensor {}",
            d.id,
            c.bind,
            c.remote,
            c.remote,
            args.socket_dir
                .join(format!("taut-{}-i2c.sock", d.id))
                .display()
        );
    }
    eprintln!(
        "[plant] truth on {}; scenario {}, seed {}, noise {}",
        ipc.service_name(names::TRUTH),
        scenario.name,
        args.seed,
        if cfg.perturbation_enabled {
            "on"
        } else {
            "off"
        }
    );

    let tick_ns = args.tick_us.max(100) * 1000;
    let mut spans = SpanHistograms::new(&["jitter", "work", "step"]);
    let mut lp = PeriodicLoop::starting_at(t0 + tick_ns, tick_ns);
    let (mut ticks, mut late_ticks, mut truth_published) = (0u64, 0u64, 0u64);
    let mut max_lag_ns = 0u64;
    let truth_period_ns = 10_000_000;
    let mut next_truth_ns = t0;
    let mut next_tension_truth_ns = t0;
    let end_ns = args.duration.map(|d| t0 + (d * 1e9) as u64);
    let wall = Instant::now();
    let max_steps_per_tick = (4 * tick_ns / plant.dt_ns()).max(1);
    loop {
        let tick = lp.wait();
        ticks += 1;
        spans.record_span(
            "jitter",
            tick.deadline_ns,
            tick.deadline_ns + tick.lateness_ns,
        );
        let now = now_ns();
        if stop_requested() || end_ns.is_some_and(|e| now >= e) {
            break;
        }
        for (i, link) in links.iter_mut().enumerate() {
            link.poll(now, &mut |msg| plant.handle(i, msg));
        }
        let target = now - t0;
        let mut steps = 0;
        while plant.time_ns() + plant.dt_ns() <= target && steps < max_steps_per_tick {
            let s = now_ns();
            plant.step();
            spans.record_span("step", s, now_ns());
            if let Some(p) = pilot.as_mut() {
                p.on_step(&mut plant);
            }
            steps += 1;
        }
        max_lag_ns = max_lag_ns.max(target.saturating_sub(plant.time_ns()));
        for (i, link) in links.iter_mut().enumerate() {
            link.send_due(now, &plant.telemetry(i));
        }
        for (i, s) in sensors.iter().enumerate() {
            s.drive(now, plant.anchor_force_frd(i));
        }
        if now >= next_tension_truth_ns {
            next_tension_truth_ns += TRUTH_TENSION_PERIOD_NS;
            for (i, p) in tension_truth_pubs.iter_mut().enumerate() {
                // A full subscriber queue is the subscriber's problem; the plant keeps time.
                let _ = p.publish(truth_tension(&plant, i, t0 + plant.time_ns()));
            }
        }
        if now >= next_truth_ns {
            next_truth_ns += truth_period_ns;
            let mut truth = plant.truth();
            truth.header.t_origin_ns = t0 + plant.time_ns();
            if truth_pub.publish(truth).is_ok() {
                truth_published += 1;
            }
        }
        let done = now_ns();
        spans.record_span("work", now, done);
        if done > lp.schedule().next_deadline_ns() {
            late_ticks += 1;
        }
        // Without --duration a piloted run ends with the scenario; with it, the drones hold
        // their last setpoints until the time is up.
        if end_ns.is_none() && pilot.as_ref().is_some_and(|p| p.finished()) {
            break;
        }
    }
    let pct = |n: &str| spans.percentiles(n).unwrap_or(ZERO);
    Ok(RealTimeReport {
        scenario: scenario.name.clone(),
        seed: args.seed,
        noise: cfg.perturbation_enabled,
        wall_s: wall.elapsed().as_secs_f64(),
        sim_s: plant.time_ns() as f64 * 1e-9,
        tick_period_us: tick_ns / 1000,
        ticks,
        overruns: lp.schedule().overruns(),
        late_ticks,
        jitter_us: pct("jitter"),
        tick_work_us: pct("work"),
        step_us: pct("step"),
        max_sim_lag_ms: max_lag_ns as f64 * 1e-6,
        links: [links[0].counters(), links[1].counters()],
        failsafe_count: plant.failsafe_count(),
        crash_flags: plant.crash_flags(),
        truth_published,
        phases_completed: pilot.as_ref().map_or(0, |p| p.phases_completed()),
        completed: pilot.as_ref().is_some_and(|p| p.completed()),
    })
}

const ZERO: Percentiles = Percentiles {
    count: 0,
    p50: 0.0,
    p99: 0.0,
    p999: 0.0,
    max: 0.0,
};
