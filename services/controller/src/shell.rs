//! The controller service: `<uav>-controller`, subscribes VEHICLE_STATE, the tension topic of
//! `controller.tension_source` (TENSION, TENSION_ESTIMATE or TENSION_TRUTH) and
//! MISSION_SETPOINT, publishes ATTITUDE_SETPOINT, until SIGINT/SIGTERM.
//!
//! Triggers (`controller.trigger`):
//! - `odometry`: step when a vehicle state arrives; if none arrives within 1.5 periods, step on
//!   that deadline anyway so PX4's offboard stream never stops (the stage flags the odometry
//!   STALE_ODOMETRY once it is older than `odometry_max_age_s`);
//! - `timer`: step on an absolute-deadline timer at `rate_hz`.
//!
//! Tension and mission are drained without blocking, keeping the newest. Before the first
//! vehicle state the stage sees a disarmed, level, stale one and streams IDLE setpoints. On
//! exit it prints the counters and the p50/p99 of (publish − tension t_origin) and
//! (publish − odometry t_origin), µs, from two preallocated histograms (recording does not
//! allocate). `cfg.services.controller` (the ServiceRt) is applied here, first thing.

use std::time::Duration;

use hdrhistogram::Histogram;
use rt_config::periodic::{now_ns, PeriodicLoop};
use rt_config::{Config, ControllerTrigger, TensionSource};
use shared_types::{names, AttitudeSetpoint, MissionSetpoint, TensionSample, VehicleState};
use taut_ipc::{stop_requested, Ipc, TopicPublisher, TopicSubscriber};

use crate::ControllerStage;

/// Latencies from the input's physical measurement to the setpoint's publication, µs.
struct LatencyRecord {
    from_tension_us: Histogram<u64>,
    from_odometry_us: Histogram<u64>,
}

impl LatencyRecord {
    fn new() -> Result<Self, String> {
        // 1 µs .. 10 s at 3 significant digits: preallocated, `saturating_record` never grows.
        let h = || Histogram::new_with_bounds(1, 10_000_000, 3).map_err(|e| e.to_string());
        Ok(Self {
            from_tension_us: h()?,
            from_odometry_us: h()?,
        })
    }

    fn add(&mut self, t_publish_ns: u64, sp: &AttitudeSetpoint) {
        let us = |origin: u64| (t_publish_ns.saturating_sub(origin) / 1000).max(1);
        if sp.tension_origin_ns != 0 {
            self.from_tension_us
                .saturating_record(us(sp.tension_origin_ns));
        }
        if sp.odometry_origin_ns != 0 {
            self.from_odometry_us
                .saturating_record(us(sp.odometry_origin_ns));
        }
    }

    fn summary(h: &Histogram<u64>) -> String {
        if h.is_empty() {
            return "none".into();
        }
        format!(
            "p50={} p99={} (n={})",
            h.value_at_quantile(0.5),
            h.value_at_quantile(0.99),
            h.len()
        )
    }
}

/// The newest sample of each input.
struct Inputs {
    state: VehicleState,
    tension: Option<TensionSample>,
    mission: Option<MissionSetpoint>,
}

struct Ports {
    states: TopicSubscriber<VehicleState>,
    tensions: TopicSubscriber<TensionSample>,
    missions: TopicSubscriber<MissionSetpoint>,
    output: TopicPublisher<AttitudeSetpoint>,
}

/// Runs the controller service until a stop signal.
pub fn run(cfg: &Config) -> Result<(), String> {
    let report =
        rt_config::rt::apply(&cfg.services.controller).map_err(|e| format!("controller: {e}"))?;
    eprintln!("[controller] real-time: {report}");
    let mut stage =
        ControllerStage::new(&cfg.vehicle, &cfg.controller).map_err(|e| e.to_string())?;
    eprintln!(
        "[controller] law {}, tension from {} ({})",
        cfg.controller.law.as_str(),
        cfg.controller.tension_source.as_str(),
        tension_topic(cfg.controller.tension_source)
    );
    let ipc = Ipc::new(&format!("{}-controller", cfg.uav), &cfg.ipc_root, &cfg.uav)
        .map_err(|e| e.to_string())?;
    let e = |e: taut_ipc::IpcError| e.to_string();
    let mut ports = Ports {
        states: ipc.subscriber(names::VEHICLE_STATE).map_err(e)?,
        tensions: ipc
            .subscriber(tension_topic(cfg.controller.tension_source))
            .map_err(e)?,
        missions: ipc.subscriber(names::MISSION_SETPOINT).map_err(e)?,
        output: ipc.publisher(names::ATTITUDE_SETPOINT).map_err(e)?,
    };
    let mut inputs = Inputs {
        // Until the bridge speaks: disarmed, level, never measured (stale).
        state: VehicleState::before_first_odometry(),
        tension: None,
        mission: None,
    };
    let mut record = LatencyRecord::new()?;
    let mut errors = 0u64;
    let period_ns = ((1e9 / cfg.controller.rate_hz).round() as u64).max(1);
    match cfg.controller.trigger {
        ControllerTrigger::Odometry => {
            let mut last_step_ns = now_ns();
            while !stop_requested() {
                let deadline = last_step_ns + period_ns * 3 / 2;
                let now = now_ns();
                if now < deadline
                    && ports
                        .states
                        .wait(Duration::from_nanos(deadline - now))
                        .is_err()
                    && !stop_requested()
                {
                    errors += 1;
                }
                let fresh = drain_newest(&ports.states, &mut errors)
                    .map(|s| inputs.state = s)
                    .is_some();
                if !fresh && now_ns() < deadline {
                    continue;
                }
                last_step_ns = now_ns();
                step_and_publish(
                    &mut stage,
                    &mut inputs,
                    &mut ports,
                    &mut record,
                    &mut errors,
                );
            }
        }
        ControllerTrigger::Timer => {
            let mut timer = PeriodicLoop::new(period_ns);
            while !stop_requested() {
                timer.wait();
                if let Some(s) = drain_newest(&ports.states, &mut errors) {
                    inputs.state = s;
                }
                step_and_publish(
                    &mut stage,
                    &mut inputs,
                    &mut ports,
                    &mut record,
                    &mut errors,
                );
            }
        }
    }
    let c = stage.counters();
    eprintln!(
        "[controller] stopped: steps={} non_finite={} idle={} stale_tension={} stale_mission={} \
         stale_odometry={} tilt_limited={} thrust_limited={} formation_limit={} \
         tension_flagged={} ipc_errors={errors}; publish - tension origin us: {}; \
         publish - odometry origin us: {}",
        c.steps,
        c.non_finite_inputs,
        c.idle_steps,
        c.stale_tension_steps,
        c.stale_mission_steps,
        c.stale_odometry_steps,
        c.tilt_limited_steps,
        c.thrust_limited_steps,
        c.formation_limit_steps,
        c.tension_flagged_steps,
        LatencyRecord::summary(&record.from_tension_us),
        LatencyRecord::summary(&record.from_odometry_us),
    );
    Ok(())
}

/// The topic of `controller.tension_source`: the sensor's TENSION, the estimator's
/// TENSION_ESTIMATE, or the plant's TENSION_TRUTH (all `TensionSample`, pull on the drone, FRD).
pub fn tension_topic(source: TensionSource) -> &'static str {
    match source {
        TensionSource::Sensor => names::TENSION,
        TensionSource::Estimator => names::TENSION_ESTIMATE,
        TensionSource::Truth => names::TENSION_TRUTH,
    }
}

/// The newest queued sample, if any (older ones are dropped).
fn drain_newest<T: taut_ipc::Stamped>(sub: &TopicSubscriber<T>, errors: &mut u64) -> Option<T> {
    let mut newest = None;
    if sub.drain(&mut |s| newest = Some(s)).is_err() {
        *errors += 1;
    }
    newest
}

fn step_and_publish(
    stage: &mut ControllerStage,
    inputs: &mut Inputs,
    ports: &mut Ports,
    record: &mut LatencyRecord,
    errors: &mut u64,
) {
    if let Some(t) = drain_newest(&ports.tensions, errors) {
        inputs.tension = Some(t);
    }
    if let Some(m) = drain_newest(&ports.missions, errors) {
        inputs.mission = Some(m);
    }
    let sp = stage.step(
        now_ns(),
        &inputs.state,
        inputs.tension.as_ref(),
        inputs.mission.as_ref(),
    );
    match ports.output.publish(sp) {
        Ok(header) => record.add(header.t_publish_ns, &sp),
        Err(_) => *errors += 1,
    }
}
