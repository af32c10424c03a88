//! Scenarios as files: the arena, the box and obstacles, the initial state of drones and payload,
//! and each drone's setpoint path per mission phase. `scenarios/test-a.toml` and
//! `scenarios/test-b.toml` (the paper's Test A and Test B) are built in.
//!
//! A phase ends (in the mission, and in the plant's own pilot; see [`PhaseTracker`]) when every path of the
//! phase has run to its end and both drones have stayed within `tolerance_m` of their setpoints
//! for `settle_s`; `timeout_s` bounds it.

mod path;
mod tracker;

use std::path::Path as FsPath;

use nalgebra::Vector3;
use serde::Deserialize;

pub use path::{Path, PathSample, Segment};
pub use tracker::{PhaseEvent, PhaseTracker, Readiness};

/// Test A, payload drop (paper VI).
pub const TEST_A: &str = include_str!("../../../scenarios/test-a.toml");
/// Test B, narrow passage (paper VI).
pub const TEST_B: &str = include_str!("../../../scenarios/test-b.toml");

/// The mission phase a scenario phase is (issue: Idle, Takeoff, Move, Hold, Land).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseKind {
    Takeoff,
    Move,
    Hold,
    Land,
}

/// An axis-aligned box, NED, m.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    pub name: String,
    pub center_ned_m: [f64; 3],
    pub half_extents_m: [f64; 3],
}

impl BoxSpec {
    /// True if `p` (NED) is inside the box grown by `margin_m` on every side.
    pub fn contains(&self, p: &Vector3<f64>, margin_m: f64) -> bool {
        (0..3).all(|k| (p[k] - self.center_ned_m[k]).abs() <= self.half_extents_m[k] + margin_m)
    }
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Arena {
    pub min_ned_m: [f64; 3],
    pub max_ned_m: [f64; 3],
}

/// How a drone starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DroneStart {
    /// Landed and disarmed, PX4 in Position mode.
    Ground,
    /// Armed and hovering in Position mode at its start position (as after a manual take-off).
    Hover,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DroneSpec {
    pub id: String,
    pub start: DroneStart,
    /// Centre of mass, NED, m (for `ground`, z is where it stands on its legs).
    pub position_ned_m: [f64; 3],
    pub yaw_deg: f64,
}

/// How the payload starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PayloadStart {
    /// At `position_ned_m`, at rest (e.g. on the box).
    Resting,
    /// Hanging from both drones: placed below them and settled before the scenario starts.
    Hanging,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PayloadSpec {
    pub start: PayloadStart,
    /// Centre of mass, NED, m (for `hanging`, only a first guess is derived from the drones).
    #[serde(default)]
    pub position_ned_m: Option<[f64; 3]>,
    #[serde(default)]
    pub yaw_deg: f64,
}

/// A drone's path in one phase, starting where its previous setpoint ended.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    pub drone: String,
    pub segments: Vec<Segment>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseSpec {
    pub name: String,
    pub kind: PhaseKind,
    /// Both drones within this distance of their setpoints ...
    #[serde(default = "default_tolerance")]
    pub tolerance_m: f64,
    /// ... for this long ends the phase (after every path has finished).
    #[serde(default = "default_settle")]
    pub settle_s: f64,
    /// The phase fails if it has not ended after this long.
    pub timeout_s: f64,
    /// A drone without a path holds its previous setpoint.
    #[serde(default)]
    pub paths: Vec<PathSpec>,
}

fn default_tolerance() -> f64 {
    0.3
}
fn default_settle() -> f64 {
    1.0
}

/// A whole scenario file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub arena: Arena,
    /// Physical boxes the payload can rest on.
    #[serde(default)]
    pub boxes: Vec<BoxSpec>,
    /// Keep-out volumes: a drone inside one has crashed.
    #[serde(default)]
    pub obstacles: Vec<BoxSpec>,
    pub payload: PayloadSpec,
    pub drones: [DroneSpec; 2],
    pub phases: Vec<PhaseSpec>,
    /// Time after the last phase ends that the flight goes on (e.g. to watch the swing), s.
    #[serde(default)]
    pub linger_s: f64,
}

/// Why a scenario was rejected; every message names the key or value.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    #[error("cannot read scenario {path}: {source}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    #[error("scenario {name}: {message}")]
    Parse { name: String, message: String },
    #[error("scenario {name}: {key} = {value}: {why}")]
    Invalid {
        name: String,
        key: String,
        value: String,
        why: &'static str,
    },
    #[error("unknown built-in scenario {0:?} (known: test-a, test-b)")]
    Unknown(String),
}

impl Scenario {
    /// `test-a` / `test-b`, or a path to a TOML file.
    pub fn load(name_or_path: &str) -> Result<Self, ScenarioError> {
        match name_or_path {
            "test-a" => Self::from_toml_str("test-a", TEST_A),
            "test-b" => Self::from_toml_str("test-b", TEST_B),
            p if p.ends_with(".toml") || FsPath::new(p).exists() => {
                let text = std::fs::read_to_string(p).map_err(|source| ScenarioError::Read {
                    path: p.to_string(),
                    source,
                })?;
                Self::from_toml_str(p, &text)
            }
            other => Err(ScenarioError::Unknown(other.to_string())),
        }
    }

    pub fn from_toml_str(origin: &str, text: &str) -> Result<Self, ScenarioError> {
        let s: Scenario = toml::from_str(text).map_err(|e| ScenarioError::Parse {
            name: origin.to_string(),
            message: e.to_string(),
        })?;
        s.validate()?;
        Ok(s)
    }

    fn invalid(&self, key: String, value: String, why: &'static str) -> ScenarioError {
        ScenarioError::Invalid {
            name: self.name.clone(),
            key,
            value,
            why,
        }
    }

    /// Checks what serde cannot: finite numbers, known drone ids, positive durations, the
    /// arena containing every start and setpoint.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let finite3 = |a: &[f64; 3]| a.iter().all(|v| v.is_finite());
        for (k, d) in self.drones.iter().enumerate() {
            if !finite3(&d.position_ned_m) || !d.yaw_deg.is_finite() {
                return Err(self.invalid(
                    format!("drones[{k}].position_ned_m"),
                    format!("{:?}", d.position_ned_m),
                    "must be finite",
                ));
            }
            if !self.in_arena(&path::v3(d.position_ned_m)) {
                return Err(self.invalid(
                    format!("drones[{k}].position_ned_m"),
                    format!("{:?}", d.position_ned_m),
                    "outside the arena",
                ));
            }
        }
        if self.drones[0].id == self.drones[1].id {
            return Err(self.invalid(
                "drones[1].id".into(),
                self.drones[1].id.clone(),
                "both drones have the same id",
            ));
        }
        if self.payload.start == PayloadStart::Resting && self.payload.position_ned_m.is_none() {
            return Err(self.invalid(
                "payload.position_ned_m".into(),
                "missing".into(),
                "a resting payload needs a position",
            ));
        }
        if self.phases.is_empty() {
            return Err(self.invalid("phases".into(), "[]".into(), "needs a phase"));
        }
        for (i, ph) in self.phases.iter().enumerate() {
            let bad_num = |v: f64| !(v.is_finite() && v > 0.0);
            for (key, v) in [
                ("tolerance_m", ph.tolerance_m),
                ("settle_s", ph.settle_s),
                ("timeout_s", ph.timeout_s),
            ] {
                if bad_num(v) {
                    return Err(self.invalid(
                        format!("phases[{i}].{key}"),
                        v.to_string(),
                        "must be positive and finite",
                    ));
                }
            }
            for (j, p) in ph.paths.iter().enumerate() {
                if self.drone_index(&p.drone).is_none() {
                    return Err(self.invalid(
                        format!("phases[{i}].paths[{j}].drone"),
                        p.drone.clone(),
                        "no drone has this id",
                    ));
                }
                if p.segments
                    .iter()
                    .any(|s| !s.duration_s().is_finite() || s.duration_s() < 0.0)
                {
                    return Err(self.invalid(
                        format!("phases[{i}].paths[{j}].segments"),
                        format!("{:?}", p.segments),
                        "durations must be >= 0 and finite",
                    ));
                }
            }
        }
        for k in 0..2 {
            let mut at = self.takeoff_point(k);
            for (i, ph) in self.phases.iter().enumerate() {
                let path = self.path(i, k, at);
                let end = path.end();
                if !self.in_arena(&end) || !end.iter().all(|v| v.is_finite()) {
                    return Err(self.invalid(
                        format!(
                            "phases[{i}] ({}) setpoint of {}",
                            ph.name, self.drones[k].id
                        ),
                        format!("{:?}", end.as_slice()),
                        "ends outside the arena",
                    ));
                }
                at = end;
            }
        }
        Ok(())
    }

    pub fn drone_index(&self, id: &str) -> Option<usize> {
        self.drones.iter().position(|d| d.id == id)
    }

    fn in_arena(&self, p: &Vector3<f64>) -> bool {
        (0..3).all(|k| {
            p[k] >= self.arena.min_ned_m[k] - 1e-9 && p[k] <= self.arena.max_ned_m[k] + 1e-9
        })
    }

    /// Where drone `k`'s setpoint starts: its start position.
    pub fn takeoff_point(&self, k: usize) -> Vector3<f64> {
        path::v3(self.drones[k].position_ned_m)
    }

    /// Drone `k`'s path in phase `i`, starting at `from` (its previous setpoint).
    pub fn path(&self, i: usize, k: usize, from: Vector3<f64>) -> Path {
        let id = &self.drones[k].id;
        let segments = self.phases[i]
            .paths
            .iter()
            .filter(|p| &p.drone == id)
            .flat_map(|p| p.segments.iter().cloned())
            .collect();
        Path::new(from, segments)
    }

    /// Every phase's path for drone `k`, each starting where the previous ended.
    pub fn paths_of(&self, k: usize) -> Vec<Path> {
        let mut at = self.takeoff_point(k);
        (0..self.phases.len())
            .map(|i| {
                let p = self.path(i, k, at);
                at = p.end();
                p
            })
            .collect()
    }

    /// Yaw setpoint of drone `k`, rad (kept for the whole flight).
    pub fn yaw_rad(&self, k: usize) -> f64 {
        self.drones[k].yaw_deg.to_radians()
    }
}

#[cfg(test)]
mod tests;
