//! `taut replay RUN.mcap`: runs the controller library again on the inputs a recorded flight's
//! controller was handed, and checks that every recorded attitude setpoint comes out bit for
//! bit.
//!
//! Each recorded `AttitudeSetpoint` names its step time (`step_ns`) and the sequences of the
//! vehicle state, tension sample and mission setpoint handed to the step (`given_inputs`), so
//! the replay needs no clock and no guess about which sample the service had: it looks them up
//! by sequence. The controller is rebuilt from the drone's config as attached to the recording.
//! Bit for bit means the JSON text of every field, which for finite floats is their exact bits
//! (shortest round-trip notation both ways).

use std::collections::HashMap;
use std::path::PathBuf;

use controller::ControllerStage;
use recorder::{Recordable, Recording, Timed};
use rt_config::Config;
use serde_json::Value;
use shared_types::{
    given_inputs, names, AttitudeSetpoint, MissionSetpoint, TensionSample, VehicleState,
};

#[derive(clap::Args, Debug)]
pub struct ReplayArgs {
    /// The recording (`recording.mcap` in a `taut sim --out` folder).
    pub recording: PathBuf,
    /// Only this drone (default: every drone in the recording).
    #[arg(long)]
    pub uav: Option<String>,
}

/// Why a drone's flight cannot be replayed at all.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error("{0}")]
    Read(#[from] recorder::ReadError),
    #[error("the recording has no attachment {name}: the controller cannot be rebuilt")]
    NoConfig { name: String },
    #[error("the attached config {name} is invalid: {message}")]
    BadConfig { name: String, message: String },
    #[error("{uav}: no attitude setpoints recorded")]
    NoSetpoints { uav: String },
    #[error(
        "{uav}: the first recorded setpoint is number {sequence}, not 0: the controller's state \
         before it is unknown"
    )]
    LateStart { uav: String, sequence: u64 },
}

/// The first setpoint that did not come out the same.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// Setpoint sequence number and its step time.
    pub sequence: u64,
    pub step_ns: u64,
    /// What differs: a field path with both values, or a missing input.
    pub what: String,
}

/// One drone's replay.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayOutcome {
    pub uav: String,
    /// Setpoints replayed up to and including the first mismatch (all of them if none).
    pub steps: usize,
    pub first_mismatch: Option<Mismatch>,
}

/// Samples of one topic by their header sequence.
fn by_sequence<T: Recordable>(samples: Vec<Timed<T>>) -> HashMap<u64, T> {
    samples
        .into_iter()
        .map(|t| (t.sample.header().sequence, t.sample))
        .collect()
}

/// The topic the drone's controller takes its tension from.
pub fn controller_tension_topic(cfg: &Config) -> &'static str {
    controller::shell::tension_topic(cfg.controller.tension_source)
}

/// The drone's config as attached to the recording.
pub fn attached_config(rec: &Recording, uav: &str) -> Result<Config, ReplayError> {
    let name = recorder::format::config_attachment(uav);
    let bytes = rec
        .attachments
        .get(&name)
        .ok_or_else(|| ReplayError::NoConfig { name: name.clone() })?;
    let text = String::from_utf8_lossy(bytes);
    Config::from_toml_str(&text, &name).map_err(|e| ReplayError::BadConfig {
        name,
        message: e.to_string(),
    })
}

/// Replays `uav`'s controller over the whole recording.
pub fn replay_drone(rec: &Recording, uav: &str) -> Result<ReplayOutcome, ReplayError> {
    let cfg = attached_config(rec, uav)?;
    let mut stage = ControllerStage::new(&cfg.vehicle, &cfg.controller).map_err(|e| {
        ReplayError::BadConfig {
            name: recorder::format::config_attachment(uav),
            message: e.to_string(),
        }
    })?;
    let states = by_sequence(rec.samples::<VehicleState>(uav, names::VEHICLE_STATE)?);
    let tensions = by_sequence(rec.samples::<TensionSample>(uav, controller_tension_topic(&cfg))?);
    let missions = by_sequence(rec.samples::<MissionSetpoint>(uav, names::MISSION_SETPOINT)?);
    let mut setpoints: Vec<AttitudeSetpoint> = rec
        .samples::<AttitudeSetpoint>(uav, names::ATTITUDE_SETPOINT)?
        .into_iter()
        .map(|t| t.sample)
        .collect();
    setpoints.sort_by_key(|s| s.header.sequence);
    let first = setpoints.first().ok_or_else(|| ReplayError::NoSetpoints {
        uav: uav.to_string(),
    })?;
    if first.header.sequence != 0 {
        return Err(ReplayError::LateStart {
            uav: uav.to_string(),
            sequence: first.header.sequence,
        });
    }
    let mut outcome = ReplayOutcome {
        uav: uav.to_string(),
        steps: 0,
        first_mismatch: None,
    };
    for (expected_sequence, recorded) in (0u64..).zip(&setpoints) {
        outcome.steps += 1;
        let mismatch = |what: String| Mismatch {
            sequence: recorded.header.sequence,
            step_ns: recorded.step_ns,
            what,
        };
        if recorded.header.sequence != expected_sequence {
            // A lost setpoint: the controller stepped without us seeing its inputs.
            outcome.first_mismatch = Some(mismatch(format!(
                "setpoints {expected_sequence}..{} are not in the recording",
                recorded.header.sequence
            )));
            break;
        }
        match step_again(&mut stage, recorded, &states, &tensions, &missions) {
            Ok(replayed) => {
                if let Some(what) = first_difference(recorded, &replayed) {
                    outcome.first_mismatch = Some(mismatch(what));
                    break;
                }
            }
            Err(what) => {
                outcome.first_mismatch = Some(mismatch(what));
                break;
            }
        }
    }
    Ok(outcome)
}

/// Runs the step again on the inputs `recorded` names; `Err` names an input not recorded.
fn step_again(
    stage: &mut ControllerStage,
    recorded: &AttitudeSetpoint,
    states: &HashMap<u64, VehicleState>,
    tensions: &HashMap<u64, TensionSample>,
    missions: &HashMap<u64, MissionSetpoint>,
) -> Result<AttitudeSetpoint, String> {
    let bits = recorded.given_inputs;
    let state = given(
        bits & given_inputs::ODOMETRY != 0,
        recorded.odometry_sequence,
        states,
        "vehicle state",
    )?
    .copied()
    .unwrap_or_else(VehicleState::before_first_odometry);
    let tension = given(
        bits & given_inputs::TENSION != 0,
        recorded.given_tension_sequence,
        tensions,
        "tension sample",
    )?;
    let mission = given(
        bits & given_inputs::MISSION != 0,
        recorded.given_mission_sequence,
        missions,
        "mission setpoint",
    )?;
    let mut out = stage.step(recorded.step_ns, &state, tension, mission);
    // Stamped by the publisher, not computed by the step.
    out.header.sequence = recorded.header.sequence;
    out.header.t_publish_ns = recorded.header.t_publish_ns;
    Ok(out)
}

/// The sample numbered `sequence` if the step was handed one; `Err` if it is not recorded.
fn given<'a, T>(
    handed: bool,
    sequence: u64,
    by_sequence: &'a HashMap<u64, T>,
    what: &str,
) -> Result<Option<&'a T>, String> {
    if !handed {
        return Ok(None);
    }
    by_sequence
        .get(&sequence)
        .map(Some)
        .ok_or_else(|| format!("input {what} {sequence} is not in the recording"))
}

/// The first field whose JSON text differs, as `path: recorded X, replayed Y`.
pub fn first_difference(
    recorded: &AttitudeSetpoint,
    replayed: &AttitudeSetpoint,
) -> Option<String> {
    let a = serde_json::to_value(recorded).ok()?;
    let b = serde_json::to_value(replayed).ok()?;
    diff_value(&a, &b, String::new())
}

fn diff_value(a: &Value, b: &Value, path: String) -> Option<String> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => x.iter().find_map(|(k, va)| {
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            match y.get(k) {
                Some(vb) => diff_value(va, vb, p),
                None => Some(format!("{p}: missing in the replay")),
            }
        }),
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (va, vb))| diff_value(va, vb, format!("{path}[{i}]"))),
        // Leaves compare by their JSON text: for floats that is their exact bits.
        _ => (serde_json::to_string(a).ok() != serde_json::to_string(b).ok())
            .then(|| format!("{path}: recorded {a}, replayed {b}")),
    }
}

/// The command: replays every drone (or `--uav`), prints the outcome, fails on a mismatch.
pub fn run(args: &ReplayArgs) -> Result<(), String> {
    let rec = Recording::open(&args.recording).map_err(|e| e.to_string())?;
    if rec.truncated {
        eprintln!(
            "{}: the recording was cut short; replaying what it holds",
            args.recording.display()
        );
    }
    let uavs = match &args.uav {
        Some(u) => vec![u.clone()],
        None => rec.uavs(),
    };
    if uavs.is_empty() {
        return Err(format!(
            "{}: no drone in the recording",
            args.recording.display()
        ));
    }
    let mut failed = Vec::new();
    for uav in &uavs {
        let o = replay_drone(&rec, uav).map_err(|e| e.to_string())?;
        match &o.first_mismatch {
            None => println!("{uav}: {} setpoints replayed, all bit for bit", o.steps),
            Some(m) => {
                println!(
                    "{uav}: first mismatch at setpoint {} (step {:.3} s, {} replayed): {}",
                    m.sequence,
                    m.step_ns as f64 * 1e-9,
                    o.steps,
                    m.what
                );
                failed.push(uav.clone());
            }
        }
    }
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!("replay differs for {}", failed.join(", ")))
    }
}

#[cfg(test)]
#[path = "replay_tests.rs"]
mod tests;
