//! Config of the mission: the scenario and the zenoh link to the peer drone.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MissionConfig {
    /// `test-a`, `test-b` (embedded) or a scenario file.
    pub scenario: String,
    /// This drone's id in the scenario (`uav1` | `uav2`); empty: the config's `uav`.
    pub drone: String,
    /// The peer's id: its phase signals are accepted, every other sender's ignored.
    pub peer: String,
    /// Zenoh endpoints this drone listens on, e.g. `tcp/127.0.0.1:7447`.
    pub listen: Vec<String>,
    /// Zenoh endpoints of the peer to connect to.
    pub connect: Vec<String>,
    /// Zenoh key prefix of the phase signals (`<prefix>/<drone id>`).
    pub key_prefix: String,
    /// Mission tick and phase-signal rate, Hz.
    pub rate_hz: f64,
    /// Not hearing the peer for this long means Hold, s.
    pub peer_timeout_s: f64,
    /// Both drones must be armed in offboard within this long of the arm request, s.
    pub arm_timeout_s: f64,
}

impl Default for MissionConfig {
    fn default() -> Self {
        Self {
            scenario: "test-a".to_string(),
            drone: String::new(),
            peer: "uav2".to_string(),
            listen: vec!["tcp/127.0.0.1:7447".to_string()],
            connect: vec!["tcp/127.0.0.1:7448".to_string()],
            key_prefix: "taut/mission".to_string(),
            rate_hz: 100.0,
            peer_timeout_s: 0.5,
            arm_timeout_s: 15.0,
        }
    }
}
