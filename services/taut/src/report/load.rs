//! A recording loaded for the report: every channel the report knows, decoded message by
//! message (one undecodable message is counted and skipped, it does not hide the channel), and
//! a list of what is absent.

use recorder::format::{schema_name, Recordable, META_RECORDING};
use recorder::{Recording, Timed};
use shared_types::names;
use shared_types::{
    AttitudeSetpoint, ImuSample, MissionSetpoint, MotorSpeeds, PlantTruth, RawAdcFrame,
    TensionSample, VehicleState,
};
use std::path::{Path, PathBuf};

use super::ReportError;

/// The 8 bytes every MCAP file starts with.
/// One drone's channels.
#[derive(Debug, Clone, Default)]
pub struct DroneData {
    pub id: String,
    /// Index of this drone in the plant's truth (`PlantTruth::drones[k]`).
    pub truth_index: usize,
    pub raw_adc: Vec<Timed<RawAdcFrame>>,
    pub tension: Vec<Timed<TensionSample>>,
    pub tension_estimate: Vec<Timed<TensionSample>>,
    pub tension_truth: Vec<Timed<TensionSample>>,
    pub vehicle_state: Vec<Timed<VehicleState>>,
    pub imu: Vec<Timed<ImuSample>>,
    pub motor_speeds: Vec<Timed<MotorSpeeds>>,
    pub mission: Vec<Timed<MissionSetpoint>>,
    pub attitude: Vec<Timed<AttitudeSetpoint>>,
}

/// What the report reads from one recording.
#[derive(Debug, Clone, Default)]
pub struct FlightData {
    pub path: PathBuf,
    pub drones: Vec<DroneData>,
    pub truth: Vec<Timed<PlantTruth>>,
    /// `mode` of the `taut.recording` metadata (`realtime` | `fast`), if recorded.
    pub mode: Option<String>,
    /// The recording ended before its footer: read up to its last complete record.
    pub truncated: bool,
    /// Drone id -> its effective config (TOML) from the `config/<uav>.toml` attachment.
    pub configs: Vec<(String, String)>,
    /// Per-channel samples lost to sequence gaps (`taut.drops`), as recorded.
    pub drops: Vec<(String, String)>,
    /// Human-readable notes: absent channels, undecodable messages, fallbacks taken.
    pub notes: Vec<String>,
    /// Origin of the time axis: the earliest sample time of any channel, ns.
    pub t0_ns: u64,
}

impl FlightData {
    pub fn open(path: &Path) -> Result<Self, ReportError> {
        let rec = Recording::open(path).map_err(|e| ReportError::Read {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        Ok(Self::from_recording(&rec, path))
    }

    /// Everything the report needs from `rec`; never fails: absences become notes.
    pub fn from_recording(rec: &Recording, path: &Path) -> Self {
        let mut notes = Vec::new();
        if rec.truncated {
            notes.push("the recording ends before its footer (a crash?): read up to its last complete chunk".into());
        }
        let mut ids = rec.uavs();
        ids.sort();
        if ids.is_empty() {
            notes.push("no drone channel in the recording".into());
        }
        let drones: Vec<DroneData> = ids
            .iter()
            .enumerate()
            .map(|(k, id)| DroneData {
                id: id.clone(),
                truth_index: k.min(1),
                raw_adc: decode(rec, id, names::RAW_ADC, &mut notes),
                tension: decode(rec, id, names::TENSION, &mut notes),
                tension_estimate: decode(rec, id, names::TENSION_ESTIMATE, &mut notes),
                tension_truth: decode(rec, id, names::TENSION_TRUTH, &mut notes),
                vehicle_state: decode(rec, id, names::VEHICLE_STATE, &mut notes),
                imu: decode(rec, id, names::IMU, &mut notes),
                motor_speeds: decode(rec, id, names::MOTOR_SPEEDS, &mut notes),
                mission: decode(rec, id, names::MISSION_SETPOINT, &mut notes),
                attitude: decode(rec, id, names::ATTITUDE_SETPOINT, &mut notes),
            })
            .collect();
        if ids.len() > 2 {
            notes.push(format!(
                "{} drones recorded; the plant's truth holds two: drones after the second use its index 1",
                ids.len()
            ));
        }
        let truth = decode(rec, names::PLANT, names::TRUTH, &mut notes);
        let configs = rec
            .attachments
            .iter()
            .filter_map(|(name, bytes)| {
                let id = name.strip_prefix("config/")?.strip_suffix(".toml")?;
                Some((id.to_string(), String::from_utf8_lossy(bytes).into_owned()))
            })
            .collect();
        let drops = rec
            .metadata
            .get(recorder::format::META_DROPS)
            .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        let mut data = FlightData {
            path: path.to_path_buf(),
            drones,
            truth,
            mode: rec.meta(META_RECORDING, "mode").map(str::to_string),
            truncated: rec.truncated,
            configs,
            drops,
            notes,
            t0_ns: 0,
        };
        data.t0_ns = data.earliest_ns().unwrap_or(0);
        data
    }

    /// Seconds since the time origin of an instant in ns (negative before it).
    pub fn secs(&self, t_ns: u64) -> f64 {
        (t_ns as i128 - self.t0_ns as i128) as f64 * 1e-9
    }

    fn earliest_ns(&self) -> Option<u64> {
        let mut firsts: Vec<Option<u64>> = vec![self.truth.first().map(sample_time_ns)];
        for d in &self.drones {
            firsts.extend([
                d.raw_adc.first().map(sample_time_ns),
                d.tension.first().map(sample_time_ns),
                d.tension_estimate.first().map(sample_time_ns),
                d.tension_truth.first().map(sample_time_ns),
                d.vehicle_state.first().map(sample_time_ns),
                d.imu.first().map(sample_time_ns),
                d.motor_speeds.first().map(sample_time_ns),
                d.mission.first().map(sample_time_ns),
                d.attitude.first().map(sample_time_ns),
            ]);
        }
        firsts.into_iter().flatten().min()
    }

    /// The drone's config attachment, if recorded.
    pub fn config_text(&self, id: &str) -> Option<&str> {
        self.configs
            .iter()
            .find(|(u, _)| u == id)
            .map(|(_, t)| t.as_str())
    }
}

/// The instant a sample stands for, on the recording's clock (ns).
pub trait SampleTime {
    fn time_ns(&self) -> u64;
}

macro_rules! origin_time {
    ($($t:ty),*) => {$(
        impl SampleTime for $t {
            /// Its physical measurement (`t_origin_ns`).
            fn time_ns(&self) -> u64 {
                self.header.t_origin_ns
            }
        }
    )*};
}
origin_time!(
    RawAdcFrame,
    TensionSample,
    VehicleState,
    ImuSample,
    MotorSpeeds,
    MissionSetpoint,
    PlantTruth
);

impl SampleTime for AttitudeSetpoint {
    /// When the step ran (`step_ns`), or its publication in recordings older than `step_ns`;
    /// its `t_origin_ns` is that of an input.
    fn time_ns(&self) -> u64 {
        if self.step_ns > 0 {
            self.step_ns
        } else {
            self.header.t_publish_ns
        }
    }
}

/// A recorded sample's time: its own (see [`SampleTime`]), or when the recorder took it if the
/// sample carries none (0).
pub fn sample_time_ns<T: SampleTime>(t: &Timed<T>) -> u64 {
    match t.sample.time_ns() {
        0 => t.log_time_ns,
        ns => ns,
    }
}

/// Decodes `/<uav>/<topic>` message by message; absence, a wrong schema and undecodable
/// messages become notes.
fn decode<T: Recordable>(
    rec: &Recording,
    uav: &str,
    topic: &str,
    notes: &mut Vec<String>,
) -> Vec<Timed<T>> {
    let name = recorder::channel_topic(uav, topic);
    let Some(ch) = rec.channel(&name) else {
        notes.push(format!("{name}: not recorded"));
        return Vec::new();
    };
    let wanted = schema_name::<T>();
    if ch.schema_name != wanted {
        notes.push(format!(
            "{name}: holds {}, not {wanted}: ignored",
            ch.schema_name
        ));
        return Vec::new();
    }
    let mut bad = 0usize;
    let mut first_error = String::new();
    let out = ch
        .messages
        .iter()
        .filter_map(|(t, bytes)| match serde_json::from_slice::<T>(bytes) {
            Ok(sample) => Some(Timed {
                log_time_ns: *t,
                sample,
            }),
            Err(e) => {
                if bad == 0 {
                    first_error = e.to_string();
                }
                bad += 1;
                None
            }
        })
        .collect();
    if bad > 0 {
        notes.push(format!(
            "{name}: {bad} of {} messages do not decode as {wanted} and are left out (first: {first_error})",
            ch.messages.len()
        ));
    }
    out
}
