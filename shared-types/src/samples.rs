use iceoryx2::prelude::ZeroCopySend;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The header every sample starts with (after PX4 uORB's `timestamp`/`timestamp_sample`).
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct Header {
    /// Per publisher, starts at 0, +1 per sample; a gap means a lost sample.
    pub sequence: u64,
    /// When the physical measurement this sample derives from was taken (CLOCK_MONOTONIC ns).
    /// Copied forward unchanged by every downstream stage.
    pub t_origin_ns: u64,
    /// When this sample was published (CLOCK_MONOTONIC ns).
    pub t_publish_ns: u64,
}

/// State of one ADC channel in a [`RawAdcFrame`].
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub enum ChannelStatus {
    /// A conversion finished since the previous frame; the code is new.
    #[default]
    Fresh = 0,
    /// No new conversion in time (chip silent or not ready); the code is the last good one.
    Stale = 1,
    /// The code sits at a rail (-2048 or +2047): the true value is out of range.
    Saturated = 2,
    /// The bus failed on this chip after the retries allowed within the period; the code is the
    /// last good one.
    BusError = 3,
}

impl ChannelStatus {
    /// True for a code that was measured this period and is in range.
    pub fn is_fresh(self) -> bool {
        self == ChannelStatus::Fresh
    }
}

/// Sampling mode of the four MCP3423s, as recorded in each frame.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub enum SamplingMode {
    /// Each chip free-runs at 240 SPS; channels may be up to one period apart.
    #[default]
    Continuous = 0,
    /// A general-call one-shot starts all four conversions at the same instant.
    Synchronous = 1,
}

/// One reading of the four load-cell ADCs (one MCP3423 per cell), published by `adc-sampler`.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct RawAdcFrame {
    /// `t_origin_ns` is the mean `conversion_ns` of the channels measured for this frame.
    pub header: Header,
    /// 12-bit two's-complement codes, -2048..=2047; 1 LSB = 1 mV at PGA gain 1.
    pub codes: [i16; 4],
    /// Per-channel state of `codes`.
    pub status: [ChannelStatus; 4],
    /// Per channel, the middle of the conversion window the code integrates over
    /// (CLOCK_MONOTONIC ns): the instant the code best represents.
    pub conversion_ns: [u64; 4],
    /// Bus errors since the sampler started, all channels (each retry that failed counts).
    pub bus_errors: u32,
    /// Frames in which at least one channel was stale, since the sampler started.
    pub stale_frames: u32,
    /// How the chips were sampled for this frame.
    pub mode: SamplingMode,
}

impl RawAdcFrame {
    /// Largest minus smallest `conversion_ns` among the channels: the inter-channel skew.
    pub fn skew_ns(&self) -> u64 {
        let max = self.conversion_ns.iter().max().copied().unwrap_or(0);
        let min = self.conversion_ns.iter().min().copied().unwrap_or(0);
        max - min
    }
}

/// Flags of a [`TensionSample`]; a bit set means the force is to be treated with care.
pub mod tension_flags {
    /// At least one input channel was saturated: the force is clipped.
    pub const SATURATED: u32 = 1 << 0;
    /// The cable pulls nearly sideways (|T_z| small against |T_xy|): lateral axes unreliable.
    pub const NEAR_SINGULARITY: u32 = 1 << 1;
    /// At least one input channel was stale or had a bus error: part of the input is old.
    pub const STALE_INPUT: u32 = 1 << 2;
    /// No calibration in the config: nominal constants were used.
    pub const CALIBRATION_MISSING: u32 = 1 << 3;
    /// The moving-average window is not full yet (start-up or after a reset).
    pub const FILTER_WARMUP: u32 = 1 << 4;
    /// A non-finite value appeared; the sample holds the last finite force.
    pub const NON_FINITE: u32 = 1 << 5;
    /// The input frame's sequence jumped: raw frames were lost.
    pub const INPUT_GAP: u32 = 1 << 6;
}

/// The cable force at the anchor, published by the `tension` stage at the sampler's rate.
///
/// Sign and frames, once for all of taut: `force_*_n` is the force the cable exerts **on the
/// drone** at the anchor (its pull), so a hanging load reads +z in FRD (down).
/// Sensor frame `S`: origin at the board centre, z towards the anchor (down when mounted), cells
/// 1..4 at (-d0,0,0), (0,-d0,0), (+d0,0,0), (0,+d0,0), anchor at (0,0,h). In it the paper's
/// equilibrium holds as written: T_z = -(f1+f2+f3+f4), T_x = -(d0/h)(f1-f3),
/// T_y = -(d0/h)(f2-f4), with a cell force f_j < 0 in tension.
#[repr(C)]
#[derive(
    Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize, JsonSchema,
)]
pub struct TensionSample {
    /// `t_origin_ns` is that of the newest raw frame in the filter window.
    pub header: Header,
    /// Calibrated, filtered normal force of each cell, N (negative = tension).
    pub cell_force_n: [f64; 4],
    /// Cable pull on the drone in the sensor frame `S`, N.
    pub force_sensor_n: [f64; 3],
    /// Cable pull on the drone in body FRD, N.
    pub force_body_n: [f64; 3],
    /// Bits of [`tension_flags`].
    pub flags: u32,
    /// Sequence of the newest raw frame used.
    pub raw_sequence: u64,
}
