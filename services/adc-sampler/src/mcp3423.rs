//! Blocking driver for the Microchip MCP3423 two-channel delta-sigma ADC (datasheet DS22088).
//!
//! Written because no maintained blocking embedded-hal 1.0 driver exists (the `mcp3424` crate is
//! async-only). The driver is generic over [`embedded_hal::i2c::I2c`], never allocates and never
//! panics on any byte pattern returned by the bus: every reply is decoded defensively.

use embedded_hal::i2c::I2c;

/// I2C general-call address: every MCP342x on the bus listens to it.
pub const GENERAL_CALL_ADDRESS: u8 = 0x00;
/// General call: reset every chip to the power-on config (0x90) and latch its address pins.
pub const GC_RESET: u8 = 0x06;
/// General call: latch the address pins again without resetting.
pub const GC_LATCH: u8 = 0x04;
/// General call: start a one-shot conversion on every chip at the same instant.
pub const GC_CONVERSION: u8 = 0x08;

/// Lowest 7-bit address (A2A1A0 = 000).
pub const ADDRESS_MIN: u8 = 0x68;
/// Highest 7-bit address (A2A1A0 = 111).
pub const ADDRESS_MAX: u8 = 0x6F;

/// Config byte written by the chip after power-on or a general-call reset.
pub const POWER_ON_CONFIG: u8 = 0x90;

/// Config-byte bit 7: on read, 1 = result not new; on write in one-shot mode, 1 = start.
const RDY_BIT: u8 = 0x80;
/// Everything in the config byte except RDY: what must match the configured state.
const SETTINGS_MASK: u8 = 0x7F;

/// Conversion mode (config bit 4, O/C).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Mode {
    /// Free-running conversions (O/C = 1); the power-on mode.
    #[default]
    Continuous,
    /// One conversion per start request, then power down (O/C = 0). Needed to sample several
    /// chips at the same instant with the general-call conversion.
    OneShot,
}

/// Sample rate and resolution (config bits 3..2, S1S0); they are tied together in the chip.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum SampleRate {
    /// 240 samples/s, 12 bit (S1S0 = 00); the power-on setting.
    #[default]
    Sps240Bits12,
    /// 60 samples/s, 14 bit (S1S0 = 01).
    Sps60Bits14,
    /// 15 samples/s, 16 bit (S1S0 = 10).
    Sps15Bits16,
    /// 3.75 samples/s, 18 bit (S1S0 = 11); the only mode with three data bytes.
    Sps3_75Bits18,
}

impl SampleRate {
    /// Resolution in bits, sign included.
    pub const fn bits(self) -> u32 {
        match self {
            SampleRate::Sps240Bits12 => 12,
            SampleRate::Sps60Bits14 => 14,
            SampleRate::Sps15Bits16 => 16,
            SampleRate::Sps3_75Bits18 => 18,
        }
    }

    /// Nominal data rate in samples per second (the chip's own clock: poll RDY, don't trust it).
    pub const fn samples_per_second(self) -> f64 {
        match self {
            SampleRate::Sps240Bits12 => 240.0,
            SampleRate::Sps60Bits14 => 60.0,
            SampleRate::Sps15Bits16 => 15.0,
            SampleRate::Sps3_75Bits18 => 3.75,
        }
    }

    /// Bytes in one read: data bytes plus the trailing config byte.
    pub const fn read_len(self) -> usize {
        match self {
            SampleRate::Sps3_75Bits18 => 4,
            _ => 3,
        }
    }

    /// Smallest code at this resolution (e.g. -2048 at 12 bit).
    pub const fn min_code(self) -> i32 {
        -(1 << (self.bits() - 1))
    }

    /// Largest code at this resolution (e.g. +2047 at 12 bit).
    pub const fn max_code(self) -> i32 {
        (1 << (self.bits() - 1)) - 1
    }

    const fn to_bits(self) -> u8 {
        match self {
            SampleRate::Sps240Bits12 => 0b00,
            SampleRate::Sps60Bits14 => 0b01,
            SampleRate::Sps15Bits16 => 0b10,
            SampleRate::Sps3_75Bits18 => 0b11,
        }
    }

    const fn from_bits(bits: u8) -> Self {
        match bits & 0b11 {
            0b00 => SampleRate::Sps240Bits12,
            0b01 => SampleRate::Sps60Bits14,
            0b10 => SampleRate::Sps15Bits16,
            _ => SampleRate::Sps3_75Bits18,
        }
    }
}

/// Programmable gain amplifier setting (config bits 1..0, G1G0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Gain {
    /// x1 (G1G0 = 00); the power-on setting.
    #[default]
    X1,
    /// x2 (G1G0 = 01).
    X2,
    /// x4 (G1G0 = 10).
    X4,
    /// x8 (G1G0 = 11).
    X8,
}

impl Gain {
    /// The amplification factor.
    pub const fn factor(self) -> u8 {
        match self {
            Gain::X1 => 1,
            Gain::X2 => 2,
            Gain::X4 => 4,
            Gain::X8 => 8,
        }
    }

    const fn to_bits(self) -> u8 {
        match self {
            Gain::X1 => 0b00,
            Gain::X2 => 0b01,
            Gain::X4 => 0b10,
            Gain::X8 => 0b11,
        }
    }

    const fn from_bits(bits: u8) -> Self {
        match bits & 0b11 {
            0b00 => Gain::X1,
            0b01 => Gain::X2,
            0b10 => Gain::X4,
            _ => Gain::X8,
        }
    }
}

/// Input channel (config bits 6..5, C1C0). The MCP3423 has two; C1 is only used by the MCP3424.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Channel {
    /// Channel 1 (C1C0 = 00); the power-on setting.
    #[default]
    Ch1,
    /// Channel 2 (C1C0 = 01).
    Ch2,
}

/// One configuration of the chip, i.e. the config byte without its RDY bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Config {
    pub mode: Mode,
    pub rate: SampleRate,
    pub gain: Gain,
    pub channel: Channel,
}

impl Config {
    /// Encodes the config byte. `start` sets RDY, which starts a conversion in one-shot mode
    /// (the chip ignores it in continuous mode).
    pub const fn to_byte(self, start: bool) -> u8 {
        let rdy = if start { RDY_BIT } else { 0 };
        let channel = match self.channel {
            Channel::Ch1 => 0b00,
            Channel::Ch2 => 0b01,
        };
        let mode = match self.mode {
            Mode::Continuous => 1,
            Mode::OneShot => 0,
        };
        rdy | (channel << 5) | (mode << 4) | (self.rate.to_bits() << 2) | self.gain.to_bits()
    }

    /// Decodes a config byte, ignoring RDY. Total: C1 (MCP3424 channels 3/4) is ignored and only
    /// C0 picks the channel, so compare raw bytes when an exact match matters.
    pub const fn from_byte(byte: u8) -> Config {
        Config {
            mode: if byte & 0x10 != 0 {
                Mode::Continuous
            } else {
                Mode::OneShot
            },
            rate: SampleRate::from_bits(byte >> 2),
            gain: Gain::from_bits(byte),
            channel: if byte & 0x20 != 0 {
                Channel::Ch2
            } else {
                Channel::Ch1
            },
        }
    }
}

/// One decoded read from the chip.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reading {
    /// Signed output code, sign-extended from the resolution's top bit.
    pub code: i32,
    /// RDY bit was 0: this is a new result not read before.
    pub ready: bool,
    /// Code at the minimum or maximum of the resolution: the input is out of range.
    pub saturated: bool,
    /// The raw config byte the chip returned after the data.
    pub config: u8,
}

impl Reading {
    /// Decodes a raw reply (`read_len` bytes) for the given sample rate. Returns `None` only if
    /// the buffer is too short.
    pub fn decode(rate: SampleRate, bytes: &[u8]) -> Option<Reading> {
        match (rate, bytes) {
            (SampleRate::Sps3_75Bits18, [b0, b1, b2, cfg, ..]) => Some(Self::from_raw(
                rate,
                u32::from_be_bytes([0, *b0, *b1, *b2]),
                *cfg,
            )),
            (SampleRate::Sps3_75Bits18, _) => None,
            (_, [b0, b1, cfg, ..]) => Some(Self::from_raw(
                rate,
                u32::from(u16::from_be_bytes([*b0, *b1])),
                *cfg,
            )),
            _ => None,
        }
    }

    /// Builds a reading from the big-endian data word and the config byte.
    fn from_raw(rate: SampleRate, raw: u32, config: u8) -> Reading {
        // Keep only the resolution's bits and sign-extend from the top one: the chip copies the
        // sign into the upper bits, but a glitch there must not turn into a huge value.
        let shift = 32 - rate.bits();
        let code = ((raw << shift) as i32) >> shift;
        Reading {
            code,
            ready: config & RDY_BIT == 0,
            saturated: code == rate.min_code() || code == rate.max_code(),
            config,
        }
    }

    /// Input voltage in volts for the rate and gain the reading was taken with:
    /// LSB = 2 * 2.048 V / 2^N / gain (1 mV at 12 bit, x1).
    pub fn volts(&self, rate: SampleRate, gain: Gain) -> f64 {
        let lsb = 2.0 * 2.048 / f64::from(1u32 << rate.bits()) / f64::from(gain.factor());
        f64::from(self.code) * lsb
    }
}

/// The requested address is not one the MCP3423 can have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("MCP3423 address {0:#04X} is outside 0x68..=0x6F")]
pub struct AddressError(pub u8);

/// Driver errors, generic over the bus error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Error<E: core::fmt::Debug> {
    /// The I2C transfer failed (NACK, arbitration loss, ...); the driver stays usable.
    #[error("MCP3423 I2C bus error: {0:?}")]
    Bus(E),
    /// The config byte read back differs from the configured one (RDY ignored): the chip was
    /// reset (power glitch, general-call reset) or another device answered.
    #[error(
        "MCP3423 returned config byte {got:#04X}, expected {expected:#04X} (RDY ignored): \
         chip reset or wrong device"
    )]
    UnexpectedConfig { expected: u8, got: u8 },
}

/// One MCP3423 at a fixed address. Remembers the last configuration written so that a read
/// knows its length and can check the config byte the chip sends back.
#[derive(Debug)]
pub struct Mcp3423<I2C> {
    i2c: I2C,
    address: u8,
    config: Config,
}

impl<I2C: I2c> Mcp3423<I2C> {
    /// Wraps a bus for the chip at `address` (0x68..=0x6F). Does no I/O: the chip is assumed
    /// to be in its power-on configuration until [`configure`](Self::configure) is called.
    pub fn new(i2c: I2C, address: u8) -> Result<Self, AddressError> {
        if !(ADDRESS_MIN..=ADDRESS_MAX).contains(&address) {
            return Err(AddressError(address));
        }
        Ok(Self {
            i2c,
            address,
            config: Config::default(),
        })
    }

    /// Writes the config byte (RDY = 0), which restarts the conversion. The configuration is
    /// remembered only if the write succeeded; a failed write leaves the old one, and a later
    /// read reports [`Error::UnexpectedConfig`] if the chip did take it after all.
    pub fn configure(&mut self, config: Config) -> Result<(), Error<I2C::Error>> {
        self.write_config(config.to_byte(false))?;
        self.config = config;
        Ok(())
    }

    /// Starts one conversion: writes the current config in one-shot mode with RDY = 1. This
    /// switches the chip to one-shot mode if it was continuous.
    pub fn start_one_shot(&mut self) -> Result<(), Error<I2C::Error>> {
        let config = Config {
            mode: Mode::OneShot,
            ..self.config
        };
        self.write_config(config.to_byte(true))?;
        self.config = config;
        Ok(())
    }

    /// Reads data plus config byte (3 bytes, or 4 at 18 bit) in one I2C read, whether or not
    /// the result is new (see [`Reading::ready`]).
    pub fn read(&mut self) -> Result<Reading, Error<I2C::Error>> {
        let rate = self.config.rate;
        let reading = if rate.read_len() == 4 {
            let mut b = [0u8; 4];
            self.i2c.read(self.address, &mut b).map_err(Error::Bus)?;
            Reading::from_raw(rate, u32::from_be_bytes([0, b[0], b[1], b[2]]), b[3])
        } else {
            let mut b = [0u8; 3];
            self.i2c.read(self.address, &mut b).map_err(Error::Bus)?;
            Reading::from_raw(rate, u32::from(u16::from_be_bytes([b[0], b[1]])), b[2])
        };
        let expected = self.expected_config();
        if reading.config & SETTINGS_MASK != expected {
            return Err(Error::UnexpectedConfig {
                expected,
                got: reading.config,
            });
        }
        Ok(reading)
    }

    /// Like [`read`](Self::read) but returns `None` when RDY = 1, i.e. the conversion has not
    /// finished since the last read. Poll this rather than trusting the chip's clock.
    pub fn read_ready(&mut self) -> Result<Option<Reading>, Error<I2C::Error>> {
        let reading = self.read()?;
        Ok(reading.ready.then_some(reading))
    }

    /// Tells the driver that the chip went back to its power-on config, e.g. after
    /// [`general_call_reset`], so reads expect 0x90 again.
    pub fn assume_power_on(&mut self) {
        self.config = Config::default();
    }

    /// The configuration the driver believes the chip has.
    pub fn config(&self) -> Config {
        self.config
    }

    /// The chip's 7-bit address.
    pub fn address(&self) -> u8 {
        self.address
    }

    /// Gives the bus back.
    pub fn release(self) -> I2C {
        self.i2c
    }

    /// The bus, e.g. to send a general call through it.
    pub fn bus_mut(&mut self) -> &mut I2C {
        &mut self.i2c
    }

    fn expected_config(&self) -> u8 {
        self.config.to_byte(false) & SETTINGS_MASK
    }

    fn write_config(&mut self, byte: u8) -> Result<(), Error<I2C::Error>> {
        self.i2c.write(self.address, &[byte]).map_err(Error::Bus)
    }
}

fn general_call<I2C: I2c>(i2c: &mut I2C, command: u8) -> Result<(), Error<I2C::Error>> {
    i2c.write(GENERAL_CALL_ADDRESS, &[command])
        .map_err(Error::Bus)
}

/// General-call reset: every MCP342x on the bus returns to power-on config 0x90, latches its
/// address pins and restarts converting. Call [`Mcp3423::assume_power_on`] on each driver after.
pub fn general_call_reset<I2C: I2c>(i2c: &mut I2C) -> Result<(), Error<I2C::Error>> {
    general_call(i2c, GC_RESET)
}

/// General-call latch: every MCP342x latches its address pins again, without a reset.
pub fn general_call_latch<I2C: I2c>(i2c: &mut I2C) -> Result<(), Error<I2C::Error>> {
    general_call(i2c, GC_LATCH)
}

/// General-call conversion: every MCP342x on the bus starts a conversion at the same instant,
/// the only way to sample several chips together (in continuous mode they free-run and can be
/// up to one period apart). Use it with the chips in one-shot mode, then poll each for RDY.
pub fn general_call_conversion<I2C: I2c>(i2c: &mut I2C) -> Result<(), Error<I2C::Error>> {
    general_call(i2c, GC_CONVERSION)
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::i2c::{ErrorKind, NoAcknowledgeSource};
    use embedded_hal_mock::eh1::i2c::{Mock, Transaction};

    const ADDR: u8 = 0x68;

    fn driver(expectations: &[Transaction]) -> Mcp3423<Mock> {
        Mcp3423::new(Mock::new(expectations), ADDR).unwrap()
    }

    fn finish(dev: Mcp3423<Mock>) {
        dev.release().done();
    }

    fn one_shot_18() -> Config {
        Config {
            mode: Mode::OneShot,
            rate: SampleRate::Sps3_75Bits18,
            gain: Gain::X8,
            channel: Channel::Ch2,
        }
    }

    #[test]
    fn config_bytes() {
        assert_eq!(Config::default().to_byte(true), POWER_ON_CONFIG);
        assert_eq!(Config::default().to_byte(false), 0x10);
        let one_shot = Config {
            mode: Mode::OneShot,
            ..Config::default()
        };
        assert_eq!(one_shot.to_byte(true), 0x80);
        assert_eq!(one_shot.to_byte(false), 0x00);
        // RDY=0, C1C0=01, O/C=0, S1S0=11, G1G0=11.
        assert_eq!(one_shot_18().to_byte(false), 0b0010_1111);
        let c = Config {
            mode: Mode::Continuous,
            rate: SampleRate::Sps60Bits14,
            gain: Gain::X2,
            channel: Channel::Ch1,
        };
        assert_eq!(c.to_byte(false), 0x15);
        let c = Config {
            rate: SampleRate::Sps15Bits16,
            gain: Gain::X4,
            ..Config::default()
        };
        assert_eq!(c.to_byte(false), 0x1A);
    }

    #[test]
    fn config_round_trip_all_bytes() {
        for byte in 0..=u8::MAX {
            let cfg = Config::from_byte(byte);
            // C1 (bit 6) is not representable on the MCP3423; everything else survives.
            assert_eq!(
                cfg.to_byte(byte & RDY_BIT != 0),
                byte & !0x40,
                "byte {byte:#04X}"
            );
        }
        assert_eq!(Config::from_byte(0x90), Config::default());
    }

    #[test]
    fn configure_writes_one_byte() {
        let mut dev = driver(&[Transaction::write(ADDR, vec![0x15])]);
        let cfg = Config {
            rate: SampleRate::Sps60Bits14,
            gain: Gain::X2,
            ..Config::default()
        };
        dev.configure(cfg).unwrap();
        assert_eq!(dev.config(), cfg);
        finish(dev);
    }

    #[test]
    fn read_positive_code() {
        let mut dev = driver(&[Transaction::read(ADDR, vec![0x01, 0xF4, 0x10])]);
        let r = dev.read().unwrap();
        assert_eq!(r.code, 500);
        assert!(r.ready);
        assert!(!r.saturated);
        assert_eq!(r.config, 0x10);
        assert!((r.volts(SampleRate::Sps240Bits12, Gain::X1) - 0.500).abs() < 1e-12);
        finish(dev);
    }

    #[test]
    fn read_negative_code() {
        let mut dev = driver(&[Transaction::read(ADDR, vec![0xFE, 0x0C, 0x10])]);
        let r = dev.read().unwrap();
        assert_eq!(r.code, -500);
        assert!(!r.saturated);
        assert!((r.volts(SampleRate::Sps240Bits12, Gain::X2) + 0.250).abs() < 1e-12);
        finish(dev);
    }

    #[test]
    fn read_ready_none_when_rdy_set() {
        let mut dev = driver(&[
            Transaction::read(ADDR, vec![0x01, 0xF4, 0x90]),
            Transaction::read(ADDR, vec![0x01, 0xF5, 0x10]),
        ]);
        assert_eq!(dev.read_ready().unwrap(), None);
        let r = dev.read_ready().unwrap().unwrap();
        assert_eq!(r.code, 501);
        assert!(r.ready);
        finish(dev);
    }

    #[test]
    fn saturation_at_both_ends() {
        let mut dev = driver(&[
            Transaction::read(ADDR, vec![0x07, 0xFF, 0x10]),
            Transaction::read(ADDR, vec![0xF8, 0x00, 0x10]),
            Transaction::read(ADDR, vec![0x07, 0xFE, 0x10]),
        ]);
        let hi = dev.read().unwrap();
        assert_eq!((hi.code, hi.saturated), (2047, true));
        let lo = dev.read().unwrap();
        assert_eq!((lo.code, lo.saturated), (-2048, true));
        let near = dev.read().unwrap();
        assert_eq!((near.code, near.saturated), (2046, false));
        finish(dev);
    }

    #[test]
    fn nack_is_bus_error_and_driver_recovers() {
        let nack = ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address);
        let mut dev = driver(&[
            Transaction::read(ADDR, vec![0, 0, 0]).with_error(nack),
            Transaction::write(ADDR, vec![0x00]).with_error(nack),
            Transaction::read(ADDR, vec![0x00, 0x2A, 0x10]),
        ]);
        assert_eq!(dev.read(), Err(Error::Bus(nack)));
        let one_shot = Config {
            mode: Mode::OneShot,
            ..Config::default()
        };
        assert_eq!(dev.configure(one_shot), Err(Error::Bus(nack)));
        // The failed configure is not remembered: the read still expects continuous mode.
        assert_eq!(dev.config(), Config::default());
        assert_eq!(dev.read().unwrap().code, 42);
        finish(dev);
    }

    #[test]
    fn general_call_bytes() {
        let mut bus = Mock::new(&[
            Transaction::write(0x00, vec![0x06]),
            Transaction::write(0x00, vec![0x04]),
            Transaction::write(0x00, vec![0x08]),
        ]);
        general_call_reset(&mut bus).unwrap();
        general_call_latch(&mut bus).unwrap();
        general_call_conversion(&mut bus).unwrap();
        bus.done();
    }

    #[test]
    fn general_call_through_driver_then_reset_config() {
        let mut dev = driver(&[
            Transaction::write(ADDR, vec![0x00]),
            Transaction::write(0x00, vec![0x06]),
            Transaction::read(ADDR, vec![0x00, 0x01, 0x90]),
        ]);
        dev.configure(Config {
            mode: Mode::OneShot,
            ..Config::default()
        })
        .unwrap();
        general_call_reset(dev.bus_mut()).unwrap();
        dev.assume_power_on();
        assert_eq!(dev.read_ready().unwrap(), None);
        finish(dev);
    }

    #[test]
    fn one_shot_start_byte() {
        let mut dev = driver(&[
            Transaction::write(ADDR, vec![0x80]),
            Transaction::read(ADDR, vec![0x00, 0x00, 0x80]),
            Transaction::read(ADDR, vec![0x00, 0x07, 0x00]),
        ]);
        dev.start_one_shot().unwrap();
        assert_eq!(dev.config().mode, Mode::OneShot);
        assert_eq!(dev.read_ready().unwrap(), None);
        assert_eq!(dev.read_ready().unwrap().map(|r| r.code), Some(7));
        finish(dev);
    }

    #[test]
    fn read_18_bit_uses_four_bytes() {
        let mut dev = driver(&[
            Transaction::write(ADDR, vec![0x2F]),
            Transaction::read(ADDR, vec![0x01, 0xFF, 0xFF, 0x2F]),
            Transaction::read(ADDR, vec![0xFE, 0x00, 0x00, 0x2F]),
            Transaction::read(ADDR, vec![0x00, 0x30, 0x39, 0x2F]),
        ]);
        dev.configure(one_shot_18()).unwrap();
        let hi = dev.read().unwrap();
        assert_eq!((hi.code, hi.saturated), (131_071, true));
        let lo = dev.read().unwrap();
        assert_eq!((lo.code, lo.saturated), (-131_072, true));
        let mid = dev.read().unwrap();
        assert_eq!((mid.code, mid.saturated), (12_345, false));
        // 12345 * 15.625 uV / 8.
        let v = mid.volts(SampleRate::Sps3_75Bits18, Gain::X8);
        assert!((v - 12_345.0 * 15.625e-6 / 8.0).abs() < 1e-12);
        finish(dev);
    }

    #[test]
    fn unexpected_config_is_reported() {
        let mut dev = driver(&[
            Transaction::write(ADDR, vec![0x15]),
            // Chip was reset behind our back: it reports power-on 0x90.
            Transaction::read(ADDR, vec![0x00, 0x10, 0x90]),
        ]);
        dev.configure(Config {
            rate: SampleRate::Sps60Bits14,
            gain: Gain::X2,
            ..Config::default()
        })
        .unwrap();
        let err = dev.read().unwrap_err();
        assert_eq!(
            err,
            Error::UnexpectedConfig {
                expected: 0x15,
                got: 0x90
            }
        );
        let msg = err.to_string();
        assert!(msg.contains("0x90") && msg.contains("0x15"), "{msg}");
        finish(dev);
    }

    #[test]
    fn bad_address_rejected() {
        for addr in [0x00, 0x20, 0x67, 0x70, 0xFF] {
            // The mock is shared (Arc): a clone goes into `new`, which drops it on error.
            let mut bus = Mock::new(&[]);
            let err = Mcp3423::new(bus.clone(), addr).unwrap_err();
            assert_eq!(err, AddressError(addr));
            bus.done();
        }
        assert_eq!(
            AddressError(0x20).to_string(),
            "MCP3423 address 0x20 is outside 0x68..=0x6F"
        );
        for addr in ADDRESS_MIN..=ADDRESS_MAX {
            let dev = Mcp3423::new(Mock::new(&[]), addr).unwrap();
            assert_eq!(dev.address(), addr);
            finish(dev);
        }
    }

    #[test]
    fn garbage_upper_bits_sign_extend_from_bit_11() {
        let mut dev = driver(&[
            Transaction::read(ADDR, vec![0x57, 0xD0, 0x10]),
            Transaction::read(ADDR, vec![0xA8, 0x30, 0x10]),
            Transaction::read(ADDR, vec![0x27, 0xFF, 0x10]),
        ]);
        assert_eq!(dev.read().unwrap().code, 2000);
        assert_eq!(dev.read().unwrap().code, -2000);
        let r = dev.read().unwrap();
        assert_eq!((r.code, r.saturated), (2047, true));
        finish(dev);
    }

    #[test]
    fn decode_is_total() {
        for rate in [
            SampleRate::Sps240Bits12,
            SampleRate::Sps60Bits14,
            SampleRate::Sps15Bits16,
            SampleRate::Sps3_75Bits18,
        ] {
            assert_eq!(Reading::decode(rate, &[0; 2]), None);
            for b in 0..=u8::MAX {
                let r = Reading::decode(rate, &[b, b ^ 0x5A, b, b]).unwrap();
                assert!((rate.min_code()..=rate.max_code()).contains(&r.code));
            }
        }
    }
}
