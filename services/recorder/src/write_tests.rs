//! The writer against the reader: every sample type round-trips bit for bit, drops are counted,
//! chunks close on time, and a file cut anywhere still reads up to its last complete chunk.

use super::*;
use crate::format::{META_DROPS, META_MISSED_BEFORE_START, META_RECEIVED, META_RECORDING};
use crate::read::Recording;
use shared_types::{
    AttitudeSetpoint, ImuSample, MissionSetpoint, MotorSpeeds, PlantTruth, RawAdcFrame,
    TensionSample, VehicleState,
};
use std::cell::RefCell;
use std::io::{Cursor, SeekFrom};
use std::rc::Rc;

/// A file in memory whose length the test can watch while the writer owns it.
#[derive(Clone, Default)]
struct Shared(Rc<RefCell<Cursor<Vec<u8>>>>);

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.borrow_mut().write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for Shared {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.0.borrow_mut().seek(pos)
    }
}

/// A sample of `T` whose every number is distinct and awkward (floats that need all 17
/// digits, distinct integers), built through its JSON form so every field
/// of every type is covered without naming them.
fn awkward<T: Recordable + Default>(seed: u64) -> T {
    fn fill(v: &mut serde_json::Value, k: &mut u64) {
        use serde_json::Value;
        match v {
            Value::Number(n) => {
                *k += 1;
                *v = if n.is_f64() {
                    Value::from(
                        (*k as f64 + 0.1) / 3.0 * if k.is_multiple_of(2) { -1.0 } else { 1.0 },
                    )
                } else {
                    // Fits every integer field (the ADC codes are i16).
                    Value::from(*k % 30_000 + 7)
                };
            }
            Value::Array(a) => a.iter_mut().for_each(|x| fill(x, k)),
            Value::Object(o) => o.values_mut().for_each(|x| fill(x, k)),
            _ => {}
        }
    }
    let mut v = serde_json::to_value(T::default()).unwrap();
    let mut k = seed * 1000;
    fill(&mut v, &mut k);
    serde_json::from_value(v).expect("an awkward sample decodes")
}

fn info(period_ns: u64) -> RecordingInfo {
    RecordingInfo {
        mode: Mode::Fast,
        uavs: vec!["uav1".into()],
        chunk_period_ns: period_ns,
    }
}

fn writer(period_ns: u64) -> RecordingWriter<Cursor<Vec<u8>>> {
    RecordingWriter::from_writer(Cursor::new(Vec::new()), &info(period_ns)).unwrap()
}

/// Writes `n` awkward samples of `T` (sequences 0..n) on `uav1/topic`, 1 ms apart.
fn put<T: Recordable + Default>(
    w: &mut RecordingWriter<Cursor<Vec<u8>>>,
    topic: &str,
    n: u64,
) -> Vec<T> {
    let ch = w.add_channel::<T>("uav1", topic).unwrap();
    (0..n)
        .map(|i| {
            let mut s: T = awkward(i + 1);
            s.header_mut().sequence = i;
            w.write(ch, 1_000_000 * (i + 1), &s).unwrap();
            s
        })
        .collect()
}

fn check<T: Recordable + Default + PartialEq>(rec: &Recording, topic: &str, sent: &[T]) {
    let got = rec.samples::<T>("uav1", topic).unwrap();
    assert_eq!(got.len(), sent.len(), "{topic}");
    for (i, (g, s)) in got.iter().zip(sent).enumerate() {
        assert_eq!(&g.sample, s, "{topic} sample {i}");
        assert_eq!(g.log_time_ns, 1_000_000 * (i as u64 + 1));
    }
}

#[test]
fn every_sample_type_round_trips_bit_for_bit() {
    let mut w = writer(DEFAULT_CHUNK_PERIOD_NS);
    w.attach_config("uav1", "uav = \"uav1\"\n").unwrap();
    let a = put::<RawAdcFrame>(&mut w, "raw_adc", 5);
    let b = put::<TensionSample>(&mut w, "tension", 5);
    let c = put::<PlantTruth>(&mut w, "truth", 5);
    let d = put::<VehicleState>(&mut w, "vehicle_state", 5);
    let e = put::<ImuSample>(&mut w, "imu", 5);
    let f = put::<MotorSpeeds>(&mut w, "motor_speeds", 5);
    let g = put::<MissionSetpoint>(&mut w, "mission_setpoint", 5);
    let h = put::<AttitudeSetpoint>(&mut w, "attitude_setpoint", 5);
    assert_ne!(
        b[1].force_body_n[0], 0.0,
        "the awkward sample is not trivial"
    );
    let (stats, cur) = w.finish_into_inner().unwrap();
    assert!(stats.iter().all(|s| s.received == 5 && s.drops == 0));
    let rec = Recording::from_bytes(cur.get_ref()).unwrap();
    assert!(!rec.truncated);
    check(&rec, "raw_adc", &a);
    check(&rec, "tension", &b);
    check(&rec, "truth", &c);
    check(&rec, "vehicle_state", &d);
    check(&rec, "imu", &e);
    check(&rec, "motor_speeds", &f);
    check(&rec, "mission_setpoint", &g);
    check(&rec, "attitude_setpoint", &h);
    assert_eq!(rec.meta(META_RECORDING, "mode"), Some("fast"));
    assert_eq!(rec.meta(META_RECORDING, "uavs"), Some("uav1"));
    assert_eq!(rec.meta(META_RECEIVED, "/uav1/imu"), Some("5"));
    assert_eq!(rec.meta(META_DROPS, "/uav1/imu"), Some("0"));
    assert_eq!(rec.attachments["config/uav1.toml"], b"uav = \"uav1\"\n");
    assert_eq!(rec.uavs(), ["uav1"]);
}

#[test]
fn gaps_are_recorded_as_drops_and_a_late_first_sequence_is_not() {
    let mut w = writer(DEFAULT_CHUNK_PERIOD_NS);
    let ch = w.add_channel::<TensionSample>("uav1", "tension").unwrap();
    for (i, seq) in [3u64, 4, 7, 8, 20].into_iter().enumerate() {
        let mut s = TensionSample::default();
        s.header.sequence = seq;
        w.write(ch, i as u64, &s).unwrap();
    }
    let wrong = w.write(ch, 9, &ImuSample::default()).unwrap_err();
    assert!(wrong.to_string().contains("TensionSample"), "{wrong}");
    let (stats, cur) = w.finish_into_inner().unwrap();
    assert_eq!((stats[0].drops, stats[0].missed_before_start), (2 + 11, 3));
    let rec = Recording::from_bytes(cur.get_ref()).unwrap();
    assert_eq!(rec.meta(META_DROPS, "/uav1/tension"), Some("13"));
    assert_eq!(
        rec.meta(META_MISSED_BEFORE_START, "/uav1/tension"),
        Some("3")
    );
    assert_eq!(rec.meta(META_RECEIVED, "/uav1/tension"), Some("5"));
}

/// 1 kHz for 3.5 s with a 0.5 s chunk period, the file cut at every length from just after the
/// first chunk to the end: what reads is a gap-free prefix, and it lacks at most the messages of
/// one chunk period (500) plus the torn chunk's own.
#[test]
fn a_cut_file_reads_up_to_its_last_complete_chunk() {
    let period_ns = 500_000_000;
    let file = Shared::default();
    let mut w = RecordingWriter::from_writer(file.clone(), &info(period_ns)).unwrap();
    w.attach_config("uav1", "x = 1\n").unwrap();
    let ch = w.add_channel::<TensionSample>("uav1", "tension").unwrap();
    let mut ends = Vec::new(); // (file length after a chunk closed, messages in it)
    for i in 0..3500u64 {
        let mut s = TensionSample::default();
        s.header.sequence = i;
        w.write(ch, (i + 1) * 1_000_000, &s).unwrap();
        if w.chunk_opened_ns.is_none() {
            ends.push((file.0.borrow().get_ref().len(), i + 1));
        }
    }
    assert!(ends.len() >= 6, "chunks closed: {}", ends.len());
    w.finish().unwrap();
    let bytes = file.0.borrow().get_ref().clone();
    let step = (bytes.len() / 97).max(1);
    for cut in (ends[0].0..bytes.len()).step_by(step) {
        let rec = Recording::from_bytes(&bytes[..cut]).unwrap();
        let got = rec.samples::<TensionSample>("uav1", "tension").unwrap();
        let seqs: Vec<u64> = got.iter().map(|t| t.sample.header.sequence).collect();
        assert!(
            seqs.iter().enumerate().all(|(i, &q)| q == i as u64),
            "cut {cut}: gaps"
        );
        // Every chunk that ended before the cut is there.
        let complete = ends
            .iter()
            .filter(|(len, _)| *len <= cut)
            .map(|e| e.1)
            .max();
        assert!(
            seqs.len() as u64 >= complete.unwrap_or(0),
            "cut {cut}: {} < {complete:?}",
            seqs.len()
        );
        assert!(rec.truncated, "cut {cut} not flagged");
        assert_eq!(rec.attachments["config/uav1.toml"], b"x = 1\n");
    }
}

#[test]
fn an_idle_open_chunk_is_closed_by_tick() {
    let mut w = writer(100);
    let ch = w
        .add_channel::<MotorSpeeds>("uav1", "motor_speeds")
        .unwrap();
    w.write(ch, 1_000, &MotorSpeeds::default()).unwrap();
    assert!(!w.tick(1_050).unwrap());
    assert!(w.tick(1_100).unwrap());
    assert!(!w.tick(5_000).unwrap(), "nothing open");
    assert!(RecordingWriter::from_writer(Cursor::new(Vec::new()), &info(0)).is_err());
}
