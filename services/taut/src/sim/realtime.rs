//! The real-time flight: the plant process and, per drone, the five service processes (each
//! drone under its own id in one iceoryx2 root for this run), watched from here through the
//! same topics the services use plus the plant's ground truth. One recorder takes every topic
//! of both drones and the truth into `<out>/recording.mcap`: started first and confirmed
//! subscribed before anything publishes, stopped last so it drains what the others sent.

use super::metrics::MetricsRecorder;
use super::setup::{drone_config, scenario_arg_for_children, write_configs, Ports};
use super::summary::Summary;
use super::{new_recorder, Outcome, SimArgs};
use crate::supervisor::{ServiceSpec, Supervisor, Verdict};
use shared_types::{
    mission_flags, names, AttitudeSetpoint, MissionPhase, MissionSetpoint, PlantTruth,
};
use sim_plant::scenario::Scenario;
use std::path::Path;
use std::time::{Duration, Instant};
use taut_ipc::{stop_requested, Ipc, TopicSubscriber};

struct DroneTopics {
    mission: TopicSubscriber<MissionSetpoint>,
    setpoint: TopicSubscriber<AttitudeSetpoint>,
}

pub fn run(args: &SimArgs, scenario: &Scenario, out: &Path) -> Result<Summary, String> {
    let run_id = format!("sim{}", std::process::id());
    let socket_dir = std::env::temp_dir().join(format!("taut-{run_id}"));
    std::fs::create_dir_all(&socket_dir).map_err(|e| format!("{}: {e}", socket_dir.display()))?;
    let logs = out.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| format!("{}: {e}", logs.display()))?;
    let ports = Ports::pick()?;
    let scenario_arg = scenario_arg_for_children(&args.scenario);
    let cfgs = [0, 1].map(|k| {
        let mut c = drone_config(&scenario_arg, scenario, k, &run_id, &socket_dir, &ports);
        super::apply_baselines(args, &mut c);
        if let Some(t) = args.controller_trigger {
            c.controller.trigger = match t {
                super::Trigger::Odometry => rt_config::ControllerTrigger::Odometry,
                super::Trigger::Timer => rt_config::ControllerTrigger::Timer,
            };
        }
        c
    });
    let cfg_paths = write_configs(out, &cfgs)?;

    let mut sup = Supervisor::new(cfgs[0].supervisor)?.log_to(&logs);
    let wall = Instant::now();
    let result = (|| {
        start_recorder(&mut sup, out, &run_id, &cfgs, &cfg_paths, &socket_dir)?;
        let mut plant_args: Vec<String> = [
            "plant",
            "--scenario",
            &scenario_arg,
            "--seed",
            &args.seed.to_string(),
            "--ipc-root",
            &run_id,
            "--socket-dir",
            &socket_dir.display().to_string(),
            "--local-port",
            &ports.mavlink_local_base.to_string(),
            "--remote-port",
            &ports.mavlink_remote_base.to_string(),
        ]
        .map(String::from)
        .to_vec();
        if args.no_noise {
            plant_args.push("--no-noise".into());
        }
        sup.start(ServiceSpec {
            name: "plant".into(),
            args: plant_args,
        })?;
        for d in &scenario.drones {
            wait_for_file(&socket_dir.join(format!("taut-{}-i2c.sock", d.id)))?;
        }
        for (k, path) in cfg_paths.iter().enumerate() {
            for svc in crate::supervisor::FLIGHT_SERVICES {
                let mut spec =
                    ServiceSpec::svc(svc, vec!["--config".into(), path.display().to_string()]);
                spec.name = format!("{}-{svc}", cfgs[k].uav);
                sup.start(spec)?;
            }
        }
        monitor(args, scenario, &run_id, &mut sup, wall)
    })();
    sup.stop_all(Duration::from_secs(3));
    let _ = std::fs::remove_dir_all(&socket_dir);
    let (outcome, recorder) = result?;
    Ok(outcome.summary(
        args,
        scenario,
        "real-time",
        &recorder,
        wall.elapsed().as_secs_f64(),
    ))
}

fn wait_for_file(path: &Path) -> Result<(), String> {
    for _ in 0..1000 {
        if path.exists() {
            return Ok(());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Err(format!("the plant did not open {}", path.display()))
}

/// The recording of this flight.
pub const RECORDING: &str = "recording.mcap";

/// Starts `taut record` for both drones and the truth, each drone's config attached, and waits
/// until it is subscribed to every topic; the supervisor stops it after everything else.
fn start_recorder(
    sup: &mut Supervisor,
    out: &Path,
    root: &str,
    cfgs: &[rt_config::Config; 2],
    cfg_paths: &[std::path::PathBuf; 2],
    socket_dir: &Path,
) -> Result<(), String> {
    let ready = socket_dir.join("recorder.ready");
    let mut args: Vec<String> = vec![
        "record".into(),
        "--out".into(),
        out.join(RECORDING).display().to_string(),
        "--root".into(),
        root.into(),
        "--truth".into(),
        "--ready".into(),
        ready.display().to_string(),
    ];
    for (c, p) in cfgs.iter().zip(cfg_paths) {
        args.extend(["--uav".into(), c.uav.clone()]);
        args.extend(["--attach".into(), format!("{}={}", c.uav, p.display())]);
    }
    sup.start(ServiceSpec {
        name: "recorder".into(),
        args,
    })?;
    sup.stop_last("recorder");
    if crate::supervisor::wait_for_file(&ready, Duration::from_secs(10)) {
        Ok(())
    } else {
        Err("the recorder did not subscribe within 10 s (see logs/recorder.log)".into())
    }
}

/// Watches the flight until it ends (done, failed, or interrupted).
fn monitor(
    args: &SimArgs,
    scenario: &Scenario,
    root: &str,
    sup: &mut Supervisor,
    wall: Instant,
) -> Result<(Outcome, MetricsRecorder), String> {
    let node = format!("sim-monitor-{}", std::process::id());
    let plant_ipc = Ipc::new(&node, root, names::PLANT).map_err(|e| e.to_string())?;
    let truth_sub = plant_ipc
        .subscriber::<PlantTruth>(names::TRUTH)
        .map_err(|e| e.to_string())?;
    let mut drones = Vec::new();
    let mut ipcs = Vec::new();
    for d in &scenario.drones {
        let ipc = Ipc::new(&format!("{node}-{}", d.id), root, &d.id).map_err(|e| e.to_string())?;
        drones.push(DroneTopics {
            mission: ipc
                .subscriber(names::MISSION_SETPOINT)
                .map_err(|e| e.to_string())?,
            setpoint: ipc
                .subscriber(names::ATTITUDE_SETPOINT)
                .map_err(|e| e.to_string())?,
        });
        ipcs.push(ipc);
    }
    let mut rec = new_recorder(scenario);
    let mut outcome = Outcome::default();
    let limit_s = args.time_limit_s(scenario);
    let mut last_phase = [None::<MissionSetpoint>; 2];
    loop {
        let mut err = None;
        let _ = truth_sub.wait_and_drain(Duration::from_millis(20), |t| {
            rec.on_truth(&t);
            outcome.sim_s = t.sim_time_ns as f64 * 1e-9;
            outcome.observe_truth(&t);
        });
        for (k, d) in drones.iter().enumerate() {
            let mut f = |m: MissionSetpoint| {
                if let Some((i, name, t)) = rec.on_mission(k, &m) {
                    println!(
                        "[sim] {} phase {i} {name} started at {t:.2} s",
                        scenario.drones[k].id
                    );
                }
                last_phase[k] = Some(m);
            };
            if let Err(e) = d.mission.drain(&mut f) {
                err = Some(e.to_string());
            }
            if let Err(e) = d
                .setpoint
                .drain(&mut |s: AttitudeSetpoint| rec.on_setpoint(k, &s, true))
            {
                err = Some(e.to_string());
            }
        }
        if let Some(e) = err {
            outcome.fail(format!("monitor: {e}"));
        }
        outcome.observe_missions(&last_phase);
        if let Verdict::Failed(why) = sup.poll() {
            outcome.fail(why);
        }
        if stop_requested() {
            outcome.fail("interrupted".into());
        }
        if wall.elapsed().as_secs_f64() > limit_s {
            outcome.fail(format!("no end after {limit_s:.0} s"));
        }
        if outcome.failure.is_some() {
            break;
        }
        if let Some(done_s) = outcome.done_at_s {
            if outcome.sim_s >= done_s + scenario.linger_s.max(1.0) {
                break;
            }
        }
    }
    Ok((outcome, rec))
}

/// True once both drones' missions report Done.
pub fn both_done(m: &[Option<MissionSetpoint>; 2]) -> bool {
    m.iter()
        .all(|s| s.is_some_and(|s| s.phase == MissionPhase::Done))
}

/// Whether a drone's mission reports a timed-out phase.
pub fn timed_out(m: &MissionSetpoint) -> bool {
    m.flags & mission_flags::TIMED_OUT != 0
}
