//! Parameters of the emulated force sensor: geometry, electronics and imperfections.
//!
//! Every field has a default (see [`SensorParams::default`]), so a config file only names what
//! it changes. Units are in the field names. Geometry and electronics follow MODEL.md; the
//! imperfection defaults are our own picks for "a realistic sensor", sized so that the z-axis
//! metrics land near the paper's uncalibrated numbers (crossload a few %FS, non-linearity and
//! hysteresis around 0.5 %FS of the 5.5 kg test range). They are assumptions, not measurements.

use serde::Deserialize;

/// Standard gravity, to express the cell capacity in kg.
pub const G0: f64 = 9.80665;

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Parameters of one force sensor (four cells, four amplifiers).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SensorParams {
    /// Distance from the board centre to each cell, m. Default 0.03 (MODEL.md assumption).
    pub d0_m: f64,
    /// Height of the anchor point above the board centre, m. Default 0.03.
    pub h_m: f64,
    /// Rotation body FRD -> sensor frame S, row-major (`f_s = R f_body`). Default identity
    /// (sensor z along body z, i.e. down, towards the anchor).
    pub mounting: [[f64; 3]; 3],
    /// Capacity of each cell, N. Default 5 kg = 49.033 N.
    pub capacity_n: f64,
    /// Cell sensitivity at capacity, mV per V of excitation. Default 1.0.
    pub sensitivity_mv_per_v: f64,
    /// Bridge excitation, V. Default 5.0.
    pub excitation_v: f64,
    /// Instrumentation amplifier gain (AD8293G160). Default 160.
    pub amp_gain: f64,
    /// Amplifier reference, the at-rest output, V. Default 0.5.
    pub reference_v: f64,
    /// Amplifier output swing `[low, high]`, V; the output clamps there. Default [0.0, 4.9].
    pub rails_v: [f64; 2],
    /// Per-cell multiplicative gain error. Default [1.02, 0.985, 1.01, 0.99]: the spread the
    /// paper's per-cell gamma calibration removes.
    pub gain_error: [f64; 4],
    /// Crossload matrix M: the force that reaches the cells is `M * T` (sensor frame).
    /// Default: z leaks 2.5 % into x and -1.8 % into y, small x/y couplings
    /// (the paper measured 3.8 %FS crossload before compensation).
    pub crossload: [[f64; 3]; 3],
    /// Per-cell quadratic non-linearity, fraction of capacity at capacity:
    /// `f + k f |f| / capacity`. Default [0.015, 0.012, 0.018, 0.014].
    pub nonlinearity: [f64; 4],
    /// Per-cell hysteresis, fraction of capacity: width of a play (backlash) operator; the
    /// output lags the input by half of it after a change of direction.
    /// Default [0.0012, 0.0009, 0.0015, 0.0010] (~0.4 %FS summed over the 5.5 kg z test).
    pub hysteresis: [f64; 4],
    /// Per-cell white noise at the ADC input, V (1 mV = 1 LSB at 12 bit, x1).
    /// Default 0.6 mV each (about 37 mN per cell).
    pub noise_std_v: [f64; 4],
    /// Per-cell zero offset at the amplifier output (bridge imbalance, amplifier offset), V.
    /// Default [3.1, -2.2, 1.5, -4.0] mV: a few codes that a tare removes.
    pub zero_offset_v: [f64; 4],
}

impl Default for SensorParams {
    fn default() -> Self {
        SensorParams {
            d0_m: 0.03,
            h_m: 0.03,
            mounting: IDENTITY,
            capacity_n: 5.0 * G0,
            sensitivity_mv_per_v: 1.0,
            excitation_v: 5.0,
            amp_gain: 160.0,
            reference_v: 0.5,
            rails_v: [0.0, 4.9],
            gain_error: [1.02, 0.985, 1.01, 0.99],
            crossload: [
                [1.0, 0.008, 0.025],
                [-0.006, 1.0, -0.018],
                [0.004, -0.003, 1.0],
            ],
            nonlinearity: [0.015, 0.012, 0.018, 0.014],
            hysteresis: [0.0012, 0.0009, 0.0015, 0.0010],
            noise_std_v: [0.0006; 4],
            zero_offset_v: [0.0031, -0.0022, 0.0015, -0.0040],
        }
    }
}

/// A parameter value the model cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("sensor parameter `{key}`: {msg}")]
pub struct ParamsError {
    pub key: &'static str,
    pub msg: String,
}

impl SensorParams {
    /// Default geometry and electronics with no imperfections: unit gains, no crossload,
    /// linear, no hysteresis, no noise, no zero offset.
    pub fn ideal() -> Self {
        SensorParams {
            gain_error: [1.0; 4],
            crossload: IDENTITY,
            nonlinearity: [0.0; 4],
            hysteresis: [0.0; 4],
            noise_std_v: [0.0; 4],
            zero_offset_v: [0.0; 4],
            ..SensorParams::default()
        }
    }

    /// Bridge-to-ADC transfer: ADC volts per newton of cell tension (ideal cell).
    pub fn volts_per_newton(&self) -> f64 {
        self.amp_gain * self.sensitivity_mv_per_v * 1e-3 * self.excitation_v / self.capacity_n
    }

    /// Checks that every value is finite and in range.
    pub fn validate(&self) -> Result<(), ParamsError> {
        fn err(key: &'static str, msg: impl Into<String>) -> Result<(), ParamsError> {
            Err(ParamsError {
                key,
                msg: msg.into(),
            })
        }
        let positive = [
            ("d0_m", self.d0_m),
            ("h_m", self.h_m),
            ("capacity_n", self.capacity_n),
            ("sensitivity_mv_per_v", self.sensitivity_mv_per_v),
            ("excitation_v", self.excitation_v),
            ("amp_gain", self.amp_gain),
        ];
        for (key, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return err(key, format!("{v} must be finite and > 0"));
            }
        }
        let finite: [(&'static str, &[f64]); 7] = [
            ("reference_v", &[self.reference_v]),
            ("rails_v", &self.rails_v),
            ("gain_error", &self.gain_error),
            ("nonlinearity", &self.nonlinearity),
            ("mounting", self.mounting.as_flattened()),
            ("crossload", self.crossload.as_flattened()),
            ("zero_offset_v", &self.zero_offset_v),
        ];
        for (key, vs) in finite {
            if let Some(v) = vs.iter().find(|v| !v.is_finite()) {
                return err(key, format!("{v} is not finite"));
            }
        }
        let non_negative: [(&'static str, &[f64]); 2] = [
            ("hysteresis", &self.hysteresis),
            ("noise_std_v", &self.noise_std_v),
        ];
        for (key, vs) in non_negative {
            if let Some(v) = vs.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return err(key, format!("{v} must be finite and >= 0"));
            }
        }
        if self.rails_v[0] >= self.rails_v[1] {
            return err("rails_v", "low rail must be below the high rail");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_parse_partially() {
        SensorParams::default().validate().unwrap();
        SensorParams::ideal().validate().unwrap();
        let p: SensorParams = toml::from_str("d0_m = 0.04\nhysteresis = [0,0,0,0]\n").unwrap();
        assert_eq!(p.d0_m, 0.04);
        assert_eq!(p.h_m, 0.03);
        assert_eq!(p.hysteresis, [0.0; 4]);
        assert!(toml::from_str::<SensorParams>("d0 = 0.04\n").is_err());
    }

    #[test]
    fn validate_names_the_key() {
        let p = SensorParams {
            h_m: 0.0,
            ..SensorParams::default()
        };
        assert_eq!(p.validate().unwrap_err().key, "h_m");
        let p = SensorParams {
            rails_v: [1.0, 0.5],
            ..SensorParams::default()
        };
        assert_eq!(p.validate().unwrap_err().key, "rails_v");
        let p = SensorParams {
            noise_std_v: [0.0, -1.0, 0.0, 0.0],
            ..SensorParams::default()
        };
        assert_eq!(p.validate().unwrap_err().key, "noise_std_v");
    }
}
