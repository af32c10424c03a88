//! One drone's emulated sensor I2C bus: four MCP3423s (chip i reads cell i+1), the sensor model
//! feeding their inputs from a load profile, fault injection, counters and ground truth.
//!
//! The API is at transaction level (one address phase and its bytes), with the time of the
//! transaction in CLOCK_MONOTONIC ns. Time never runs backwards for the bus: a timestamp older
//! than the newest seen is treated as the newest (requests served from several threads can
//! reach the lock slightly out of order). Noise comes from one RNG seeded at construction and
//! fault rolls from a second one, so for a given seed and sequence of calls everything is
//! deterministic, and turning NACK faults on does not change the noise.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::Deserialize;

use super::mcp3423::{GeneralCall, Mcp3423};
use super::model::SensorModel;
use super::profile::LoadProfile;

/// Default chip addresses (Adr pins tied, MODEL.md): cells 1..4.
pub const DEFAULT_ADDRESSES: [u8; 4] = [0x68, 0x6A, 0x6C, 0x6E];
/// The I2C general-call address.
pub const GENERAL_CALL_ADDRESS: u8 = 0x00;

/// Bus layout and per-chip oscillator errors.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BusConfig {
    /// 7-bit address of the chip reading cell 1..4. Default 0x68, 0x6A, 0x6C, 0x6E.
    pub addresses: [u8; 4],
    /// Relative oscillator error per chip (period = 1/240 s * (1 + e)). Default
    /// [+0.12, -0.08, +0.19, -0.15] %: enough for the free-running chips to drift apart
    /// visibly. (The datasheet's data-rate limits are far wider; configs may go further.)
    pub osc_error: [f64; 4],
}

impl Default for BusConfig {
    fn default() -> Self {
        BusConfig {
            addresses: DEFAULT_ADDRESSES,
            osc_error: [0.0012, -0.0008, 0.0019, -0.0015],
        }
    }
}

impl BusConfig {
    /// Default addresses, exact oscillators.
    pub fn ideal() -> Self {
        BusConfig {
            osc_error: [0.0; 4],
            ..BusConfig::default()
        }
    }
}

/// A bus configuration that cannot work.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BusConfigError {
    #[error("chip address {0:#04x} is not a usable 7-bit address (0x01..=0x7F)")]
    BadAddress(u8),
    #[error("chip address {0:#04x} is used twice")]
    DuplicateAddress(u8),
    #[error("oscillator error {0} is not finite or not within +-50 %")]
    BadOscError(f64),
}

/// An input forced regardless of the load (fault injection).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ForcedInput {
    /// The amplifier's high rail.
    RailHigh,
    /// The amplifier's low rail.
    RailLow,
    /// Any voltage at the ADC input.
    Volts(f64),
}

/// Faults to inject; all off by default. Settable at start and at run time
/// ([`SensorBus::set_faults`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Faults {
    /// Probability that a transaction to chip i is not acknowledged (address NACK).
    pub nack_probability: [f64; 4],
    /// Chip i answers but never finishes a conversion (RDY stays 1, data frozen).
    pub stuck: [bool; 4],
    /// Chip i NACKs everything and ignores general calls (dead or unpowered).
    pub silent: [bool; 4],
    /// Chip i's input forced to a rail or a voltage.
    pub forced_input: [Option<ForcedInput>; 4],
    /// Extra force (body FRD, N) the sensor sees on top of the profile, e.g. a snag; it is not
    /// part of the ground truth.
    pub extra_force_body: [f64; 3],
}

/// Why a transaction was not acknowledged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Nack {
    #[error("address not acknowledged")]
    Address,
    #[error("data not acknowledged")]
    Data,
}

/// Per-chip counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ChipCounters {
    /// Transactions addressed to the chip (acknowledged or not).
    pub transactions: u64,
    /// Of those, not acknowledged.
    pub nacks: u64,
    /// Conversions the chip completed.
    pub conversions: u64,
}

/// One emulated sensor bus.
#[derive(Debug)]
pub struct SensorBus {
    addresses: [u8; 4],
    chips: [Mcp3423; 4],
    model: SensorModel,
    profile: LoadProfile,
    t0_ns: u64,
    rng: StdRng,
    fault_rng: StdRng,
    faults: Faults,
    counters: [ChipCounters; 4],
    general_calls: u64,
    unknown_address_nacks: u64,
    last_t_ns: u64,
}

fn seconds_since(t_ns: u64, t0_ns: u64) -> f64 {
    (i128::from(t_ns) - i128::from(t0_ns)) as f64 * 1e-9
}

/// The analog input of chip `i` at `t_ns`.
fn analog_input(
    model: &mut SensorModel,
    profile: &LoadProfile,
    t0_ns: u64,
    rng: &mut StdRng,
    faults: &Faults,
    i: usize,
    t_ns: u64,
) -> f64 {
    let rails = model.params().rails_v;
    match faults.forced_input.get(i).copied().flatten() {
        Some(ForcedInput::RailHigh) => rails[1],
        Some(ForcedInput::RailLow) => rails[0],
        Some(ForcedInput::Volts(v)) => v,
        None => {
            let f = profile.force_at(seconds_since(t_ns, t0_ns));
            let e = faults.extra_force_body;
            model.cell_volts(i, [f[0] + e[0], f[1] + e[1], f[2] + e[2]], rng)
        }
    }
}

impl SensorBus {
    /// A bus whose chips power on at `t0_ns`, the profile's start. `seed` fixes the noise and
    /// the fault rolls.
    pub fn new(
        config: BusConfig,
        model: SensorModel,
        profile: LoadProfile,
        t0_ns: u64,
        seed: u64,
    ) -> Result<Self, BusConfigError> {
        for (i, &a) in config.addresses.iter().enumerate() {
            if a == GENERAL_CALL_ADDRESS || a > 0x7F {
                return Err(BusConfigError::BadAddress(a));
            }
            if config.addresses[..i].contains(&a) {
                return Err(BusConfigError::DuplicateAddress(a));
            }
        }
        if let Some(&e) = config
            .osc_error
            .iter()
            .find(|e| !(e.is_finite() && e.abs() < 0.5))
        {
            return Err(BusConfigError::BadOscError(e));
        }
        Ok(SensorBus {
            addresses: config.addresses,
            chips: std::array::from_fn(|i| Mcp3423::new(i, config.osc_error[i], t0_ns)),
            model,
            profile,
            t0_ns,
            rng: StdRng::seed_from_u64(seed),
            fault_rng: StdRng::seed_from_u64(seed ^ 0x9E37_79B9_7F4A_7C15),
            faults: Faults::default(),
            counters: [ChipCounters::default(); 4],
            general_calls: 0,
            unknown_address_nacks: 0,
            last_t_ns: t0_ns,
        })
    }

    fn clamp_time(&mut self, t_ns: u64) -> u64 {
        self.last_t_ns = self.last_t_ns.max(t_ns);
        self.last_t_ns
    }

    fn chip_index(&self, addr: u8) -> Option<usize> {
        self.addresses.iter().position(|&a| a == addr)
    }

    /// Runs `op` on chip `i` (all chips if None) with the analog input wired up.
    fn with_chips(
        &mut self,
        only: Option<usize>,
        mut op: impl FnMut(&mut Mcp3423, &mut dyn FnMut(usize, u64) -> f64),
    ) {
        let SensorBus {
            chips,
            model,
            profile,
            t0_ns,
            rng,
            faults,
            ..
        } = self;
        let mut input = |i: usize, t: u64| analog_input(model, profile, *t0_ns, rng, faults, i, t);
        for (i, chip) in chips.iter_mut().enumerate() {
            if only.is_none_or(|o| o == i) {
                op(chip, &mut input);
            }
        }
    }

    /// Address phase for chip `i`: counts it and applies silent / NACK-probability faults.
    fn address_chip(&mut self, i: usize) -> Result<(), Nack> {
        self.counters[i].transactions += 1;
        let p = self.faults.nack_probability[i];
        let nack = self.faults.silent[i] || (p > 0.0 && self.fault_rng.random::<f64>() < p);
        if nack {
            self.counters[i].nacks += 1;
            return Err(Nack::Address);
        }
        Ok(())
    }

    /// An I2C write transaction. To a chip: each byte is a config byte. To the general-call
    /// address: each byte is a command (0x06 reset, 0x04 latch, 0x08 conversion); an unknown
    /// command is not acknowledged ([`Nack::Data`]), and the call is NACKed if every chip is
    /// silent. Unknown address: [`Nack::Address`].
    pub fn write(&mut self, addr: u8, bytes: &[u8], t_ns: u64) -> Result<(), Nack> {
        let t = self.clamp_time(t_ns);
        if addr == GENERAL_CALL_ADDRESS {
            return self.general_call(bytes, t);
        }
        let Some(i) = self.chip_index(addr) else {
            self.unknown_address_nacks += 1;
            return Err(Nack::Address);
        };
        self.address_chip(i)?;
        self.with_chips(Some(i), |chip, input| chip.write(bytes, t, input));
        Ok(())
    }

    /// An I2C read transaction filling `buf`. The general-call address cannot be read.
    pub fn read(&mut self, addr: u8, buf: &mut [u8], t_ns: u64) -> Result<(), Nack> {
        let t = self.clamp_time(t_ns);
        let Some(i) = self.chip_index(addr) else {
            self.unknown_address_nacks += 1;
            return Err(Nack::Address);
        };
        self.address_chip(i)?;
        self.with_chips(Some(i), |chip, input| chip.read(buf, t, input));
        Ok(())
    }

    fn general_call(&mut self, bytes: &[u8], t: u64) -> Result<(), Nack> {
        self.general_calls += 1;
        if self.faults.silent.iter().all(|&s| s) {
            return Err(Nack::Address);
        }
        for &b in bytes {
            let cmd = GeneralCall::from_byte(b).ok_or(Nack::Data)?;
            let silent = self.faults.silent;
            self.with_chips(None, |chip, input| {
                if !silent[chip.index()] {
                    chip.general_call(cmd, t, input);
                }
            });
        }
        Ok(())
    }

    /// Lets every chip finish the conversions due by `t_ns` (no bus traffic).
    pub fn advance_to(&mut self, t_ns: u64) {
        let t = self.clamp_time(t_ns);
        self.with_chips(None, |chip, input| chip.advance(t, input));
    }

    /// Replaces the faults from `t_ns` on. Conversions due before `t_ns` complete under the old
    /// faults first.
    pub fn set_faults(&mut self, faults: Faults, t_ns: u64) {
        self.advance_to(t_ns);
        let t = self.last_t_ns;
        let stuck = faults.stuck;
        self.with_chips(None, |chip, input| {
            chip.set_stuck(stuck[chip.index()], t, input);
        });
        self.faults = faults;
    }

    pub fn faults(&self) -> &Faults {
        &self.faults
    }

    /// Replaces the load profile; `t0_ns` is its new start. Conversions are evaluated lazily
    /// (at the next transaction), so call [`SensorBus::advance_to`] first if the ones already
    /// due must see the old profile.
    pub fn set_profile(&mut self, profile: LoadProfile, t0_ns: u64) {
        self.profile = profile;
        self.t0_ns = t0_ns;
    }

    pub fn profile(&self) -> &LoadProfile {
        &self.profile
    }

    pub fn t0_ns(&self) -> u64 {
        self.t0_ns
    }

    /// Ground truth: the profile's force at `t_ns`, body FRD, N (without fault offsets).
    pub fn true_force_at(&self, t_ns: u64) -> [f64; 3] {
        self.profile.force_at(seconds_since(t_ns, self.t0_ns))
    }

    pub fn model(&self) -> &SensorModel {
        &self.model
    }

    pub fn addresses(&self) -> [u8; 4] {
        self.addresses
    }

    /// Chip `i` (0..4, cell i+1), to inspect its state and last conversion window.
    pub fn chip(&self, i: usize) -> Option<&Mcp3423> {
        self.chips.get(i)
    }

    /// Counters per chip, cell order.
    pub fn counters(&self) -> [ChipCounters; 4] {
        let mut c = self.counters;
        for (c, chip) in c.iter_mut().zip(&self.chips) {
            c.conversions = chip.conversions();
        }
        c
    }

    /// General-call transactions seen.
    pub fn general_calls(&self) -> u64 {
        self.general_calls
    }

    /// Transactions to addresses no chip has.
    pub fn unknown_address_nacks(&self) -> u64 {
        self.unknown_address_nacks
    }
}

#[cfg(test)]
#[path = "bus_tests.rs"]
mod tests;
