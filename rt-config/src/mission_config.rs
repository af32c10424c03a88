//! Config of the mission: the scenario and the zenoh link to the peer drone.

use serde::{Deserialize, Serialize};

/// Longest drone id a phase signal carries, bytes.
pub const MAX_DRONE_ID_LEN: usize = 16;

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
    /// A vehicle state older than this (its `t_origin_ns`) is stale: not ready, s.
    pub state_timeout_s: f64,
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
            state_timeout_s: 0.5,
        }
    }
}

fn is_id(s: &str) -> bool {
    !s.is_empty()
        && s.len() <= MAX_DRONE_ID_LEN
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
}

impl MissionConfig {
    /// Checks what serde cannot; each message names the key (`mission.<field>`).
    pub fn validate(&self) -> Result<(), String> {
        if self.scenario.is_empty() {
            return Err("key `mission.scenario` = \"\": name test-a, test-b or a file".into());
        }
        if !self.drone.is_empty() && !is_id(&self.drone) {
            return Err(format!(
                "key `mission.drone` = {:?}: at most {MAX_DRONE_ID_LEN} letters, digits, '-', '_'",
                self.drone
            ));
        }
        if !is_id(&self.peer) {
            return Err(format!(
                "key `mission.peer` = {:?}: 1..={MAX_DRONE_ID_LEN} letters, digits, '-', '_'",
                self.peer
            ));
        }
        if self.drone == self.peer {
            return Err(format!(
                "key `mission.peer` = {:?}: the same as mission.drone",
                self.peer
            ));
        }
        for (key, list) in [("listen", &self.listen), ("connect", &self.connect)] {
            for (i, e) in list.iter().enumerate() {
                let addr = e.strip_prefix("tcp/").unwrap_or("");
                if addr
                    .rsplit_once(':')
                    .is_none_or(|(h, p)| h.is_empty() || p.parse::<u16>().is_err())
                {
                    return Err(format!(
                        "key `mission.{key}[{i}]` = {e:?}: expected tcp/<host>:<port> (only TCP is built in)"
                    ));
                }
            }
        }
        if self.listen.is_empty() && self.connect.is_empty() {
            return Err("key `mission.connect` = []: with no listen endpoint either, the peer can never be reached".into());
        }
        let p = &self.key_prefix;
        if p.is_empty()
            || p.starts_with('/')
            || p.ends_with('/')
            || p.contains("//")
            || p.contains(['*', '$', '?', '#', ' '])
        {
            return Err(format!(
                "key `mission.key_prefix` = {p:?}: a zenoh key without wildcards or empty chunks"
            ));
        }
        if !(self.rate_hz.is_finite() && (1.0..=1000.0).contains(&self.rate_hz)) {
            return Err(format!(
                "key `mission.rate_hz` = {}: must be 1..=1000 Hz",
                self.rate_hz
            ));
        }
        let period_s = 1.0 / self.rate_hz;
        for (key, v) in [
            ("peer_timeout_s", self.peer_timeout_s),
            ("arm_timeout_s", self.arm_timeout_s),
            ("state_timeout_s", self.state_timeout_s),
        ] {
            if !(v.is_finite() && v >= 2.0 * period_s) {
                return Err(format!(
                    "key `mission.{key}` = {v}: must be finite and at least two ticks ({} s)",
                    2.0 * period_s
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bad(f: impl FnOnce(&mut MissionConfig)) -> String {
        let mut c = MissionConfig {
            drone: "uav1".into(),
            ..Default::default()
        };
        f(&mut c);
        c.validate().unwrap_err()
    }

    #[test]
    fn default_is_valid_and_bad_values_name_their_key() {
        MissionConfig::default().validate().unwrap();
        assert!(bad(|c| c.peer_timeout_s = 0.0).contains("mission.peer_timeout_s"));
        assert!(bad(|c| c.rate_hz = f64::NAN).contains("mission.rate_hz"));
        assert!(bad(|c| c.peer = "uav1".into()).contains("mission.peer"));
        assert!(bad(|c| c.peer = "x".repeat(17)).contains("mission.peer"));
        assert!(bad(|c| c.listen = vec!["udp/1.2.3.4:5".into()]).contains("mission.listen[0]"));
        assert!(bad(|c| c.connect = vec!["tcp/host".into()]).contains("mission.connect[0]"));
        assert!(bad(|c| c.key_prefix = "a/*".into()).contains("mission.key_prefix"));
        assert!(bad(|c| c.state_timeout_s = 0.001).contains("mission.state_timeout_s"));
    }
}
