//! The sampler: reads four MCP3423s into [`RawAdcFrame`]s, one conversion of each chip per
//! frame, at the chips' own rate.
//!
//! Rate-aware polling: the sampler learns when each chip's next conversion will finish,
//! sleeps until just before it and then polls that chip's RDY bit every `poll_interval`, so each
//! conversion is timestamped to within one poll interval without polling the bus continuously.
//! A frame is complete when every chip has delivered a new result; a chip that has not by the
//! frame deadline is marked stale (its last code is repeated), a chip whose transfers keep
//! failing is marked as a bus error; the loop never stops for either.
//!
//! - Continuous: a general-call reset starts all chips in phase; each then free-runs on its own
//!   oscillator, so their phases drift apart (the inter-channel skew the frames record).
//! - Synchronous: every frame starts with a general-call conversion, which starts all four
//!   one-shot conversions at the same instant; the frame period is one conversion plus polling.

use crate::mcp3423::{self, Config as ChipConfig, Mcp3423, Mode};
use embedded_hal::i2c::I2c;
use shared_types::{ChannelStatus, Header, RawAdcFrame, SamplingMode};

/// Where the sampler gets time and sleeps: CLOCK_MONOTONIC in the service, a simulated
/// clock in tests.
pub trait Clock {
    fn now_ns(&mut self) -> u64;
    fn sleep_until_ns(&mut self, t_ns: u64);
}

/// Timing and retry settings of a [`Sampler`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplerSettings {
    pub mode: SamplingMode,
    /// Nominal conversion time at 240 SPS, ns.
    pub conversion_ns: u64,
    /// Retries of a failed transfer before the channel is flagged for this frame.
    pub retries: u32,
    /// RDY polling interval once a result is due, ns.
    pub poll_interval_ns: u64,
    /// How long before a result is due the polling starts, ns.
    pub lead_ns: u64,
    /// Extra time past the last expected result before a frame is closed, ns.
    pub grace_ns: u64,
}

impl SamplerSettings {
    /// Defaults for `rate_hz` (240 on the MCP3423 at 12 bits).
    pub fn new(mode: SamplingMode, rate_hz: f64, retries: u32) -> Self {
        let conversion_ns = (1e9 / rate_hz).round() as u64;
        Self {
            mode,
            conversion_ns,
            retries,
            poll_interval_ns: 100_000,
            lead_ns: 250_000,
            grace_ns: conversion_ns / 4,
        }
    }
}

/// What a sampler has counted since it started.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SamplerCounters {
    pub frames: u64,
    /// Failed transfers, each retry counted.
    pub bus_errors: u64,
    /// Frames with at least one stale or bus-error channel.
    pub degraded_frames: u64,
    /// RDY polls that found no new result.
    pub not_ready_polls: u64,
}

#[derive(Debug, Clone, Copy)]
struct Track {
    /// When to poll next, ns: the predicted finish, or sooner while polling for it.
    next_due_ns: u64,
    /// When the next conversion should finish by the learned phase and period, ns.
    predicted_finish_ns: u64,
    /// Learned conversion period of this chip, ns.
    period_ns: f64,
    last_finish_ns: Option<u64>,
    last_poll_ns: u64,
    /// A poll found no new result since this chip's last one: the next edge will be seen.
    saw_not_ready: bool,
    /// How long before the predicted finish polling starts, ns (widened after a missed edge).
    lead_ns: u64,
    last_code: i16,
    last_conversion_ns: u64,
}

/// Four chips, a handle for the general call, and what the sampler has learned about them.
pub struct Sampler<I2C: I2c> {
    chips: [Mcp3423<I2C>; 4],
    general_call: I2C,
    settings: SamplerSettings,
    tracks: [Track; 4],
    counters: SamplerCounters,
    sequence: u64,
}

impl<I2C: I2c> Sampler<I2C> {
    /// `chips[j]` reads cell j+1; `general_call` is any handle on the same bus (on Linux its
    /// own `I2cdev`, since one reopens the device when the address changes).
    pub fn new(chips: [Mcp3423<I2C>; 4], general_call: I2C, settings: SamplerSettings) -> Self {
        let track = Track {
            next_due_ns: 0,
            predicted_finish_ns: 0,
            period_ns: settings.conversion_ns as f64,
            last_finish_ns: None,
            last_poll_ns: 0,
            saw_not_ready: false,
            lead_ns: settings.lead_ns,
            last_code: 0,
            last_conversion_ns: 0,
        };
        Self {
            chips,
            general_call,
            settings,
            tracks: [track; 4],
            counters: SamplerCounters::default(),
            sequence: 0,
        }
    }

    pub fn counters(&self) -> SamplerCounters {
        self.counters
    }

    pub fn settings(&self) -> &SamplerSettings {
        &self.settings
    }

    /// Resets the chips together and configures them for the mode. Failures are counted, not
    /// fatal: a chip that missed its configuration shows up as stale or a bus error later.
    pub fn start(&mut self, clock: &mut impl Clock) {
        let retries = self.settings.retries;
        // A failed reset is counted; chips that missed it show up as stale or bus errors.
        let _ = with_retries(retries, &mut self.counters, || {
            mcp3423::general_call_reset(&mut self.general_call)
        });
        let t0 = clock.now_ns();
        let cfg = ChipConfig {
            mode: match self.settings.mode {
                SamplingMode::Continuous => Mode::Continuous,
                SamplingMode::Synchronous => Mode::OneShot,
            },
            ..ChipConfig::default()
        };
        for chip in &mut self.chips {
            chip.assume_power_on();
            if self.settings.mode == SamplingMode::Synchronous {
                // Continuous chips are already in their power-on config 0x90 after the reset:
                // writing it again would restart them one by one, out of phase.
                let _ = with_retries(retries, &mut self.counters, || chip.configure(cfg));
            }
        }
        for t in &mut self.tracks {
            t.predicted_finish_ns = t0 + self.settings.conversion_ns;
            t.next_due_ns = t.predicted_finish_ns.saturating_sub(t.lead_ns);
            t.last_poll_ns = t0;
        }
    }

    /// Collects the next frame: blocks (through `clock`) until every chip has delivered a
    /// new result or the frame deadline has passed. `t_publish_ns` is left for the publisher.
    pub fn next_frame(&mut self, clock: &mut impl Clock) -> RawAdcFrame {
        let s = self.settings;
        let round_start = clock.now_ns();
        let mut start_ns = None;
        if s.mode == SamplingMode::Synchronous {
            let before = clock.now_ns();
            // If no conversion starts, the chips never become ready: the deadline below marks
            // them stale and the next frame tries again.
            let _ = with_retries(s.retries, &mut self.counters, || {
                mcp3423::general_call_conversion(&mut self.general_call)
            });
            // The chips start at the general call's stop condition, inside this interval.
            let t0 = before + (clock.now_ns() - before) / 2;
            start_ns = Some(t0);
            for t in &mut self.tracks {
                t.predicted_finish_ns = t0 + s.conversion_ns;
                t.next_due_ns = t.predicted_finish_ns.saturating_sub(t.lead_ns);
                t.last_poll_ns = t0;
                t.saw_not_ready = false;
            }
        }
        // Close the frame a little after the last result is due (never before one nominal
        // period, never after two), so one silent chip cannot stall the others.
        let latest_due = self.tracks.iter().map(|t| t.next_due_ns).max().unwrap_or(0);
        let deadline = latest_due.clamp(
            round_start + s.conversion_ns,
            round_start + 2 * s.conversion_ns,
        ) + s.grace_ns;

        let mut pending = [true; 4];
        let mut status = [ChannelStatus::Stale; 4];
        // Every chip is polled at its predicted edge, also one already collected for this
        // frame (a newer result replaces the older), so each edge is seen as it happens and
        // timestamped to within a poll interval. The frame closes when none is pending.
        while pending.iter().any(|&p| p) {
            let Some(c) = (0..4)
                .filter(|&c| status[c] != ChannelStatus::BusError)
                .min_by_key(|&c| self.tracks[c].next_due_ns)
            else {
                break;
            };
            let wake = self.tracks[c].next_due_ns;
            if wake >= deadline {
                break;
            }
            if wake > clock.now_ns() {
                clock.sleep_until_ns(wake);
            }
            // The chip answers with its state at the start of the transfer.
            let now = clock.now_ns();
            let result = with_retries(s.retries, &mut self.counters, || self.chips[c].read_ready());
            let track = &mut self.tracks[c];
            match result {
                Ok(Some(reading)) => {
                    let period = (track.period_ns as u64).max(1);
                    let finish = if track.saw_not_ready {
                        // The edge lies between the previous poll and this one: learn from it.
                        let finish = track.last_poll_ns + (now - track.last_poll_ns) / 2;
                        if let Some(prev) = track.last_finish_ns {
                            let interval = finish.saturating_sub(prev) as f64;
                            let periods = (interval / track.period_ns).round().max(1.0);
                            let one = interval / periods;
                            if (0.8..1.25).contains(&(one / track.period_ns)) {
                                track.period_ns += 0.2 * (one - track.period_ns);
                            }
                        }
                        track.lead_ns = (track.lead_ns * 15 / 16).max(s.lead_ns);
                        finish
                    } else {
                        // Ready at the first poll: the edge was missed. Place it on the learned
                        // schedule (the newest scheduled finish not after now), learn nothing,
                        // and start polling earlier next time.
                        track.lead_ns = (track.lead_ns * 2).min(period / 2);
                        // (A schedule still ahead of now was merely late: the edge was just now.)
                        let p = track.predicted_finish_ns;
                        let newest = if p <= now {
                            p + (now - p) / period * period
                        } else {
                            now
                        };
                        newest.max(track.last_poll_ns)
                    };
                    track.saw_not_ready = false;
                    track.last_finish_ns = Some(finish);
                    track.predicted_finish_ns = finish + period;
                    track.next_due_ns = track.predicted_finish_ns.saturating_sub(track.lead_ns);
                    track.last_code = reading.code as i16;
                    // One-shot: the window opened at the general call, exactly.
                    track.last_conversion_ns = match start_ns {
                        Some(t0) => t0 + s.conversion_ns / 2,
                        None => finish.saturating_sub(period / 2),
                    };
                    status[c] = if reading.saturated {
                        ChannelStatus::Saturated
                    } else {
                        ChannelStatus::Fresh
                    };
                    pending[c] = false;
                }
                Ok(None) => {
                    self.counters.not_ready_polls += 1;
                    track.saw_not_ready = true;
                    track.next_due_ns = now + s.poll_interval_ns;
                }
                Err(()) => {
                    status[c] = ChannelStatus::BusError;
                    pending[c] = false;
                    track.saw_not_ready = false;
                    track.predicted_finish_ns += track.period_ns as u64;
                    track.next_due_ns = track.predicted_finish_ns.max(now);
                }
            }
            track.last_poll_ns = now;
            if clock.now_ns() >= deadline {
                break;
            }
        }
        // Chips still pending are stale; look for them again one period on.
        let now = clock.now_ns();
        for (track, _) in self.tracks.iter_mut().zip(pending).filter(|(_, p)| *p) {
            if track.next_due_ns <= now {
                track.next_due_ns = now + s.poll_interval_ns;
            }
        }

        if status
            .iter()
            .any(|st| matches!(st, ChannelStatus::Stale | ChannelStatus::BusError))
        {
            self.counters.degraded_frames += 1;
        }
        let conversion_ns = self.tracks.map(|t| t.last_conversion_ns);
        // The frame is as old as what was measured for it; a stale channel's old time would
        // make it look older than it is.
        let measured = (0..4)
            .filter(|&c| matches!(status[c], ChannelStatus::Fresh | ChannelStatus::Saturated));
        let (sum, n) = measured.fold((0u64, 0u64), |(s, n), c| (s + conversion_ns[c], n + 1));
        let t_origin_ns = sum.checked_div(n).unwrap_or(now);
        let frame = RawAdcFrame {
            header: Header {
                sequence: self.sequence,
                t_origin_ns,
                t_publish_ns: 0,
            },
            codes: self.tracks.map(|t| t.last_code),
            status,
            conversion_ns,
            bus_errors: self.counters.bus_errors.min(u32::MAX as u64) as u32,
            stale_frames: self.counters.degraded_frames.min(u32::MAX as u64) as u32,
            mode: s.mode,
        };
        self.sequence += 1;
        self.counters.frames += 1;
        frame
    }
}

/// Runs `op` up to `1 + retries` times; counts every failure.
fn with_retries<T, E>(
    retries: u32,
    counters: &mut SamplerCounters,
    mut op: impl FnMut() -> Result<T, E>,
) -> Result<T, ()> {
    for _ in 0..=retries {
        match op() {
            Ok(v) => return Ok(v),
            Err(_) => counters.bus_errors += 1,
        }
    }
    Err(())
}
