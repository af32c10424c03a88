//! Config of the recorder service (`[recorder]`): where its MCAP files go and how it chunks.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RecorderConfig {
    /// Whether `taut launch` starts the recorder.
    pub enabled: bool,
    /// Folder of the recordings (`<dir>/<uav>-<UTC time>.mcap`), created if missing.
    pub dir: String,
    /// A chunk is closed (flushed to disk) once it spans this long: the most a SIGKILL loses, s.
    pub chunk_period_s: f64,
    /// Samples each of the recorder's subscribers holds before the oldest are lost.
    pub buffer: usize,
}

impl Default for RecorderConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            dir: "recordings".to_string(),
            chunk_period_s: 1.0,
            buffer: 256,
        }
    }
}

/// The deepest buffer the topics allow (taut-ipc's `SUBSCRIBER_MAX_BUFFER`).
pub const RECORDER_MAX_BUFFER: usize = 256;

impl RecorderConfig {
    /// Checks what serde cannot; each message names the key (`recorder.<field>`).
    pub fn validate(&self) -> Result<(), String> {
        if self.dir.trim().is_empty() {
            return Err("key `recorder.dir` = \"\": name a folder for the recordings".into());
        }
        if !(self.chunk_period_s.is_finite() && (0.01..=60.0).contains(&self.chunk_period_s)) {
            return Err(format!(
                "key `recorder.chunk_period_s` = {}: must lie in 0.01..=60 s",
                self.chunk_period_s
            ));
        }
        if !(1..=RECORDER_MAX_BUFFER).contains(&self.buffer) {
            return Err(format!(
                "key `recorder.buffer` = {}: must be 1..={RECORDER_MAX_BUFFER} samples",
                self.buffer
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::Config;

    /// The embedded config with `line` first in its `[recorder]` section.
    fn with_recorder(line: &str) -> Result<Config, String> {
        let text = crate::EMBEDDED_SIM_CONFIG.replacen(
            "[recorder]\n",
            &format!("[recorder]\n{line}\n"),
            1,
        );
        assert_ne!(text, crate::EMBEDDED_SIM_CONFIG, "no [recorder] section");
        Config::from_toml_str(&text, "test.toml").map_err(|e| e.to_string())
    }

    #[test]
    fn defaults_and_overrides() {
        assert!(!Config::embedded_sim().recorder.enabled);
        assert!(super::RecorderConfig::default().enabled);
        let text =
            crate::EMBEDDED_SIM_CONFIG.replacen("chunk_period_s = 1.0", "chunk_period_s = 0.5", 1);
        let c = Config::from_toml_str(&text, "test.toml").unwrap();
        assert_eq!(c.recorder.chunk_period_s, 0.5);
        assert_eq!(c.recorder.buffer, 256);
        assert_eq!(c.recorder.dir, "recordings");
    }

    #[test]
    fn bad_values_name_their_key() {
        for (line, key) in [("enabled = false", "enabled"), ("dri = \"x\"", "dri")] {
            let err = with_recorder(line).unwrap_err();
            assert!(err.contains(key), "{line}: {err}");
        }
        for (from, to, key) in [
            (
                "chunk_period_s = 1.0",
                "chunk_period_s = 0.0",
                "recorder.chunk_period_s",
            ),
            ("buffer = 256", "buffer = 1000", "recorder.buffer"),
            ("dir = \"recordings\"", "dir = \"\"", "recorder.dir"),
        ] {
            let text = crate::EMBEDDED_SIM_CONFIG.replacen(from, to, 1);
            let err = Config::from_toml_str(&text, "t.toml")
                .unwrap_err()
                .to_string();
            assert!(err.contains(key), "{to}: {err}");
        }
    }
}
