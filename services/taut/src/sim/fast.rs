//! `taut sim --fast`: the whole flight in one process, in simulated time. The plant is the same
//! `Plant` the real-time process steps; per drone the same library code as the services runs:
//! the tension stage, the cascade controller, the mission's phase machine, and the bridge's
//! offboard link, which exchanges the very MAVLink messages it would put on the wire with the
//! plant's emulated PX4 (in memory, no encoding). Peer signals go from one mission to the other
//! directly.
//!
//! Where it differs from the real-time run (and so what the comparison's tolerance covers):
//! - The force sensor's four chips are read at the sampler's nominal 240 Hz at the instant of
//!   each frame, not through the sampler's edge-tracking I2C schedule; a chip not ready yet is
//!   marked stale, as the sampler does.
//! - No scheduling or IPC delays: a stage's output is seen by the next at the same simulated
//!   instant (the real-time latencies are tens of µs to a few ms, see the summary).
//! - The plant's clock is the only clock: every `t_origin_ns` is simulated time.
//!
//! The baselines run here as in real time: the force estimator is fed the bridge's IMU and
//! motor-speed telemetry (at the rates the bridge asks for), the plant's true anchor force is
//! a TensionSample every 2 ms (TENSION_TRUTH), and each controller takes the source and law of
//! its config (`taut sim --law / --tension-source`).

use super::fast_record::{FastRecording, FastTopic};
use super::force_metrics::ForceSource;
use super::metrics::MetricsRecorder;
use super::summary::Summary;
use super::trace::Trace;
use super::{new_recorder, Outcome, SimArgs};
use adc_sampler::mcp3423::{Reading, SampleRate};
use controller::ControllerStage;
use force_estimator::ForceEstimator;
use mission::{MissionStage, PeerSignal};
use px4_bridge::mavlink::dialects::common::MavMessage;
use px4_bridge::mavlink::MavHeader;
use px4_bridge::{OffboardLink, Telemetry};
use rt_config::{Config, TensionSource};
use shared_types::{
    AttitudeSetpoint, ChannelStatus, MissionSetpoint, RawAdcFrame, SamplingMode, TensionSample,
    VehicleState,
};
use sim_plant::mavlink_link::{outbound, LinkConfig, Stream, StreamSchedule};
use sim_plant::plant::{Plant, PlantConfig};
use sim_plant::scenario::Scenario;
use sim_plant::sensor::{BusConfig, LoadProfile, SensorBus, SensorModel, SensorParams};
use std::time::Instant;
use tension::{TensionStage, TensionStageConfig};

/// MAV_CMD_SET_MESSAGE_INTERVAL: answered by the link layer, as the plant's endpoint does.
const MAV_CMD_SET_MESSAGE_INTERVAL: u16 = 511;
/// The sensor is driven by the anchor force with a 1 ms zero-order hold, as in real time.
const SENSOR_HOLD_NS: u64 = 1_000_000;
/// The plant publishes its truth at 100 Hz in real time; the metrics see it at the same rate.
const TRUTH_PERIOD_NS: u64 = 10_000_000;
use crate::plant_cmd::TRUTH_TENSION_PERIOD_NS;

#[path = "fast_link.rs"]
mod link;

/// One drone's companion side, in process.
struct FastDrone {
    cfg: Config,
    sensor: SensorBus,
    tension: TensionStage,
    controller: ControllerStage,
    mission: MissionStage,
    link: OffboardLink,
    /// The plant side of the link: which streams are due (SET_MESSAGE_INTERVAL changes it).
    streams: StreamSchedule,
    plant_link: LinkConfig,
    frame_period_ns: u64,
    next_frame_ns: u64,
    last_codes: [i16; 4],
    newest_tension: Option<TensionSample>,
    estimator: ForceEstimator,
    newest_estimate: Option<TensionSample>,
    /// Estimates made since the metrics last saw them (at most one per IMU message).
    estimate_pending: bool,
    newest_truth_tension: Option<TensionSample>,
    newest_state: Option<VehicleState>,
    newest_mission: Option<MissionSetpoint>,
    state_pending: bool,
    next_mission_ns: u64,
    mission_period_ns: u64,
    last_signal: Option<PeerSignal>,
    controller_period_ns: u64,
    next_controller_ns: u64,
    /// The bridge's own messages of one tick (heartbeat, handshake, message intervals).
    outbox: Vec<MavMessage>,
}

impl FastDrone {
    fn new(cfg: Config, scenario: &Scenario, k: usize, seed: u64) -> Result<Self, String> {
        let model = SensorModel::new(SensorParams::default()).map_err(|e| e.to_string())?;
        let sensor = SensorBus::new(
            BusConfig::default(),
            model,
            LoadProfile::Constant([0.0; 3]),
            0,
            seed.wrapping_mul(2).wrapping_add(k as u64),
        )
        .map_err(|e| e.to_string())?;
        let controller = ControllerStage::new(&cfg.vehicle, &cfg.controller)
            .map_err(|e| format!("{}: {e}", cfg.uav))?;
        let mission = MissionStage::new(scenario, k, &cfg.mission)
            .map_err(|e| format!("{}: {e}", cfg.uav))?;
        let link =
            OffboardLink::new(&cfg.px4, &cfg.vehicle).map_err(|e| format!("{}: {e}", cfg.uav))?;
        let estimator = ForceEstimator::new(&cfg.vehicle, &cfg.estimator)
            .map_err(|e| format!("{}: {e}", cfg.uav))?;
        let plant_link = LinkConfig::px4_sitl(k as u8);
        Ok(FastDrone {
            tension: TensionStage::new(TensionStageConfig::from_config(&cfg)),
            streams: StreamSchedule::new(&plant_link.rates),
            plant_link,
            frame_period_ns: (1e9 / cfg.sensor.rate_hz).round() as u64,
            next_frame_ns: 0,
            last_codes: [0; 4],
            newest_tension: None,
            estimator,
            newest_estimate: None,
            estimate_pending: false,
            newest_truth_tension: None,
            newest_state: None,
            newest_mission: None,
            state_pending: false,
            mission_period_ns: (1e9 / cfg.mission.rate_hz).round() as u64,
            next_mission_ns: 0,
            last_signal: None,
            controller_period_ns: (1e9 / cfg.controller.rate_hz).round() as u64,
            next_controller_ns: 0,
            outbox: Vec::with_capacity(16),
            sensor,
            controller,
            mission,
            link,
            cfg,
        })
    }

    /// Reads the four chips at `t_ns` like one sampler frame, and runs the tension stage.
    fn sample_sensor(&mut self, k: usize, t_ns: u64, out: &mut FastRecording) {
        let addresses = self.cfg.sensor.addresses;
        let mut frame = RawAdcFrame {
            mode: SamplingMode::Continuous,
            ..Default::default()
        };
        for (c, addr) in addresses.iter().enumerate() {
            let mut buf = [0u8; 3];
            let read = self.sensor.read(*addr, &mut buf, t_ns);
            let reading = read
                .ok()
                .and_then(|_| Reading::decode(SampleRate::Sps240Bits12, &buf));
            frame.status[c] = match reading {
                Some(r) if r.ready => {
                    self.last_codes[c] = r.code as i16;
                    if r.saturated {
                        ChannelStatus::Saturated
                    } else {
                        ChannelStatus::Fresh
                    }
                }
                Some(_) => ChannelStatus::Stale,
                None => ChannelStatus::BusError,
            };
            frame.codes[c] = self.last_codes[c];
            // The code integrates the conversion that just ended: its middle is half a period back.
            frame.conversion_ns[c] = t_ns.saturating_sub(self.frame_period_ns / 2);
        }
        frame.header.t_origin_ns = t_ns.saturating_sub(self.frame_period_ns / 2);
        out.publish(k, FastTopic::RawAdc, t_ns, &mut frame);
        let mut s = self.tension.process(&frame);
        out.publish(k, FastTopic::Tension, t_ns, &mut s);
        self.newest_tension = Some(s);
    }

    /// A message from the emulated PX4 to the bridge.
    fn deliver_to_bridge(
        &mut self,
        k: usize,
        t_ns: u64,
        msg: &MavMessage,
        out: &mut FastRecording,
    ) {
        let header = MavHeader {
            system_id: u32::from(self.plant_link.system_id),
            component_id: self.plant_link.component_id,
            sequence: 0,
        };
        match self.link.on_message(t_ns, &header, msg) {
            Some(Telemetry::State(mut s)) => {
                out.publish(k, FastTopic::VehicleState, t_ns, &mut s);
                self.newest_state = Some(s);
                self.state_pending = true;
            }
            Some(Telemetry::Imu(mut s)) => {
                out.publish(k, FastTopic::Imu, t_ns, &mut s);
                let mut e = self.estimator.on_imu(&s);
                out.publish(k, FastTopic::TensionEstimate, t_ns, &mut e);
                self.newest_estimate = Some(e);
                self.estimate_pending = true;
            }
            Some(Telemetry::Motors(mut m)) => {
                out.publish(k, FastTopic::MotorSpeeds, t_ns, &mut m);
                self.estimator.on_motor_speeds(&m);
            }
            None => {}
        }
    }

    /// The newest sample of the controller's tension source (`controller.tension_source`).
    fn tension_for_controller(&self) -> Option<&TensionSample> {
        match self.cfg.controller.tension_source {
            TensionSource::Sensor => self.newest_tension.as_ref(),
            TensionSource::Estimator => self.newest_estimate.as_ref(),
            TensionSource::Truth => self.newest_truth_tension.as_ref(),
        }
    }
}

/// Flies `scenario` in simulated time; with `recording`, writes every sample there (MCAP).
pub fn run(
    args: &SimArgs,
    scenario: &Scenario,
    recording: Option<&std::path::Path>,
) -> Result<Summary, String> {
    let plant_cfg = PlantConfig {
        seed: args.seed,
        perturbation_enabled: !args.no_noise,
        ..PlantConfig::default()
    };
    let mut plant = Plant::new(scenario, &plant_cfg).map_err(|e| e.to_string())?;
    let ports = super::setup::Ports {
        mavlink_remote_base: 14540,
        mavlink_local_base: 14580,
        zenoh: [7447, 7448],
    };
    let mut drones = Vec::new();
    let mut texts = Vec::new();
    for k in 0..2 {
        let mut cfg = super::setup::drone_config(
            &args.scenario,
            scenario,
            k,
            "fast",
            std::path::Path::new("/nonexistent"),
            &ports,
        );
        super::apply_baselines(args, &mut cfg);
        // Fly the config as its TOML reads back: the recording attaches that text, and a
        // replay rebuilds the controller from it.
        let text = cfg.to_toml();
        let cfg = Config::from_toml_str(&text, &cfg.uav).map_err(|e| e.to_string())?;
        texts.push(text);
        drones.push(FastDrone::new(cfg, scenario, k, args.seed)?);
    }
    let mut out = match recording {
        Some(path) => {
            let uavs = [drones[0].cfg.uav.as_str(), drones[1].cfg.uav.as_str()];
            FastRecording::create(path, &uavs, &texts)
                .map_err(|e| format!("{}: {e}", path.display()))?
        }
        None => FastRecording::stamp_only(drones.len()),
    };
    let mut rec = new_recorder(scenario);
    let mut outcome = Outcome::default();
    let limit_ns = (args.time_limit_s(scenario) * 1e9) as u64;
    let wall = Instant::now();
    let mut next_truth_ns = 0;
    let mut next_hold_ns = 0;
    let mut next_truth_tension_ns = 0;
    let mut trace = match &args.trace {
        Some(p) => Some(Trace::create(p)?),
        None => None,
    };
    while plant.time_ns() < limit_ns {
        plant.step();
        let t = plant.time_ns();
        fly_companions(
            &mut plant,
            &mut drones,
            (&mut rec, &mut out),
            t,
            (&mut next_hold_ns, &mut next_truth_tension_ns),
            &mut trace,
            args.quiet,
        );
        if t >= next_truth_ns {
            next_truth_ns += TRUTH_PERIOD_NS;
            let mut truth = plant.truth();
            truth.header.t_origin_ns = t;
            out.publish_truth(t, &mut truth);
            rec.on_truth(&truth);
            outcome.sim_s = t as f64 * 1e-9;
            outcome.observe_truth(&truth);
            outcome.observe_missions(&[drones[0].newest_mission, drones[1].newest_mission]);
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
    if outcome.failure.is_none() && outcome.done_at_s.is_none() {
        outcome.fail(format!("no end after {:.0} s", limit_ns as f64 * 1e-9));
    }
    if let Err(e) = out.finish() {
        outcome.fail(format!("recording: {e}"));
    }
    Ok(outcome.summary(args, scenario, "fast", &rec, wall.elapsed().as_secs_f64()))
}

/// Everything the companions do at plant time `t`.
fn fly_companions(
    plant: &mut Plant,
    drones: &mut [FastDrone],
    (rec, out): (&mut MetricsRecorder, &mut FastRecording),
    t: u64,
    (next_hold_ns, next_truth_tension_ns): (&mut u64, &mut u64),
    trace: &mut Option<Trace>,
    quiet: bool,
) {
    let drive_sensor = t >= *next_hold_ns;
    if drive_sensor {
        *next_hold_ns += SENSOR_HOLD_NS;
    }
    let publish_truth = t >= *next_truth_tension_ns;
    if publish_truth {
        *next_truth_tension_ns += TRUTH_TENSION_PERIOD_NS;
    }
    for (k, d) in drones.iter_mut().enumerate() {
        if drive_sensor {
            d.sensor.advance_to(t);
            d.sensor
                .set_profile(LoadProfile::Constant(plant.anchor_force_frd(k)), 0);
        }
        if publish_truth {
            let mut s = crate::plant_cmd::truth_tension(plant, k, t);
            out.publish(k, FastTopic::TensionTruth, t, &mut s);
            rec.on_force_truth(k, &s);
            d.newest_truth_tension = Some(s);
        }
        if t >= d.next_frame_ns {
            d.next_frame_ns += d.frame_period_ns;
            d.sample_sensor(k, t, out);
            if let Some(s) = &d.newest_tension {
                rec.on_force_sample(k, ForceSource::Sensor, s);
            }
        }
        // Telemetry the emulated PX4 streams now.
        let tel = plant.telemetry(k);
        for stream in Stream::ALL {
            if d.streams.take_due(stream, t) {
                let msg = match stream {
                    Stream::Heartbeat => outbound::heartbeat(&tel),
                    s => outbound::stream_message(s, &tel),
                };
                d.deliver_to_bridge(k, t, &msg, out);
            }
        }
        // The bridge's own traffic: heartbeats, the handshake, message intervals.
        d.link
            .poll(t, &mut |m: &MavMessage| d.outbox.push(m.clone()));
        let mut outbox = std::mem::take(&mut d.outbox);
        for m in outbox.drain(..) {
            d.deliver_to_plant(plant, k, t, &m, out);
        }
        // Keep the buffer's capacity for the next tick.
        d.outbox = outbox;
        if d.estimate_pending {
            d.estimate_pending = false;
            if let Some(e) = &d.newest_estimate {
                rec.on_force_sample(k, ForceSource::Estimator, e);
            }
        }
    }
    // Missions at their rate, each seeing the other's newest signal.
    for k in 0..2 {
        if t < drones[k].next_mission_ns {
            continue;
        }
        drones[k].next_mission_ns += drones[k].mission_period_ns;
        let peer_signal = drones[1 - k].last_signal;
        let d = &mut drones[k];
        let step = d.mission.step(
            t,
            d.newest_state.as_ref(),
            peer_signal.as_ref().map(|s| (s, t)),
        );
        let mut sp = step.setpoint;
        out.publish(k, FastTopic::MissionSetpoint, t, &mut sp);
        d.newest_mission = Some(sp);
        d.last_signal = Some(step.signal);
        if let Some((i, name, ts)) = rec.on_mission(k, &sp).filter(|_| !quiet) {
            println!(
                "[sim] drone {} phase {i} {name} started at {ts:.2} s",
                k + 1
            );
        }
    }
    // Controllers: on odometry, or on their deadline when it is late (as the service does).
    for (k, d) in drones.iter_mut().enumerate() {
        let due = d.state_pending || t >= d.next_controller_ns + d.controller_period_ns / 2;
        if !due
            || t < d
                .next_controller_ns
                .saturating_sub(d.controller_period_ns / 2)
        {
            continue;
        }
        let Some(state) = d.newest_state else {
            continue;
        };
        d.state_pending = false;
        d.next_controller_ns = t + d.controller_period_ns;
        let tension = d.tension_for_controller().copied();
        let mut sp: AttitudeSetpoint =
            d.controller
                .step(t, &state, tension.as_ref(), d.newest_mission.as_ref());
        out.publish(k, FastTopic::AttitudeSetpoint, t, &mut sp);
        rec.on_setpoint(k, &sp, false);
        if let Some(tr) = trace.as_mut() {
            tr.row(t, k, &state, &sp, &plant.truth());
        }
        if let Some(msg) = d.link.on_setpoint(t, &sp) {
            d.deliver_to_plant(plant, k, t, &msg, out);
        }
    }
}
