//! The flight's metrics, computed from the plant's ground truth and the services' own samples:
//! pure (no clock, no I/O), fed the same way by the real-time run (samples over iceoryx2) and
//! the fast run (in process), so their summaries compare.
//!
//! Definitions (the issue is silent on them; these are what `summary.json` reports):
//! - Times are seconds of simulated time since the plant started.
//! - Position error: true position against the drone's nominal setpoint ξ̄_d from the mission,
//!   from the first phase's start to the end of the flight (Idle excluded).
//! - z steady-state error in Move: mean of (true z − setpoint z) over the last `STEADY_WINDOW_S`
//!   seconds before the next Move phase starts or the flight ends (so for Test A it is the end
//!   of the hold that follows the move); reported for the last Move phase.
//! - Tension tracking: the true cable force the drone exerts on the cable (−R·anchor pull, NED)
//!   against the controller's T_d, over controller steps while the mission has the tension loop
//!   on (Test A: from the move on; the cables are meant to be slack during take-off).
//! - Swing: the pendulum angle of the payload about the line through the two drones' cable
//!   anchors (the angle between the anchors-to-payload plane and the vertical plane through
//!   that line). Along-the-line offsets (unequal heights, noise) are a stiff mode of the taut
//!   triangle, not a swing. Measured from the payload's lift-off (Test A) or the first Move
//!   (payload hanging from the start); settling time = last instant above 2° minus that start.
//!   So `swing_rms_deg` is the swing RMS after the drop (lift-off) in Test A.
//! - Force sources against the truth (`force_rmse`): see [`super::force_metrics`].

pub use super::swing::{quat, swing_deg};
use latency_tests::{Percentiles, SpanHistograms};
use nalgebra::Vector3;
use serde::Serialize;
use shared_types::{
    AttitudeSetpoint, ContactKind, MissionPhase, MissionSetpoint, PlantTruth, TensionSample,
};

use super::force_metrics::{ForceErrors, ForceRmse, ForceSource};

/// Window of the z steady-state error, s.
pub const STEADY_WINDOW_S: f64 = 3.0;
/// Swing below this counts as settled, degrees.
pub const SWING_SETTLED_DEG: f64 = 2.0;

const SPANS: [&str; 4] = [
    "uav1_tension_to_setpoint",
    "uav1_odometry_to_setpoint",
    "uav2_tension_to_setpoint",
    "uav2_odometry_to_setpoint",
];

#[derive(Debug, Clone, Serialize)]
pub struct PhaseRecord {
    pub name: String,
    pub index: usize,
    /// When drone uav1 / uav2 started it, s.
    pub start_s: [Option<f64>; 2],
}

#[derive(Debug, Clone, Serialize)]
pub struct DroneMetrics {
    pub id: String,
    pub position_rmse_m: Option<f64>,
    /// Last Move phase, see the module doc.
    pub z_steady_state_error_m: Option<f64>,
    pub tension_rmse_n: Option<f64>,
    /// True distance to the nominal setpoint at the end, m.
    pub final_position_error_m: Option<f64>,
    /// The same by PX4's estimate (what the phase rule sees; differs by the perturbation), m.
    pub final_estimate_error_m: Option<f64>,
    pub failsafe_count: u32,
    pub crash_flags: u32,
    /// Controller steps without a fresh tension sample.
    pub position_only_steps: u64,
    pub setpoints: u64,
    /// Sensor, estimator and used force against the true anchor force, airborne.
    pub force_rmse: ForceRmse,
}

#[derive(Debug, Clone, Serialize)]
pub struct PayloadMetrics {
    /// When the payload left its support, s (None: hanging from the start or never lifted).
    pub lifted_at_s: Option<f64>,
    /// Start of the swing window, s.
    pub swing_from_s: Option<f64>,
    pub swing_rms_deg: Option<f64>,
    pub swing_max_deg: Option<f64>,
    /// Time from the window's start until the swing stays below 2°, s (None: not settled).
    pub settling_time_s: Option<f64>,
    pub final_swing_deg: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
pub struct FlightMetrics {
    pub phases: Vec<PhaseRecord>,
    pub drones: Vec<DroneMetrics>,
    pub payload: PayloadMetrics,
    pub max_cable_force_n: f64,
    /// Sample-to-setpoint latency per drone, µs: setpoint publish − tension sample's physical
    /// measurement (`t_origin_ns`), and − odometry receipt. Empty in fast mode (no clock).
    pub latency_us: std::collections::BTreeMap<String, Percentiles>,
    pub failsafe_fired: bool,
    pub crashed: bool,
}

#[derive(Debug, Clone, Default)]
struct DroneAcc {
    mission: Option<MissionSetpoint>,
    phase_index: Option<u32>,
    sq_err: f64,
    n_err: u64,
    tension_sq: f64,
    n_tension: u64,
    final_err: Option<f64>,
    final_estimate_err: Option<f64>,
    position_only: u64,
    setpoints: u64,
    /// (time s, z error m, phase index) over the flight, for the steady-state window.
    z_err: Vec<(f64, f64, u32)>,
}

/// Accumulates the metrics of one flight.
pub struct MetricsRecorder {
    ids: [String; 2],
    phase_names: Vec<String>,
    phase_is_move: Vec<bool>,
    phases: Vec<PhaseRecord>,
    drones: [DroneAcc; 2],
    /// CLOCK_MONOTONIC minus simulated time, ns (0 in fast mode).
    clock_offset_ns: Option<i128>,
    last_truth: Option<PlantTruth>,
    anchor_frd_m: Vector3<f64>,
    started_on_support: Option<bool>,
    lifted_at_s: Option<f64>,
    /// (time s, swing deg).
    swing: Vec<(f64, f64)>,
    max_cable_force_n: f64,
    spans: SpanHistograms,
    forces: ForceErrors,
}

impl MetricsRecorder {
    pub fn new(
        ids: [String; 2],
        phase_names: Vec<String>,
        phase_is_move: Vec<bool>,
        anchor_frd_m: [f64; 3],
    ) -> Self {
        let phases = phase_names
            .iter()
            .enumerate()
            .map(|(index, name)| PhaseRecord {
                name: name.clone(),
                index,
                start_s: [None; 2],
            })
            .collect();
        MetricsRecorder {
            ids,
            phase_names,
            phase_is_move,
            phases,
            drones: Default::default(),
            clock_offset_ns: None,
            last_truth: None,
            anchor_frd_m: Vector3::from(anchor_frd_m),
            started_on_support: None,
            lifted_at_s: None,
            swing: Vec::new(),
            max_cable_force_n: 0.0,
            spans: SpanHistograms::new(&SPANS),
            forces: ForceErrors::default(),
        }
    }

    /// Simulated seconds of a CLOCK_MONOTONIC instant.
    fn sim_s(&self, t_ns: u64) -> Option<f64> {
        self.clock_offset_ns
            .map(|off| (t_ns as i128 - off) as f64 * 1e-9)
    }

    /// The phase started by drone `k` at `t_s`, if the setpoint shows a new one. Returns the
    /// phase's name for the caller's log.
    pub fn on_mission(&mut self, k: usize, sp: &MissionSetpoint) -> Option<(usize, String, f64)> {
        let acc = &mut self.drones[k];
        acc.mission = Some(*sp);
        let flying = !matches!(sp.phase, MissionPhase::Idle);
        let idx = sp.phase_index;
        if !flying || acc.phase_index == Some(idx) {
            return None;
        }
        acc.phase_index = Some(idx);
        let t_s = self.sim_s(sp.phase_start_ns)?;
        let i = idx as usize;
        let rec = self.phases.get_mut(i)?;
        rec.start_s[k] = Some(t_s);
        Some((i, self.phase_names[i].clone(), t_s))
    }

    /// Drone `k`'s true anchor force (TENSION_TRUTH).
    pub fn on_force_truth(&mut self, k: usize, s: &TensionSample) {
        self.forces.on_truth_tension(k, s);
    }

    /// A sample of drone `k`'s force sensor (TENSION) or estimator (TENSION_ESTIMATE).
    pub fn on_force_sample(&mut self, k: usize, source: ForceSource, s: &TensionSample) {
        self.forces.on_sample(k, source, s);
    }

    /// A controller output of drone `k` (carries its inputs' times and T_d, T_f).
    pub fn on_setpoint(&mut self, k: usize, sp: &AttitudeSetpoint, realtime: bool) {
        self.forces.on_setpoint(k, sp);
        let acc = &mut self.drones[k];
        acc.setpoints += 1;
        if sp.flags & shared_types::setpoint_flags::POSITION_ONLY != 0
            && sp.flags & shared_types::setpoint_flags::IDLE == 0
        {
            acc.position_only += 1;
        }
        // Latency of flight setpoints only: before arming PX4 streams odometry at its 30 Hz
        // default and the controller runs on its fallback deadline.
        if realtime && sp.flags & shared_types::setpoint_flags::IDLE == 0 {
            let t = sp.header.t_publish_ns;
            if sp.tension_origin_ns > 0 {
                self.spans
                    .record_span(SPANS[2 * k], sp.tension_origin_ns, t);
            }
            if sp.odometry_origin_ns > 0 {
                self.spans
                    .record_span(SPANS[2 * k + 1], sp.odometry_origin_ns, t);
            }
        }
        // Tension tracking against the truth of the same instant (the newest truth sample).
        let Some(truth) = &self.last_truth else {
            return;
        };
        let loop_on = acc
            .mission
            .is_some_and(|m| m.flags & shared_types::mission_flags::TENSION_ENABLED != 0);
        let td = Vector3::from(sp.tension_desired_ned_n);
        if loop_on && td.norm() > 0.0 {
            let d = &truth.drones[k];
            let q = quat(d.body.attitude_wxyz);
            let t_true = -(q * Vector3::from(d.anchor_force_frd_n));
            let e = (t_true - td).norm_squared();
            if e.is_finite() {
                acc.tension_sq += e;
                acc.n_tension += 1;
            }
        }
    }

    /// One ground-truth sample (100 Hz in real time; every 10 ms of simulated time in fast mode).
    pub fn on_truth(&mut self, truth: &PlantTruth) {
        if self.clock_offset_ns.is_none() {
            self.clock_offset_ns =
                Some(truth.header.t_origin_ns as i128 - truth.sim_time_ns as i128);
        }
        let t_s = truth.sim_time_ns as f64 * 1e-9;
        self.forces.on_truth(truth);
        for c in truth.cable_tension_n {
            if c.is_finite() {
                self.max_cable_force_n = self.max_cable_force_n.max(c);
            }
        }
        // Payload support: lift-off is the first instant it leaves the box it started on.
        let on_support = truth.payload_contact != ContactKind::Free;
        if self.started_on_support.is_none() {
            self.started_on_support = Some(on_support);
        }
        if self.started_on_support == Some(true) && !on_support && self.lifted_at_s.is_none() {
            self.lifted_at_s = Some(t_s);
        }
        for k in 0..2 {
            let acc = &mut self.drones[k];
            let Some(m) = acc.mission else { continue };
            if matches!(m.phase, MissionPhase::Idle) {
                continue;
            }
            let p = Vector3::from(truth.drones[k].body.position_ned_m);
            let e = p - Vector3::from(m.position_ned_m);
            if e.iter().all(|v| v.is_finite()) {
                acc.sq_err += e.norm_squared();
                acc.n_err += 1;
                acc.final_err = Some(e.norm());
                let est = Vector3::from(truth.drones[k].estimate_position_ned_m);
                acc.final_estimate_err = Some((est - Vector3::from(m.position_ned_m)).norm());
                acc.z_err.push((t_s, e.z, m.phase_index));
            }
        }
        let swing = self.swing_deg(truth);
        if swing.is_finite() {
            self.swing.push((t_s, swing));
        }
        self.last_truth = Some(*truth);
    }

    fn swing_deg(&self, t: &PlantTruth) -> f64 {
        swing_deg(t, self.anchor_frd_m.into())
    }

    /// Start of the first Move phase by either drone, s.
    fn first_move_s(&self) -> Option<f64> {
        self.phases
            .iter()
            .filter(|p| self.phase_is_move.get(p.index) == Some(&true))
            .find_map(|p| p.start_s.iter().flatten().copied().reduce(f64::min))
    }

    /// The metrics so far, with the plant's failsafe and crash record from the last truth.
    pub fn finish(&self) -> FlightMetrics {
        let truth = self.last_truth.unwrap_or_default();
        let last_move = self.phase_is_move.iter().rposition(|m| *m);
        let next_move_start = last_move
            .and_then(|i| self.phases.get(i + 1..))
            .and_then(|rest| {
                rest.iter()
                    .filter(|p| self.phase_is_move.get(p.index) == Some(&true))
                    .find_map(|p| p.start_s[0])
            });
        let drones = (0..2)
            .map(|k| {
                let a = &self.drones[k];
                let rms = |s: f64, n: u64| (n > 0).then(|| (s / n as f64).sqrt());
                let z_ss = last_move.and_then(|mi| {
                    let in_move: Vec<_> = a
                        .z_err
                        .iter()
                        .filter(|(_, _, p)| *p as usize >= mi)
                        .collect();
                    let end = next_move_start.or_else(|| in_move.last().map(|(t, _, _)| *t))?;
                    let w: Vec<f64> = in_move
                        .iter()
                        .filter(|(t, _, _)| *t <= end && *t > end - STEADY_WINDOW_S)
                        .map(|(_, z, _)| *z)
                        .collect();
                    (!w.is_empty()).then(|| w.iter().sum::<f64>() / w.len() as f64)
                });
                DroneMetrics {
                    id: self.ids[k].clone(),
                    position_rmse_m: rms(a.sq_err, a.n_err),
                    z_steady_state_error_m: z_ss,
                    tension_rmse_n: rms(a.tension_sq, a.n_tension),
                    final_position_error_m: a.final_err,
                    final_estimate_error_m: a.final_estimate_err,
                    failsafe_count: truth.drones[k].failsafe_count,
                    crash_flags: truth.drones[k].crash_flags,
                    position_only_steps: a.position_only,
                    setpoints: a.setpoints,
                    force_rmse: self.forces.rmse(k),
                }
            })
            .collect();
        let swing_from_s = self.lifted_at_s.or_else(|| {
            (self.started_on_support == Some(false))
                .then(|| self.first_move_s())
                .flatten()
        });
        let window: Vec<(f64, f64)> = swing_from_s
            .map(|t0| {
                self.swing
                    .iter()
                    .filter(|(t, _)| *t >= t0)
                    .copied()
                    .collect()
            })
            .unwrap_or_default();
        let n = window.len() as f64;
        let settling_time_s = swing_from_s.and_then(|t0| {
            let last_above = window
                .iter()
                .rev()
                .find(|(_, s)| s.abs() >= SWING_SETTLED_DEG);
            match last_above {
                None => Some(0.0),
                // Above at the very end: not settled.
                Some((t, _)) if Some(t) == window.last().map(|(t, _)| t) => None,
                Some((t, _)) => Some(t - t0),
            }
        });
        let payload = PayloadMetrics {
            lifted_at_s: self.lifted_at_s,
            swing_from_s,
            swing_rms_deg: (n > 0.0)
                .then(|| (window.iter().map(|(_, s)| s * s).sum::<f64>() / n).sqrt()),
            swing_max_deg: window.iter().map(|(_, s)| s.abs()).reduce(f64::max),
            settling_time_s,
            final_swing_deg: window.last().map(|(_, s)| *s),
        };
        FlightMetrics {
            phases: self.phases.clone(),
            drones,
            payload,
            max_cable_force_n: self.max_cable_force_n,
            latency_us: self.spans.summary(),
            failsafe_fired: truth.drones.iter().any(|d| d.failsafe_count > 0),
            crashed: truth.drones.iter().any(|d| d.crash_flags != 0),
        }
    }
}

#[cfg(test)]
#[path = "metrics_tests.rs"]
mod tests;
