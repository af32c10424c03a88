//! Offboard proof of life: when the setpoint stream counts as lost and when offboard counts as
//! available.
//!
//! What PX4 v1.16's code does (HealthAndArmingChecks/checks/offboardCheck.cpp): offboard is
//! available, and `offboard_control_signal_lost` false, exactly while the last
//! `offboard_control_mode` (published by every SET_ATTITUDE_TARGET that sets the attitude or
//! the roll and pitch rates) is younger than COM_OF_LOSS_T: `now < timestamp + COM_OF_LOSS_T`.
//! A single message is therefore enough to switch or arm, and the stream counts as lost at
//! exactly COM_OF_LOSS_T after the last message.
//!
//! What PX4's documentation promises (flight_modes/offboard.md): a "continuous 2 Hz proof of
//! life", and "PX4 enables offboard control only after receiving the signal for more than a
//! second". No such rate or duration test exists in the v1.16 sources we read; the plant can
//! still enforce it, which is stricter than PX4 and so catches a companion that switches too
//! early. We model it as: every gap between consecutive messages shorter than `1 / min_rate`
//! (rate strictly above 2 Hz), the latest message younger than `1 / min_rate`, and the current
//! unbroken run of such messages older than `min_duration` (strictly more than 1 s). A longer
//! gap restarts the run at the next message.
//!
//! Loss (the failsafe trigger) always follows PX4's code: COM_OF_LOSS_T after the last message.

use serde::Deserialize;

/// Which rule decides that offboard is available (for DO_SET_MODE, arming, and the return to
/// offboard after a loss failsafe).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(tag = "rule", rename_all = "snake_case", deny_unknown_fields)]
pub enum OffboardAvailability {
    /// The documented rule: a stream above `min_rate_hz` for more than `min_duration_s`.
    Documented {
        min_rate_hz: f64,
        min_duration_s: f64,
    },
    /// PX4 v1.16's code: the last proof of life is younger than COM_OF_LOSS_T.
    LastMessageAge,
}

impl Default for OffboardAvailability {
    fn default() -> Self {
        OffboardAvailability::Documented {
            min_rate_hz: 2.0,
            min_duration_s: 1.0,
        }
    }
}

/// Seconds to nanoseconds, rounded (inputs are validated finite and >= 0).
pub(crate) fn secs_to_ns(s: f64) -> u64 {
    (s * 1e9).round().max(0.0) as u64
}

/// Tracks the proof-of-life messages.
#[derive(Debug, Clone)]
pub(crate) struct OffboardStream {
    rule: OffboardAvailability,
    loss_timeout_ns: u64,
    /// Documented rule: longest gap that keeps a run going, and the run length needed.
    max_gap_ns: u64,
    min_duration_ns: u64,
    last_ns: Option<u64>,
    run_start_ns: u64,
}

impl OffboardStream {
    pub(crate) fn new(rule: OffboardAvailability, loss_timeout_s: f64) -> Self {
        let (max_gap_ns, min_duration_ns) = match rule {
            OffboardAvailability::Documented {
                min_rate_hz,
                min_duration_s,
            } => (secs_to_ns(1.0 / min_rate_hz), secs_to_ns(min_duration_s)),
            OffboardAvailability::LastMessageAge => (u64::MAX, 0),
        };
        OffboardStream {
            rule,
            loss_timeout_ns: secs_to_ns(loss_timeout_s),
            max_gap_ns,
            min_duration_ns,
            last_ns: None,
            run_start_ns: 0,
        }
    }

    /// Records a proof-of-life message at `t_ns`.
    pub(crate) fn on_message(&mut self, t_ns: u64) {
        let continues = self
            .last_ns
            .is_some_and(|last| t_ns.saturating_sub(last) < self.max_gap_ns);
        if !continues {
            self.run_start_ns = t_ns;
        }
        self.last_ns = Some(self.last_ns.map_or(t_ns, |last| last.max(t_ns)));
    }

    /// PX4's `offboard_control_signal_lost`: no message yet, or the last one is COM_OF_LOSS_T
    /// old or older.
    pub(crate) fn signal_lost(&self, t_ns: u64) -> bool {
        match self.last_ns {
            None => true,
            Some(last) => t_ns >= last.saturating_add(self.loss_timeout_ns),
        }
    }

    /// Whether offboard may be entered (or armed in) at `t_ns` under the configured rule.
    pub(crate) fn available(&self, t_ns: u64) -> bool {
        if self.signal_lost(t_ns) {
            return false;
        }
        match self.rule {
            OffboardAvailability::LastMessageAge => true,
            OffboardAvailability::Documented { .. } => {
                let last = self.last_ns.unwrap_or(0);
                t_ns.saturating_sub(last) < self.max_gap_ns
                    && t_ns.saturating_sub(self.run_start_ns) > self.min_duration_ns
            }
        }
    }

    /// Time of the last proof of life, ns.
    pub(crate) fn last_message_ns(&self) -> Option<u64> {
        self.last_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn stream_at(period_ms: u64, until_ms: u64) -> OffboardStream {
        let mut s = OffboardStream::new(OffboardAvailability::default(), 1.0);
        let mut t = 0;
        while t <= until_ms {
            s.on_message(t * MS);
            t += period_ms;
        }
        s
    }

    #[test]
    fn loss_is_exactly_com_of_loss_t_after_the_last_message() {
        let s = stream_at(10, 500);
        assert!(!s.signal_lost(1500 * MS - 1));
        assert!(s.signal_lost(1500 * MS));
        assert!(OffboardStream::new(OffboardAvailability::default(), 1.0).signal_lost(0));
    }

    #[test]
    fn documented_rule_needs_more_than_1_s_above_2_hz() {
        // 2.5 Hz (400 ms gaps) from t = 0: the run is 1.2 s old at the 1200 ms message.
        let s = stream_at(400, 1200);
        assert!(s.available(1200 * MS));
        // Exactly 1 s after the run started is not "more than a second".
        let s = stream_at(400, 800);
        assert!(!s.available(1000 * MS));
        assert!(s.available(1000 * MS + 1));
        // Exactly 2 Hz (500 ms gaps) is not above 2 Hz: every message restarts the run.
        let s = stream_at(500, 3000);
        assert!(!s.available(3000 * MS + 100 * MS));
        // A fast stream that goes quiet for 500 ms is no longer available, though not lost.
        let s = stream_at(10, 3000);
        assert!(s.available(3000 * MS + 499 * MS));
        assert!(!s.available(3000 * MS + 500 * MS));
        assert!(!s.signal_lost(3000 * MS + 500 * MS));
    }

    #[test]
    fn a_gap_restarts_the_run() {
        let mut s = stream_at(10, 2000);
        s.on_message(2600 * MS); // 600 ms gap
        for t in (2610..=3600).step_by(10) {
            s.on_message(t * MS);
        }
        assert!(!s.available(3600 * MS));
        s.on_message(3610 * MS);
        assert!(s.available(3610 * MS));
    }

    #[test]
    fn px4_code_rule_is_one_recent_message() {
        let mut s = OffboardStream::new(OffboardAvailability::LastMessageAge, 1.0);
        assert!(!s.available(0));
        s.on_message(5 * MS);
        assert!(s.available(5 * MS));
        assert!(s.available(1005 * MS - 1));
        assert!(!s.available(1005 * MS));
        assert_eq!(s.last_message_ns(), Some(5 * MS));
    }
}
