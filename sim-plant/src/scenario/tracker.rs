//! The phase logic of a scenario, pure: which phase is running, each drone's setpoint, and when
//! the phase ends (every path finished, then both drones within `tolerance_m` of their setpoints
//! for `settle_s`). The plant's own pilot uses it; the mission service runs the same rule with
//! the peer's readiness in place of the other drone's position.

use nalgebra::Vector3;

use super::{Path, PathSample, Scenario};

/// What one [`PhaseTracker::update`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhaseEvent {
    /// Still in the same phase.
    Running,
    /// Phase `finished` ended; phase `finished + 1` started (or the scenario is done).
    Ended { finished: usize },
    /// Phase `phase` did not end within its timeout.
    TimedOut { phase: usize },
}

/// Readiness of one drone in the current phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Readiness {
    /// The path of the phase has run to its end.
    pub path_done: bool,
    /// Time the drone has stayed within tolerance, s (0 when outside).
    pub within_s: f64,
}

/// Tracks the phases of a scenario for both drones. Allocates only in `new`.
#[derive(Debug, Clone)]
pub struct PhaseTracker {
    /// `paths[phase][drone]`.
    paths: Vec<[Path; 2]>,
    tolerance_m: Vec<f64>,
    settle_s: Vec<f64>,
    timeout_s: Vec<f64>,
    phase: usize,
    phase_start_s: f64,
    within_since_s: [Option<f64>; 2],
    /// Start time of each phase, s (NaN until it starts).
    starts_s: Vec<f64>,
    timed_out: bool,
}

impl PhaseTracker {
    /// Phase 0 starts at `t0_s`.
    pub fn new(scenario: &Scenario, t0_s: f64) -> Self {
        let (p0, p1) = (scenario.paths_of(0), scenario.paths_of(1));
        let paths = p0.into_iter().zip(p1).map(|(a, b)| [a, b]).collect();
        let n = scenario.phases.len();
        let mut starts_s = vec![f64::NAN; n];
        starts_s[0] = t0_s;
        PhaseTracker {
            paths,
            tolerance_m: scenario.phases.iter().map(|p| p.tolerance_m).collect(),
            settle_s: scenario.phases.iter().map(|p| p.settle_s).collect(),
            timeout_s: scenario.phases.iter().map(|p| p.timeout_s).collect(),
            phase: 0,
            phase_start_s: t0_s,
            within_since_s: [None; 2],
            starts_s,
            timed_out: false,
        }
    }

    /// Index of the running phase; equals the number of phases once all have ended.
    pub fn phase(&self) -> usize {
        self.phase
    }

    pub fn done(&self) -> bool {
        self.phase >= self.paths.len()
    }

    pub fn timed_out(&self) -> bool {
        self.timed_out
    }

    /// Start time of each phase, s (NaN if not reached).
    pub fn phase_starts_s(&self) -> &[f64] {
        &self.starts_s
    }

    /// Setpoint of drone `k` at `t_s` (after the last phase: the last setpoint).
    pub fn setpoint(&self, k: usize, t_s: f64) -> PathSample {
        match self.paths.get(self.phase) {
            Some(p) => p[k].sample(t_s - self.phase_start_s),
            None => self.paths[self.paths.len() - 1][k].sample(f64::INFINITY),
        }
    }

    /// Readiness of drone `k` at `t_s` given its position (NED).
    pub fn readiness(&mut self, k: usize, t_s: f64, position_ned: &Vector3<f64>) -> Readiness {
        let Some(paths) = self.paths.get(self.phase) else {
            return Readiness {
                path_done: true,
                within_s: f64::INFINITY,
            };
        };
        let path = &paths[k];
        let path_done = t_s - self.phase_start_s >= path.duration_s();
        let err = (path.sample(t_s - self.phase_start_s).position_ned_m - position_ned).norm();
        if path_done && err <= self.tolerance_m[self.phase] {
            let since = *self.within_since_s[k].get_or_insert(t_s);
            Readiness {
                path_done,
                within_s: t_s - since,
            }
        } else {
            self.within_since_s[k] = None;
            Readiness {
                path_done,
                within_s: 0.0,
            }
        }
    }

    /// Whether a drone with this readiness counts as ready in the running phase.
    pub fn is_ready(&self, r: &Readiness) -> bool {
        self.settle_s
            .get(self.phase)
            .is_some_and(|s| r.path_done && r.within_s >= *s)
    }

    /// Advances with both drones' positions (NED) at `t_s`.
    pub fn update(&mut self, t_s: f64, positions_ned: &[Vector3<f64>; 2]) -> PhaseEvent {
        if self.done() {
            return PhaseEvent::Running;
        }
        let r = [
            self.readiness(0, t_s, &positions_ned[0]),
            self.readiness(1, t_s, &positions_ned[1]),
        ];
        if self.is_ready(&r[0]) && self.is_ready(&r[1]) {
            return self.advance(t_s);
        }
        if t_s - self.phase_start_s > self.timeout_s[self.phase] && !self.timed_out {
            self.timed_out = true;
            return PhaseEvent::TimedOut { phase: self.phase };
        }
        PhaseEvent::Running
    }

    /// Ends the running phase at `t_s` (both drones ready) and starts the next.
    pub fn advance(&mut self, t_s: f64) -> PhaseEvent {
        let finished = self.phase;
        self.phase += 1;
        self.phase_start_s = t_s;
        self.within_since_s = [None; 2];
        if let Some(s) = self.starts_s.get_mut(self.phase) {
            *s = t_s;
        }
        PhaseEvent::Ended { finished }
    }
}
