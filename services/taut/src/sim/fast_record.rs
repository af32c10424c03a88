//! Fast mode's recording: the samples the in-process stages hand each other, stamped as their
//! publishers would stamp them (per-topic sequence from 0, `t_publish_ns` = simulated time) and
//! written to `<out>/recording.mcap` in the recorder's format, so that `taut report` and
//! `taut replay` read a fast flight like a real-time one.
//!
//! Stamping happens here, before a sample is handed on: the controller records the sequences
//! of its inputs, and a replay finds them by those numbers.

use std::path::Path;

use recorder::format::{visit_drone_topics, DroneTopicVisitor, DRONE_TOPICS};
use recorder::write::{Mode, RecordingInfo, RecordingWriter};
use recorder::{ChannelHandle, Recordable};
use shared_types::{names, PlantTruth};

/// The per-drone topics fast mode produces, in `recorder::format::DRONE_TOPICS` order (a
/// test holds them together).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FastTopic {
    RawAdc,
    Tension,
    TensionEstimate,
    TensionTruth,
    VehicleState,
    Imu,
    MotorSpeeds,
    MissionSetpoint,
    AttitudeSetpoint,
}

const TOPICS: usize = DRONE_TOPICS.len();

impl FastTopic {
    fn index(self) -> usize {
        self as usize
    }
}

/// Adds one drone's channels, in `DRONE_TOPICS` order.
struct DroneChannels<'a> {
    writer: &'a mut RecordingWriter,
    uav: &'a str,
    handles: Vec<ChannelHandle>,
}

impl DroneTopicVisitor for DroneChannels<'_> {
    type Error = String;
    fn visit<T: Recordable>(&mut self, topic: &'static str) -> Result<(), String> {
        let h = self
            .writer
            .add_channel::<T>(self.uav, topic)
            .map_err(|e| e.to_string())?;
        self.handles.push(h);
        Ok(())
    }
}

/// Stamps and (if a file is open) records every sample of both drones and the plant's truth.
pub struct FastRecording {
    writer: Option<RecordingWriter>,
    channels: Vec<[Option<ChannelHandle>; TOPICS]>,
    truth_channel: Option<ChannelHandle>,
    sequences: Vec<[u64; TOPICS]>,
    truth_sequence: u64,
    /// Samples that could not be written (the flight goes on; the count is reported).
    pub write_errors: u64,
    first_error: Option<String>,
}

impl FastRecording {
    /// Stamps without recording (when no file is wanted).
    pub fn stamp_only(drones: usize) -> Self {
        Self {
            writer: None,
            channels: vec![[None; TOPICS]; drones],
            truth_channel: None,
            sequences: vec![[0; TOPICS]; drones],
            truth_sequence: 0,
            write_errors: 0,
            first_error: None,
        }
    }

    /// Creates `path` for the drones `uavs` with their configs (TOML text, attached as they
    /// are: a replay rebuilds each controller from it).
    pub fn create(path: &Path, uavs: &[&str], configs: &[String]) -> Result<Self, String> {
        let info = RecordingInfo::new(Mode::Fast, uavs.iter().map(|u| u.to_string()).collect());
        let mut w = RecordingWriter::create(path, &info).map_err(|e| e.to_string())?;
        let mut channels = Vec::new();
        for (uav, cfg) in uavs.iter().zip(configs) {
            w.attach_config(uav, cfg).map_err(|e| e.to_string())?;
            let mut v = DroneChannels {
                writer: &mut w,
                uav,
                handles: Vec::with_capacity(TOPICS),
            };
            visit_drone_topics(&mut v)?;
            let mut row = [None; TOPICS];
            for (slot, h) in row.iter_mut().zip(v.handles) {
                *slot = Some(h);
            }
            channels.push(row);
        }
        let truth_channel = Some(
            w.add_channel::<PlantTruth>(names::PLANT, names::TRUTH)
                .map_err(|e| e.to_string())?,
        );
        Ok(Self {
            writer: Some(w),
            sequences: vec![[0; TOPICS]; channels.len()],
            channels,
            truth_channel,
            truth_sequence: 0,
            write_errors: 0,
            first_error: None,
        })
    }

    /// Stamps `sample` as drone `k`'s publisher of `topic` would at `t_ns`, and records it.
    pub fn publish<T: Recordable>(
        &mut self,
        k: usize,
        topic: FastTopic,
        t_ns: u64,
        sample: &mut T,
    ) {
        let i = topic.index();
        let h = sample.header_mut();
        h.sequence = self.sequences[k][i];
        h.t_publish_ns = t_ns;
        self.sequences[k][i] += 1;
        if let (Some(w), Some(ch)) = (self.writer.as_mut(), self.channels[k][i]) {
            if let Err(e) = w.write(ch, t_ns, sample) {
                self.write_errors += 1;
                self.first_error.get_or_insert(e.to_string());
            }
        }
    }

    /// Stamps and records the plant's truth at `t_ns`.
    pub fn publish_truth(&mut self, t_ns: u64, truth: &mut PlantTruth) {
        truth.header.sequence = self.truth_sequence;
        truth.header.t_publish_ns = t_ns;
        self.truth_sequence += 1;
        if let (Some(w), Some(ch)) = (self.writer.as_mut(), self.truth_channel) {
            if let Err(e) = w.write(ch, t_ns, truth) {
                self.write_errors += 1;
                self.first_error.get_or_insert(e.to_string());
            }
        }
    }

    /// Closes the file (summary, drop accounting). `Err` if any sample was not written.
    pub fn finish(self) -> Result<(), String> {
        if let Some(w) = self.writer {
            w.finish().map_err(|e| e.to_string())?;
        }
        match self.first_error {
            None => Ok(()),
            Some(e) => Err(format!(
                "{} samples not recorded; first: {e}",
                self.write_errors
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_topics_follow_the_recorder_order() {
        let all = [
            (FastTopic::RawAdc, names::RAW_ADC),
            (FastTopic::Tension, names::TENSION),
            (FastTopic::TensionEstimate, names::TENSION_ESTIMATE),
            (FastTopic::TensionTruth, names::TENSION_TRUTH),
            (FastTopic::VehicleState, names::VEHICLE_STATE),
            (FastTopic::Imu, names::IMU),
            (FastTopic::MotorSpeeds, names::MOTOR_SPEEDS),
            (FastTopic::MissionSetpoint, names::MISSION_SETPOINT),
            (FastTopic::AttitudeSetpoint, names::ATTITUDE_SETPOINT),
        ];
        assert_eq!(all.len(), TOPICS);
        for (t, name) in all {
            assert_eq!(DRONE_TOPICS[t.index()], name, "{t:?}");
        }
    }
}
