//! An emulated MCP3423 (datasheet DS22088): a pure state machine. Time comes in as
//! CLOCK_MONOTONIC nanoseconds with every call; nothing here reads a clock, so tests can drive
//! it with any timeline.
//!
//! Modelled:
//! - Config byte bit 7..0: RDY, C1, C0, O/C, S1, S0, G1, G0; power-on 0x90 (continuous,
//!   12 bit / 240 SPS, gain x1, channel 1).
//! - Resolution S1S0 = 12/14/16/18 bit at 240/60/15/3.75 SPS, conversion period
//!   `1/SPS * (1 + osc_error)` with a per-chip oscillator error. LSB = 2*2.048 V / 2^bits
//!   (1 mV at 12 bit), divided by the PGA gain (1/2/4/8). Codes clamp at
//!   -2^(bits-1) ..= 2^(bits-1)-1.
//! - Continuous mode: conversions back to back from power-on, reset or the last config write.
//!   One-shot mode: writing a config byte with RDY = 1 (or a general-call conversion) starts
//!   one conversion, ready one period later. Any config write restarts/aborts the conversion
//!   in progress.
//! - Read: 2 data bytes (3 at 18 bit), big-endian two's complement sign-extended into the top
//!   bits, then the config byte repeated for as many bytes as are clocked. RDY = 0 in it only
//!   if a conversion finished since the result was last read; every config byte of one read
//!   shows the same state, and any read of at least one byte marks the result as read.
//! - General call: reset (0x06: power-on config, restart, output register cleared), latch
//!   (0x04: no-op here), conversion (0x08: one-shot mode starts one conversion; continuous
//!   mode restarts the back-to-back sequence at that instant, so all chips align).
//!
//! Our choices where the datasheet is silent: a config write leaves the old data in the output
//! register but marks it as read (RDY = 1 until the restarted conversion ends), so a driver
//! that polls after a write always gets a fresh result. The conversion result is the analog
//! input sampled at the midpoint of its conversion window (a delta-sigma converter averages
//! over the window; for inputs that vary slowly against 4 ms the midpoint is that average to
//! first order). When a caller skips several conversions only the latest is computed (the
//! earlier ones are overwritten unseen anyway) but all are counted. Channel 2 (C0 = 1) has its
//! inputs tied together on this board and reads 0 V. Input pins beyond the ADC range clamp.

/// Power-on config byte: RDY=1, channel 1, continuous, 12 bit, gain x1.
pub const POWER_ON_CONFIG: u8 = 0x90;
/// Nominal sample rates for S1S0 = 00, 01, 10, 11.
pub const NOMINAL_SPS: [f64; 4] = [240.0, 60.0, 15.0, 3.75];

const RDY: u8 = 0x80;
const OC: u8 = 0x10;

/// The time span a conversion result represents.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConversionWindow {
    pub start_ns: u64,
    /// The instant at which the analog input was sampled.
    pub mid_ns: u64,
    pub end_ns: u64,
}

/// General-call commands (second byte after address 0x00).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeneralCall {
    /// 0x06: reset and latch the address pins.
    Reset,
    /// 0x04: latch the address pins.
    Latch,
    /// 0x08: start a conversion on every chip at once.
    Conversion,
}

impl GeneralCall {
    /// Decodes a general-call command byte; None for commands the MCP3423 does not know.
    pub fn from_byte(b: u8) -> Option<Self> {
        match b {
            0x06 => Some(GeneralCall::Reset),
            0x04 => Some(GeneralCall::Latch),
            0x08 => Some(GeneralCall::Conversion),
            _ => None,
        }
    }
}

/// Analog input callback: `(chip_index, t_ns) -> volts` at the ADC input (channel 1).
pub type InputFn<'a> = dyn FnMut(usize, u64) -> f64 + 'a;

/// One emulated MCP3423.
#[derive(Debug, Clone)]
pub struct Mcp3423 {
    index: usize,
    osc_error: f64,
    /// Config bits 6..0 (bit 7 is derived from `unread` when read).
    config: u8,
    /// Start of the current conversion sequence (continuous) or of the one-shot conversion.
    seq_start_ns: u64,
    /// A conversion is scheduled (always true in continuous mode unless stuck-halted).
    running: bool,
    /// Conversions completed since `seq_start_ns`.
    done_in_seq: u64,
    code: i32,
    window: Option<ConversionWindow>,
    unread: bool,
    conversions: u64,
    stuck: bool,
}

impl Mcp3423 {
    /// A chip powered on at `t_power_on_ns`; `index` is passed to the input callback.
    /// `osc_error` is the relative error of its oscillator (+0.002 = 0.2 % longer period).
    pub fn new(index: usize, osc_error: f64, t_power_on_ns: u64) -> Self {
        let osc_error = if osc_error.is_finite() && osc_error > -0.5 {
            osc_error
        } else {
            0.0
        };
        Mcp3423 {
            index,
            osc_error,
            config: POWER_ON_CONFIG & !RDY,
            seq_start_ns: t_power_on_ns,
            running: true,
            done_in_seq: 0,
            code: 0,
            window: None,
            unread: false,
            conversions: 0,
            stuck: false,
        }
    }

    pub fn index(&self) -> usize {
        self.index
    }

    pub fn osc_error(&self) -> f64 {
        self.osc_error
    }

    /// The config byte as a read returns it now (without advancing time).
    pub fn config_byte(&self) -> u8 {
        let rdy = if self.unread && !self.stuck { 0 } else { RDY };
        rdy | self.config
    }

    pub fn is_continuous(&self) -> bool {
        self.config & OC != 0
    }

    /// Resolution in bits: 12, 14, 16 or 18.
    pub fn resolution_bits(&self) -> u32 {
        12 + 2 * u32::from((self.config >> 2) & 0x3)
    }

    /// PGA gain: 1, 2, 4 or 8.
    pub fn pga_gain(&self) -> u32 {
        1 << (self.config & 0x3)
    }

    /// Conversion period in ns, including the oscillator error.
    pub fn period_ns(&self) -> f64 {
        let sps = NOMINAL_SPS[usize::from((self.config >> 2) & 0x3)];
        1e9 / sps * (1.0 + self.osc_error)
    }

    /// The code in the output register.
    pub fn result_code(&self) -> i32 {
        self.code
    }

    /// The window of the result in the output register (None before the first conversion).
    pub fn result_window(&self) -> Option<ConversionWindow> {
        self.window
    }

    /// Whether the output register holds a result not yet read.
    pub fn has_unread_result(&self) -> bool {
        self.unread && !self.stuck
    }

    /// Conversions completed since power-on.
    pub fn conversions(&self) -> u64 {
        self.conversions
    }

    pub fn is_stuck(&self) -> bool {
        self.stuck
    }

    /// The code for `volts` at the ADC input, with the current resolution and gain.
    pub fn volts_to_code(&self, volts: f64) -> i32 {
        let bits = self.resolution_bits();
        let lsb = 4.096 / f64::from(1u32 << bits);
        let x = (volts * f64::from(self.pga_gain()) / lsb).round();
        let max = (1i32 << (bits - 1)) - 1;
        let min = -(1i32 << (bits - 1));
        if x.is_nan() {
            0
        } else {
            // Clamp in f64 first: the cast saturates anyway, but this keeps the range exact.
            x.clamp(f64::from(min), f64::from(max)) as i32
        }
    }

    fn offset_ns(&self, periods: f64) -> u64 {
        self.seq_start_ns
            .saturating_add((periods * self.period_ns()).round().max(0.0) as u64)
    }

    /// Runs the conversions that have finished by `t_ns`.
    pub fn advance(&mut self, t_ns: u64, input: &mut InputFn<'_>) {
        if self.stuck || !self.running || t_ns < self.seq_start_ns {
            return;
        }
        let p = self.period_ns();
        // Completed = number of k with end(k) = start + round((k+1) p) <= t. Estimate in f64,
        // then fix up against the integer end times.
        let mut n = ((t_ns - self.seq_start_ns) as f64 / p).floor().max(0.0) as u64;
        // Bounded: the estimate is off by at most one (and times may saturate at u64::MAX).
        for _ in 0..3 {
            if n > 0 && self.offset_ns(n as f64) > t_ns {
                n -= 1;
            } else if self.offset_ns((n + 1) as f64) <= t_ns {
                n += 1;
            }
        }
        if !self.is_continuous() {
            n = n.min(1);
        }
        if n <= self.done_in_seq {
            return;
        }
        let k = (n - 1) as f64;
        let window = ConversionWindow {
            start_ns: self.offset_ns(k),
            mid_ns: self.offset_ns(k + 0.5),
            end_ns: self.offset_ns(k + 1.0),
        };
        // Channel 2's inputs are tied together on this board.
        let volts = if self.config & 0x20 == 0 {
            input(self.index, window.mid_ns)
        } else {
            0.0
        };
        self.code = self.volts_to_code(volts);
        self.window = Some(window);
        self.conversions += n - self.done_in_seq;
        self.done_in_seq = n;
        self.unread = true;
        if !self.is_continuous() {
            self.running = false;
        }
    }

    fn start_sequence(&mut self, t_ns: u64) {
        self.seq_start_ns = t_ns;
        self.done_in_seq = 0;
        self.running = true;
    }

    fn write_config(&mut self, byte: u8, t_ns: u64) {
        self.config = byte & !RDY;
        self.unread = false;
        if self.is_continuous() || byte & RDY != 0 {
            self.start_sequence(t_ns);
        } else {
            self.running = false;
        }
    }

    /// An I2C write addressed to this chip at `t_ns`: each byte is a config write (so the last
    /// one wins). An empty write (address probe) changes nothing.
    pub fn write(&mut self, bytes: &[u8], t_ns: u64, input: &mut InputFn<'_>) {
        self.advance(t_ns, input);
        for &b in bytes {
            self.write_config(b, t_ns);
        }
    }

    /// An I2C read of `buf.len()` bytes from this chip at `t_ns`.
    pub fn read(&mut self, buf: &mut [u8], t_ns: u64, input: &mut InputFn<'_>) {
        self.advance(t_ns, input);
        let cfg = self.config_byte();
        let mut data = [0u8; 3];
        let n = if self.resolution_bits() == 18 {
            data.copy_from_slice(&self.code.to_be_bytes()[1..]);
            3
        } else {
            let c = self.code.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16;
            data[..2].copy_from_slice(&c.to_be_bytes());
            2
        };
        for (i, b) in buf.iter_mut().enumerate() {
            *b = if i < n { data[i] } else { cfg };
        }
        if !buf.is_empty() {
            self.unread = false;
        }
    }

    /// A general-call command at `t_ns`.
    pub fn general_call(&mut self, cmd: GeneralCall, t_ns: u64, input: &mut InputFn<'_>) {
        self.advance(t_ns, input);
        match cmd {
            GeneralCall::Reset => {
                self.config = POWER_ON_CONFIG & !RDY;
                self.code = 0;
                self.window = None;
                self.unread = false;
                self.start_sequence(t_ns);
            }
            GeneralCall::Latch => {}
            GeneralCall::Conversion => {
                self.unread = false;
                self.start_sequence(t_ns);
            }
        }
    }

    /// Fault injection: a stuck chip still answers and takes config writes but never finishes
    /// a conversion (RDY reads 1, data frozen). Un-sticking restarts the conversion at `t_ns`.
    pub fn set_stuck(&mut self, stuck: bool, t_ns: u64, input: &mut InputFn<'_>) {
        if stuck && !self.stuck {
            self.advance(t_ns, input);
            self.stuck = true;
        } else if !stuck && self.stuck {
            self.stuck = false;
            self.unread = false;
            if self.running {
                self.start_sequence(t_ns);
            }
        }
    }
}

#[cfg(test)]
#[path = "mcp3423_tests.rs"]
mod tests;
