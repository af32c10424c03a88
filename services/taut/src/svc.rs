//! Service processes: thin shells that apply real-time settings, open their topics and feed
//! the pure step code until SIGINT/SIGTERM.

use adc_sampler::mcp3423::Mcp3423;
use adc_sampler::{Clock, Sampler, SamplerSettings};
use clap::{Args, ValueEnum};
use embedded_hal::i2c::I2c;
use rt_config::{periodic, Config, SamplingModeConfig, ServiceRt};
use shared_types::{names, RawAdcFrame, SamplingMode, TensionSample};
use sim_plant::sensor::{BusConfig, BusServer, Faults, ForcedInput, LoadProfile, SensorBus};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Duration;
use taut_ipc::{install_stop_handler, stop_requested, Ipc};
use tension::{TensionStage, TensionStageConfig};

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ServiceName {
    /// Reads the four MCP3423s, publishes RawAdcFrame.
    AdcSampler,
    /// RawAdcFrame -> TensionSample.
    Tension,
    /// The emulated force sensor: serves four MCP3423s on a Unix socket.
    SimSensor,
    /// VehicleState + TensionSample + MissionSetpoint -> AttitudeSetpoint (paper IV).
    Controller,
    /// Scenario phases agreed with the peer drone over zenoh -> MissionSetpoint.
    Mission,
    /// MAVLink link to PX4: AttitudeSetpoint -> SET_ATTITUDE_TARGET, telemetry -> VehicleState.
    Px4Bridge,
    /// Every topic of the drone -> an MCAP file in `recorder.dir` (not real-time).
    Recorder,
    /// ImuSample + MotorSpeeds -> TensionSample on TENSION_ESTIMATE (the paper's baseline).
    ForceEstimator,
}

impl ServiceName {
    pub fn as_str(self) -> &'static str {
        match self {
            ServiceName::AdcSampler => "adc-sampler",
            ServiceName::Tension => "tension",
            ServiceName::SimSensor => "sim-sensor",
            ServiceName::Controller => "controller",
            ServiceName::Mission => "mission",
            ServiceName::Px4Bridge => "px4-bridge",
            ServiceName::Recorder => "recorder",
            ServiceName::ForceEstimator => "force-estimator",
        }
    }
}

#[derive(Args, Debug)]
pub struct SvcArgs {
    pub name: ServiceName,
    /// Drone config (adc-sampler, tension).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// (recorder) Create this file once subscribed to every topic.
    #[arg(long)]
    pub ready: Option<PathBuf>,
    #[command(flatten)]
    pub sim: SimSensorArgs,
}

/// Options of the emulated sensor (`svc sim-sensor`, and `taut sensor --sim`).
#[derive(Args, Debug, Clone, Default)]
pub struct SimSensorArgs {
    /// Socket to serve the emulated I2C bus on.
    #[arg(long)]
    pub socket: Option<PathBuf>,
    /// Constant load: the cable's pull on the drone in body FRD, N ("0,0,9.81" hangs 1 kg).
    #[arg(long, allow_hyphen_values = true)]
    pub load: Option<String>,
    /// Load profile file (TOML or CSV t,fx,fy,fz; see README).
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// CLOCK_MONOTONIC time (ns) at which the profile's t = 0 falls.
    #[arg(long)]
    pub t0_ns: Option<u64>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// An ideal sensor (no gain errors, crossload, non-linearity, hysteresis or noise).
    #[arg(long)]
    pub ideal_sensor: bool,
    /// Faults: nack:CHIP:P, stuck:CHIP, silent:CHIP, saturate:CHIP (CHIP 1..4); repeatable.
    #[arg(long = "fault")]
    pub faults: Vec<String>,
}

pub fn run(args: &SvcArgs) -> Result<(), String> {
    install_stop_handler();
    match args.name {
        ServiceName::SimSensor => run_sim_sensor(&args.sim),
        // Applies cfg.services.controller itself.
        ServiceName::Controller => {
            controller::shell::run(&crate::load_config(args.config.as_deref())?)
        }
        // The shell applies cfg.services.mission itself.
        ServiceName::Mission => mission::shell::run(&crate::load_config(args.config.as_deref())?),
        // Applies cfg.services.px4_bridge itself (before starting its threads).
        ServiceName::Px4Bridge => {
            px4_bridge::shell::run(&crate::load_config(args.config.as_deref())?)
        }
        ServiceName::Recorder => recorder::shell::run_with_ready(
            &crate::load_config(args.config.as_deref())?,
            args.ready.as_deref(),
        ),
        // Applies cfg.services.force_estimator itself.
        ServiceName::ForceEstimator => {
            force_estimator::shell::run(&crate::load_config(args.config.as_deref())?)
        }
        name => {
            let cfg = crate::load_config(args.config.as_deref())?;
            let rt = match name {
                ServiceName::AdcSampler => cfg.services.adc_sampler,
                _ => cfg.services.tension,
            };
            apply_rt(name.as_str(), &rt)?;
            match name {
                ServiceName::AdcSampler => run_sampler(&cfg),
                _ => run_tension(&cfg),
            }
        }
    }
}

fn apply_rt(service: &str, rt: &ServiceRt) -> Result<(), String> {
    let report = rt_config::rt::apply(rt).map_err(|e| format!("{service}: {e}"))?;
    eprintln!("[{service}] real-time: {report}");
    Ok(())
}

fn node_name(cfg: &Config, service: &str) -> String {
    format!("{}-{}", cfg.uav, service)
}

/// CLOCK_MONOTONIC and clock_nanosleep.
pub struct MonotonicClock;

impl Clock for MonotonicClock {
    fn now_ns(&mut self) -> u64 {
        periodic::now_ns()
    }
    fn sleep_until_ns(&mut self, t_ns: u64) {
        periodic::sleep_until_ns(t_ns)
    }
}

fn run_sampler(cfg: &Config) -> Result<(), String> {
    let s = &cfg.sensor;
    let mode = match s.mode {
        SamplingModeConfig::Continuous => SamplingMode::Continuous,
        SamplingModeConfig::Synchronous => SamplingMode::Synchronous,
    };
    let settings = SamplerSettings::new(mode, s.rate_hz, s.bus_retries);
    if let Some(path) = s.bus.strip_prefix("sim:") {
        let open = || {
            sim_plant::sensor::SimI2c::connect(path)
                .map_err(|e| format!("sensor.bus = {:?}: cannot connect: {e}", s.bus))
        };
        let chips = open_chips(&s.addresses, open)?;
        sample_loop(cfg, Sampler::new(chips, open()?, settings))
    } else {
        let open = || {
            linux_embedded_hal::I2cdev::new(&s.bus)
                .map_err(|e| format!("sensor.bus = {:?}: cannot open: {e}", s.bus))
        };
        let chips = open_chips(&s.addresses, open)?;
        sample_loop(cfg, Sampler::new(chips, open()?, settings))
    }
}

/// One bus handle per chip (linux_embedded_hal reopens the device when the address changes).
fn open_chips<I: I2c>(
    addresses: &[u8; 4],
    mut open: impl FnMut() -> Result<I, String>,
) -> Result<[Mcp3423<I>; 4], String> {
    let mut chips = Vec::with_capacity(4);
    for (j, &a) in addresses.iter().enumerate() {
        let chip = Mcp3423::new(open()?, a).map_err(|e| format!("sensor.addresses[{j}]: {e}"))?;
        chips.push(chip);
    }
    chips
        .try_into()
        .map_err(|_| "four chips expected".to_string())
}

fn sample_loop<I: I2c>(cfg: &Config, mut sampler: Sampler<I>) -> Result<(), String> {
    let ipc = Ipc::new(&node_name(cfg, "adc-sampler"), &cfg.ipc_root, &cfg.uav)
        .map_err(|e| e.to_string())?;
    let mut publisher = ipc
        .publisher::<RawAdcFrame>(names::RAW_ADC)
        .map_err(|e| e.to_string())?;
    let mut clock = MonotonicClock;
    sampler.start(&mut clock);
    let mut send_errors = 0u64;
    while !stop_requested() {
        let frame = sampler.next_frame(&mut clock);
        if publisher.publish(frame).is_err() {
            send_errors += 1;
        }
    }
    let c = sampler.counters();
    eprintln!(
        "[adc-sampler] stopped: frames={} bus_errors={} degraded_frames={} not_ready_polls={} send_errors={send_errors}",
        c.frames, c.bus_errors, c.degraded_frames, c.not_ready_polls
    );
    Ok(())
}

fn run_tension(cfg: &Config) -> Result<(), String> {
    let ipc =
        Ipc::new(&node_name(cfg, "tension"), &cfg.ipc_root, &cfg.uav).map_err(|e| e.to_string())?;
    let input = ipc
        .subscriber::<RawAdcFrame>(names::RAW_ADC)
        .map_err(|e| e.to_string())?;
    let mut output = ipc
        .publisher::<TensionSample>(names::TENSION)
        .map_err(|e| e.to_string())?;
    let mut stage = TensionStage::new(TensionStageConfig::from_config(cfg));
    if stage.config().calibration.is_missing() {
        eprintln!("[tension] no [calibration] in the config: nominal constants, samples flagged");
    }
    let (mut samples, mut errors) = (0u64, 0u64);
    while !stop_requested() {
        let r = input.wait_and_drain(Duration::from_millis(100), |frame| {
            samples += 1;
            if output.publish(stage.process(&frame)).is_err() {
                errors += 1;
            }
        });
        // A stop signal interrupts the wait: that is not an error.
        if r.is_err() && !stop_requested() {
            errors += 1;
        }
    }
    eprintln!("[tension] stopped: samples={samples} errors={errors}");
    Ok(())
}

/// Parses `--fault` specs into the bus's fault set.
pub fn parse_faults(specs: &[String]) -> Result<Faults, String> {
    let mut f = Faults::default();
    for spec in specs {
        let parts: Vec<&str> = spec.split(':').collect();
        let chip = |s: Option<&&str>| -> Result<usize, String> {
            match s.and_then(|c| c.parse::<usize>().ok()) {
                Some(c @ 1..=4) => Ok(c - 1),
                _ => Err(format!("--fault {spec:?}: CHIP must be 1..4")),
            }
        };
        match parts[0] {
            "nack" => {
                let c = chip(parts.get(1))?;
                let p = parts
                    .get(2)
                    .and_then(|p| p.parse::<f64>().ok())
                    .filter(|p| (0.0..=1.0).contains(p))
                    .ok_or_else(|| {
                        format!("--fault {spec:?}: expected nack:CHIP:P with P in 0..1")
                    })?;
                f.nack_probability[c] = p;
            }
            "stuck" => f.stuck[chip(parts.get(1))?] = true,
            "silent" => f.silent[chip(parts.get(1))?] = true,
            "saturate" => f.forced_input[chip(parts.get(1))?] = Some(ForcedInput::RailHigh),
            other => {
                return Err(format!(
                    "--fault {spec:?}: unknown fault {other:?} (nack, stuck, silent, saturate)"
                ));
            }
        }
    }
    Ok(f)
}

/// The load a sim-sensor applies, from `--load` or `--profile` (default: nothing hanging).
pub fn load_profile(args: &SimSensorArgs) -> Result<LoadProfile, String> {
    match (&args.load, &args.profile) {
        (Some(_), Some(_)) => Err("give --load or --profile, not both".into()),
        (Some(l), None) => LoadProfile::from_cli(l).map_err(|e| format!("--load: {e}")),
        (None, Some(p)) => LoadProfile::from_file(p).map_err(|e| format!("--profile: {e}")),
        (None, None) => Ok(LoadProfile::Constant([0.0; 3])),
    }
}

fn run_sim_sensor(args: &SimSensorArgs) -> Result<(), String> {
    let socket = args
        .socket
        .clone()
        .ok_or("sim-sensor needs --socket PATH")?;
    let profile = load_profile(args)?;
    let model = if args.ideal_sensor {
        sim_plant::sensor::SensorModel::ideal()
    } else {
        sim_plant::sensor::SensorModel::new(sim_plant::sensor::SensorParams::default())
            .map_err(|e| e.to_string())?
    };
    let t0 = args.t0_ns.unwrap_or_else(periodic::now_ns);
    let mut bus = SensorBus::new(BusConfig::default(), model, profile, t0, args.seed)
        .map_err(|e| e.to_string())?;
    bus.set_faults(parse_faults(&args.faults)?, periodic::now_ns());
    let server = BusServer::bind(&socket, bus)
        .map_err(|e| format!("cannot serve on {}: {e}", socket.display()))?;
    static STOP: AtomicBool = AtomicBool::new(false);
    std::thread::spawn(|| {
        while !stop_requested() {
            std::thread::sleep(Duration::from_millis(20));
        }
        STOP.store(true, std::sync::atomic::Ordering::SeqCst);
    });
    server
        .serve(&STOP)
        .map_err(|e| format!("sim-sensor on {}: {e}", socket.display()))?;
    let counters = server
        .bus()
        .lock()
        .map(|b| b.counters())
        .unwrap_or_default();
    eprintln!("[sim-sensor] stopped: {counters:?}");
    Ok(())
}
