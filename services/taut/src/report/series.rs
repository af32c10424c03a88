//! Time series for the figures, pure functions of the loaded flight.
//!
//! One frame and sign for every force: **the cable's pull on the drone, NED, N** (a hanging
//! load pulls +z, down). Body-FRD forces are rotated into NED with an attitude of the same
//! instant: the plant's own attitude for the truth, PX4's estimate (`vehicle_state`, the newest
//! at or before the sample) for the sensor and the estimator. The controller's T_d is the force
//! the drone exerts on the cable, so it is negated.

pub use crate::sim::metrics::{quat, swing_deg};
use nalgebra::{UnitQuaternion, Vector3};
use recorder::Timed;
use shared_types::{
    setpoint_flags, tension_flags, ContactKind, MissionPhase, PlantTruth, TensionSample,
};

use super::load::{sample_time_ns, DroneData, FlightData};

/// What a line shows; the figures give each its colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// PX4's estimate (positions).
    Estimate,
    /// The plant's ground truth.
    Truth,
    /// The mission's nominal setpoint ξ̄_d.
    Nominal,
    /// The controller's tension-shifted setpoint ξ_d.
    Shifted,
    /// The force sensor's tension stage.
    Sensor,
    /// The model-based external-force estimator.
    Estimator,
    /// The controller's static tension T_d.
    Desired,
}

/// One line: (seconds since the time origin, value) points.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub source: Source,
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// A mission phase from `from_s` to `to_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseSpan {
    pub phase: MissionPhase,
    pub from_s: f64,
    pub to_s: f64,
}

/// Attitudes over time, body FRD -> NED, for rotating forces of other channels.
#[derive(Debug, Clone, Default)]
pub struct AttitudeTrack {
    t_ns: Vec<u64>,
    q: Vec<UnitQuaternion<f64>>,
}

impl AttitudeTrack {
    pub fn new(samples: impl IntoIterator<Item = (u64, [f64; 4])>) -> Self {
        let mut pairs: Vec<(u64, UnitQuaternion<f64>)> =
            samples.into_iter().map(|(t, q)| (t, quat(q))).collect();
        pairs.sort_by_key(|(t, _)| *t);
        let (t_ns, q) = pairs.into_iter().unzip();
        AttitudeTrack { t_ns, q }
    }

    pub fn is_empty(&self) -> bool {
        self.t_ns.is_empty()
    }

    /// The newest attitude at or before `t_ns` (the first one before the track starts).
    pub fn at(&self, t_ns: u64) -> Option<UnitQuaternion<f64>> {
        let i = self.t_ns.partition_point(|t| *t <= t_ns);
        self.q.get(i.saturating_sub(1)).copied()
    }
}

/// Three series, one per NED axis, from a vector per sample.
fn per_axis<T>(
    f: &FlightData,
    samples: impl Iterator<Item = T>,
    source: Source,
    label: &str,
    v: impl Fn(&T) -> Option<(u64, [f64; 3])>,
) -> [Series; 3] {
    let mut out: [Series; 3] = std::array::from_fn(|_| Series {
        source,
        label: label.to_string(),
        points: Vec::new(),
    });
    for s in samples {
        let Some((t, x)) = v(&s) else { continue };
        let t_s = f.secs(t);
        for (axis, value) in x.iter().enumerate() {
            if value.is_finite() {
                out[axis].points.push((t_s, *value));
            }
        }
    }
    out
}

fn push_axes(out: &mut [Vec<Series>; 3], s: [Series; 3]) {
    for (axis, series) in s.into_iter().enumerate() {
        if !series.points.is_empty() {
            out[axis].push(series);
        }
    }
}

/// The controller's flight steps (not IDLE).
fn flying(sp: &Timed<shared_types::AttitudeSetpoint>) -> bool {
    sp.sample.flags & setpoint_flags::IDLE == 0
}

/// Positions of drone `d`, NED, m: per axis (x, y, z) the estimate, the truth, the nominal and
/// the shifted setpoint (the controller's flight steps only).
pub fn positions(f: &FlightData, d: &DroneData) -> [Vec<Series>; 3] {
    let mut out: [Vec<Series>; 3] = Default::default();
    let k = d.truth_index;
    push_axes(
        &mut out,
        per_axis(
            f,
            d.vehicle_state.iter(),
            Source::Estimate,
            "PX4 estimate",
            |s| Some((sample_time_ns(s), s.sample.position_ned_m)),
        ),
    );
    push_axes(
        &mut out,
        per_axis(f, f.truth.iter(), Source::Truth, "truth", |s| {
            Some((sample_time_ns(s), s.sample.drones[k].body.position_ned_m))
        }),
    );
    push_axes(
        &mut out,
        per_axis(
            f,
            d.mission.iter(),
            Source::Nominal,
            "nominal setpoint",
            |s| Some((sample_time_ns(s), s.sample.position_ned_m)),
        ),
    );
    push_axes(
        &mut out,
        per_axis(
            f,
            d.attitude.iter(),
            Source::Shifted,
            "shifted setpoint",
            |s| flying(s).then(|| (sample_time_ns(s), s.sample.shifted_position_ned_m)),
        ),
    );
    out
}

/// Body-FRD tension samples rotated into NED with `track` (pull on the drone). Samples still
/// warming their stage's filter up (FILTER_WARMUP: the sensor's first frames read the chips
/// before their first conversion) are left out: they are not forces.
fn rotated(
    f: &FlightData,
    samples: &[Timed<TensionSample>],
    track: &AttitudeTrack,
    source: Source,
    label: &str,
) -> [Series; 3] {
    let settled = samples
        .iter()
        .filter(|s| s.sample.flags & tension_flags::FILTER_WARMUP == 0);
    per_axis(f, settled, source, label, |s| {
        let t = sample_time_ns(s);
        let q = track.at(t)?;
        Some((t, (q * Vector3::from(s.sample.force_body_n)).into()))
    })
}

/// Cable force on drone `d` per NED axis, N (the pull on the drone, see the module doc):
/// sensor, estimator, truth, and −T_d. Notes say which fallbacks were taken.
pub fn forces(f: &FlightData, d: &DroneData, notes: &mut Vec<String>) -> [Vec<Series>; 3] {
    let mut out: [Vec<Series>; 3] = Default::default();
    let k = d.truth_index;
    let truth_track = AttitudeTrack::new(
        f.truth
            .iter()
            .map(|s| (sample_time_ns(s), s.sample.drones[k].body.attitude_wxyz)),
    );
    let est_track = AttitudeTrack::new(
        d.vehicle_state
            .iter()
            .map(|s| (sample_time_ns(s), s.sample.attitude_wxyz)),
    );
    let (track, whose) = if !est_track.is_empty() {
        (&est_track, "")
    } else {
        (&truth_track, " (true attitude)")
    };
    let needs_track = !d.tension.is_empty() || !d.tension_estimate.is_empty();
    if needs_track && track.is_empty() {
        notes.push(format!(
            "{}: no attitude recorded (vehicle_state, truth): sensor and estimator forces cannot be put in NED",
            d.id
        ));
    } else if needs_track && est_track.is_empty() {
        notes.push(format!(
            "{}: no vehicle_state: sensor and estimator forces rotated with the true attitude",
            d.id
        ));
    }
    push_axes(
        &mut out,
        rotated(
            f,
            &d.tension,
            track,
            Source::Sensor,
            &format!("sensor{whose}"),
        ),
    );
    push_axes(
        &mut out,
        rotated(
            f,
            &d.tension_estimate,
            track,
            Source::Estimator,
            &format!("estimator{whose}"),
        ),
    );
    if !f.truth.is_empty() {
        push_axes(
            &mut out,
            per_axis(f, f.truth.iter(), Source::Truth, "truth", |s| {
                Some((sample_time_ns(s), true_pull_ned(&s.sample, k).into()))
            }),
        );
    } else if !d.tension_truth.is_empty() {
        push_axes(
            &mut out,
            rotated(
                f,
                &d.tension_truth,
                track,
                Source::Truth,
                "truth (tension_truth)",
            ),
        );
    }
    push_axes(
        &mut out,
        per_axis(
            f,
            d.attitude.iter(),
            Source::Desired,
            "−T_d (controller)",
            |s| {
                let td = s.sample.tension_desired_ned_n;
                flying(s).then(|| (sample_time_ns(s), [-td[0], -td[1], -td[2]]))
            },
        ),
    );
    out
}

/// The true cable pull on drone `k`, NED, N.
pub fn true_pull_ned(t: &PlantTruth, k: usize) -> Vector3<f64> {
    let d = &t.drones[k];
    quat(d.body.attitude_wxyz) * Vector3::from(d.anchor_force_frd_n)
}

/// Payload position per NED axis (truth), m.
pub fn payload_position(f: &FlightData) -> [Vec<Series>; 3] {
    let mut out: [Vec<Series>; 3] = Default::default();
    push_axes(
        &mut out,
        per_axis(f, f.truth.iter(), Source::Truth, "payload (truth)", |s| {
            Some((sample_time_ns(s), s.sample.payload.position_ned_m))
        }),
    );
    out
}

/// The payload's swing angle over time, degrees (see [`swing_deg`]), while it hangs free: on
/// its box or the ground the drones may be beside or below it and the angle means nothing.
pub fn swing(f: &FlightData, anchor_frd_m: [f64; 3]) -> Series {
    Series {
        source: Source::Truth,
        label: "swing (truth)".into(),
        points: f
            .truth
            .iter()
            .filter(|s| s.sample.payload_contact == ContactKind::Free)
            .map(|s| {
                (
                    f.secs(sample_time_ns(s)),
                    swing_deg(&s.sample, anchor_frd_m),
                )
            })
            .filter(|(_, a)| a.is_finite())
            .collect(),
    }
}

/// The mission phases of drone `d` as spans, the last one ending at `end_s`.
pub fn phases(f: &FlightData, d: &DroneData, end_s: f64) -> Vec<PhaseSpan> {
    let mut out: Vec<PhaseSpan> = Vec::new();
    for s in &d.mission {
        let t = f.secs(sample_time_ns(s));
        match out.last_mut() {
            Some(last) if last.phase == s.sample.phase => last.to_s = t,
            Some(last) => {
                last.to_s = t;
                out.push(PhaseSpan {
                    phase: s.sample.phase,
                    from_s: t,
                    to_s: t,
                });
            }
            None => out.push(PhaseSpan {
                phase: s.sample.phase,
                from_s: t,
                to_s: t,
            }),
        }
    }
    if let Some(last) = out.last_mut() {
        last.to_s = last.to_s.max(end_s);
    }
    out
}

/// The last instant of any series, s.
pub fn end_s(series: &[&Series]) -> f64 {
    series
        .iter()
        .filter_map(|s| s.points.last().map(|p| p.0))
        .fold(0.0, f64::max)
}

#[cfg(test)]
#[path = "series_tests.rs"]
mod tests;
