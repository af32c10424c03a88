//! When each outbound stream is due: fixed intervals on the caller's clock, no catch-up bursts.

use super::config::{Stream, StreamRates};

/// What MAV_CMD_SET_MESSAGE_INTERVAL asked for one stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntervalRequest {
    /// Back to the configured default rate (param2 = 0).
    Default,
    /// Stop the stream (param2 = -1; PX4 treats any negative value so).
    Disable,
    /// Send every this many ns (param2 > 0, given in us).
    IntervalNs(u64),
}

impl IntervalRequest {
    /// Reads COMMAND_LONG param2 (interval in us); `None` if it is NaN or infinite.
    pub fn from_param_us(interval_us: f32) -> Option<IntervalRequest> {
        if !interval_us.is_finite() {
            return None;
        }
        Some(if interval_us < -0.5 {
            IntervalRequest::Disable
        } else if interval_us < 0.5 {
            IntervalRequest::Default
        } else {
            IntervalRequest::IntervalNs((f64::from(interval_us) * 1e3).round() as u64)
        })
    }
}

/// Per-stream interval and next due time.
///
/// A stream that is due is sent once; its next due time keeps the phase
/// (`due + interval`) so the mean rate is exact under a jittery caller, but if that is already
/// past (the caller stalled), it restarts from now: one frame after a stall, never a burst.
#[derive(Debug, Clone)]
pub struct StreamSchedule {
    default_interval_ns: [Option<u64>; Stream::COUNT],
    interval_ns: [Option<u64>; Stream::COUNT],
    next_due_ns: [Option<u64>; Stream::COUNT],
}

impl StreamSchedule {
    /// All streams at their default rates, each due at the first call.
    pub fn new(rates: &StreamRates) -> StreamSchedule {
        let defaults = Stream::ALL.map(|s| rates.interval_ns(s));
        StreamSchedule {
            default_interval_ns: defaults,
            interval_ns: defaults,
            next_due_ns: [None; Stream::COUNT],
        }
    }

    /// Current interval of `stream` in ns, `None` when disabled.
    pub fn interval_ns(&self, stream: Stream) -> Option<u64> {
        self.interval_ns[stream.index()]
    }

    /// Applies a SET_MESSAGE_INTERVAL request at time `t_ns`; a (re)enabled stream is due at once.
    pub fn set(&mut self, stream: Stream, request: IntervalRequest, t_ns: u64) {
        let i = stream.index();
        self.interval_ns[i] = match request {
            IntervalRequest::Default => self.default_interval_ns[i],
            IntervalRequest::Disable => None,
            IntervalRequest::IntervalNs(ns) => Some(ns.max(1)),
        };
        self.next_due_ns[i] = Some(t_ns);
    }

    /// True if `stream` is due at `t_ns`; if so, books its next due time.
    pub fn take_due(&mut self, stream: Stream, t_ns: u64) -> bool {
        let i = stream.index();
        let Some(interval) = self.interval_ns[i] else {
            return false;
        };
        let due = self.next_due_ns[i].unwrap_or(t_ns);
        if t_ns < due {
            return false;
        }
        let next = due.saturating_add(interval);
        self.next_due_ns[i] = Some(if next <= t_ns {
            t_ns.saturating_add(interval)
        } else {
            next
        });
        true
    }
}

#[cfg(test)]
#[path = "schedule_tests.rs"]
mod tests;
