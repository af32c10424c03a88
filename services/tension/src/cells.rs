//! ADC code to cell force, with the nominal constants of the cell and its amplifier.

use rt_config::CellConfig;

/// Volts per LSB of an MCP3423 at 12 bits, PGA x1 (2 * 2.048 V / 4096).
pub const VOLTS_PER_LSB: f64 = 0.001;
/// The rails of a 12-bit code: a code here is saturated.
pub const CODE_MIN: i16 = -2048;
pub const CODE_MAX: i16 = 2047;

/// Nominal code -> volts -> cell force conversion of one cell and its AD8293.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellConversion {
    /// Amplifier output volts per newton of tension on the cell.
    volts_per_newton: f64,
    reference_v: f64,
}

impl CellConversion {
    pub fn new(cell: &CellConfig) -> Self {
        let bridge_v_per_n = cell.sensitivity_mv_per_v * 1e-3 * cell.excitation_v / cell.capacity_n;
        Self {
            volts_per_newton: cell.amplifier_gain * bridge_v_per_n,
            reference_v: cell.reference_v,
        }
    }

    pub fn volts_per_newton(&self) -> f64 {
        self.volts_per_newton
    }

    /// Cell force, N: negative in tension (the amplifier output rises above the reference
    /// when the cell is pulled).
    pub fn force_from_volts(&self, volts: f64) -> f64 {
        -(volts - self.reference_v) / self.volts_per_newton
    }

    pub fn force_from_code(&self, code: i16) -> f64 {
        self.force_from_volts(code as f64 * VOLTS_PER_LSB)
    }

    pub fn forces_from_codes(&self, codes: &[i16; 4]) -> [f64; 4] {
        codes.map(|c| self.force_from_code(c))
    }
}

/// True if a code sits at a rail.
pub fn is_saturated(code: i16) -> bool {
    code <= CODE_MIN || code >= CODE_MAX
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nominal_chain_by_hand() {
        // 1 mV/V * 5 V = 5 mV at 49.03325 N; x160 = 0.8 V at capacity: 16.3155 mV/N.
        let c = CellConversion::new(&CellConfig::default());
        assert!((c.volts_per_newton() - 0.8 / 49.03325).abs() < 1e-12);
        // At rest the amplifier sits on its 0.5 V reference: code 500 is zero force.
        assert_eq!(c.force_from_code(500), 0.0);
        // 1300 mV = reference + 0.8 V: a full 5 kg of tension on the cell.
        assert!((c.force_from_code(1300) + 49.03325).abs() < 1e-9);
        assert!(is_saturated(2047) && is_saturated(-2048) && !is_saturated(2046));
    }
}
