//! What a taut recording looks like, once for every writer and reader.
//!
//! - One MCAP file, chunked and zstd-compressed.
//! - One channel per (drone, topic): topic `/<uav>/<topic>` (e.g. `/uav1/tension`,
//!   `/plant/truth`), channel metadata `uav`, `topic`, `type`.
//! - Messages are JSON (`message_encoding = "json"`), one object per sample with the Rust field
//!   names; schemas are JSON Schema (`encoding = "jsonschema"`), named `taut.<Type>`. Foxglove and
//!   the Python `mcap` reader decode both without generated code. JSON has no NaN: a non-finite
//!   float is written as `null` (serde_json's rule), and the typed reader rejects that message.
//! - `log_time` is when the recorder took the sample (CLOCK_MONOTONIC ns; simulated ns in fast
//!   mode), `publish_time` the sample's `header.t_publish_ns`, `sequence` its
//!   `header.sequence` (low 32 bits).
//! - Metadata record [`META_RECORDING`] at the start (clock, mode, drones, chunk period), and at
//!   a clean close [`META_DROPS`] and [`META_RECEIVED`]: per channel topic, the samples lost
//!   (sequence gaps) and taken; also [`META_MISSED_BEFORE_START`] (the first sequence taken:
//!   published before the recorder subscribed, not a drop), [`META_RESTARTS`] (the sequence went
//!   backwards), [`META_FIRST_SEQUENCE`] and [`META_LAST_SEQUENCE`]. Attachments
//!   `config/<uav>.toml` (media type `application/toml`) hold each drone's effective
//!   configuration, written at the start so a killed recording still has them.
//! - Chunks are closed (and flushed to the OS) at least every chunk period of log time (1 s by
//!   default), so a recorder killed with SIGKILL loses at most its open chunk.

use schemars::JsonSchema;
use serde::{de::DeserializeOwned, Serialize};
use shared_types::{
    names, AttitudeSetpoint, ImuSample, MissionSetpoint, MotorSpeeds, PlantTruth, RawAdcFrame,
    TensionSample, VehicleState,
};
use taut_ipc::Stamped;

/// `message_encoding` of every channel.
pub const MESSAGE_ENCODING: &str = "json";
/// `encoding` of every schema.
pub const SCHEMA_ENCODING: &str = "jsonschema";
/// Metadata written first: `clock`, `mode` (`realtime` | `fast`), `uavs` (comma separated).
pub const META_RECORDING: &str = "taut.recording";
/// Metadata written at a clean close: channel topic -> samples lost to sequence gaps.
pub const META_DROPS: &str = "taut.drops";
/// Metadata written at a clean close: channel topic -> samples written.
pub const META_RECEIVED: &str = "taut.received";
/// Metadata written at a clean close: channel topic -> the first sequence taken (samples
/// published before the recorder subscribed).
pub const META_MISSED_BEFORE_START: &str = "taut.missed_before_start";
/// Metadata written at a clean close: channel topic -> times the publisher restarted.
pub const META_RESTARTS: &str = "taut.restarts";
/// Metadata written at a clean close: channel topic -> first sequence taken ("" if none).
pub const META_FIRST_SEQUENCE: &str = "taut.first_sequence";
/// Metadata written at a clean close: channel topic -> last sequence taken ("" if none).
pub const META_LAST_SEQUENCE: &str = "taut.last_sequence";
/// Media type of the config attachments.
pub const CONFIG_MEDIA_TYPE: &str = "application/toml";
/// Attachment name of a drone's effective configuration (TOML).
pub fn config_attachment(uav: &str) -> String {
    format!("config/{uav}.toml")
}

/// A sample type that can be recorded: its JSON form and schema name.
pub trait Recordable: Stamped + Serialize + DeserializeOwned + JsonSchema {
    /// The Rust type name; the schema is `taut.<TYPE_NAME>`.
    const TYPE_NAME: &'static str;
}

macro_rules! recordable {
    ($($t:ident),* $(,)?) => {$(
        impl Recordable for $t {
            const TYPE_NAME: &'static str = stringify!($t);
        }
    )*};
}

recordable!(
    RawAdcFrame,
    TensionSample,
    PlantTruth,
    VehicleState,
    ImuSample,
    MotorSpeeds,
    MissionSetpoint,
    AttitudeSetpoint,
);

/// Every per-drone topic a recording holds, in channel order (see [`visit_drone_topics`]).
pub const DRONE_TOPICS: [&str; 9] = [
    names::RAW_ADC,
    names::TENSION,
    names::TENSION_ESTIMATE,
    names::TENSION_TRUTH,
    names::VEHICLE_STATE,
    names::IMU,
    names::MOTOR_SPEEDS,
    names::MISSION_SETPOINT,
    names::ATTITUDE_SETPOINT,
];

/// Something done once per drone topic with its sample type (subscribe to it, add its
/// channel): the one place that pairs each topic with its type.
pub trait DroneTopicVisitor {
    type Error;
    fn visit<T: Recordable>(&mut self, topic: &'static str) -> Result<(), Self::Error>;
}

/// Visits every topic of [`DRONE_TOPICS`], in that order, with its sample type.
pub fn visit_drone_topics<V: DroneTopicVisitor>(v: &mut V) -> Result<(), V::Error> {
    v.visit::<RawAdcFrame>(names::RAW_ADC)?;
    v.visit::<TensionSample>(names::TENSION)?;
    v.visit::<TensionSample>(names::TENSION_ESTIMATE)?;
    v.visit::<TensionSample>(names::TENSION_TRUTH)?;
    v.visit::<VehicleState>(names::VEHICLE_STATE)?;
    v.visit::<ImuSample>(names::IMU)?;
    v.visit::<MotorSpeeds>(names::MOTOR_SPEEDS)?;
    v.visit::<MissionSetpoint>(names::MISSION_SETPOINT)?;
    v.visit::<AttitudeSetpoint>(names::ATTITUDE_SETPOINT)
}

/// `taut.<Type>`.
pub fn schema_name<T: Recordable>() -> String {
    format!("taut.{}", T::TYPE_NAME)
}

/// The JSON Schema of `T`, as bytes for the MCAP schema record.
pub fn schema_json<T: Recordable>() -> Vec<u8> {
    let mut schema = schemars::schema_for!(T);
    schema.insert("title".into(), schema_name::<T>().into());
    serde_json::to_vec(&schema).unwrap_or_default()
}

/// The channel topic of a drone's topic: `/<uav>/<topic>`.
pub fn channel_topic(uav: &str, topic: &str) -> String {
    format!("/{uav}/{topic}")
}

/// The channel metadata keys.
pub const CHANNEL_UAV: &str = "uav";
pub const CHANNEL_TOPIC: &str = "topic";
pub const CHANNEL_TYPE: &str = "type";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schema_names_and_titles() {
        assert_eq!(schema_name::<TensionSample>(), "taut.TensionSample");
        let v: serde_json::Value =
            serde_json::from_slice(&schema_json::<AttitudeSetpoint>()).expect("schema is JSON");
        assert_eq!(v["title"], "taut.AttitudeSetpoint");
        assert!(v["properties"]["step_ns"].is_object(), "{v}");
        assert_eq!(channel_topic("uav1", "tension"), "/uav1/tension");
    }

    #[test]
    fn the_visitor_walks_drone_topics_in_order() {
        struct Names(Vec<(&'static str, &'static str)>);
        impl DroneTopicVisitor for Names {
            type Error = ();
            fn visit<T: Recordable>(&mut self, topic: &'static str) -> Result<(), ()> {
                self.0.push((topic, T::TYPE_NAME));
                Ok(())
            }
        }
        let mut v = Names(Vec::new());
        visit_drone_topics(&mut v).expect("visit");
        let topics: Vec<&str> = v.0.iter().map(|p| p.0).collect();
        assert_eq!(topics, DRONE_TOPICS);
        assert_eq!(v.0[3], (names::TENSION_TRUTH, "TensionSample"));
        assert_eq!(v.0[8], (names::ATTITUDE_SETPOINT, "AttitudeSetpoint"));
    }

    #[test]
    fn floats_round_trip_bit_for_bit() {
        let s = AttitudeSetpoint {
            attitude_wxyz: [0.1 + 0.2, 1.0 / 3.0, -1e-300, 6.02214076e23],
            thrust_n: f64::from_bits(0x400921FB54442D19),
            step_ns: u64::MAX - 1,
            ..Default::default()
        };
        let json = serde_json::to_vec(&s).expect("encode");
        let back: AttitudeSetpoint = serde_json::from_slice(&json).expect("decode");
        assert_eq!(back, s);
        assert_eq!(back.thrust_n.to_bits(), s.thrust_n.to_bits());
    }
}
