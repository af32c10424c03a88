//! The three small filters PX4's inner loops use.
//!
//! - [`LowPassFilter2p`]: PX4's `math::LowPassFilter2p` (src/lib/mathlib/math/filter/
//!   LowPassFilter2p.hpp): a 2nd-order Butterworth low-pass from the bilinear transform with
//!   pre-warping (`ohm = tan(pi fc / fs)`), Direct Form II. Used on the gyro
//!   (IMU_GYRO_CUTOFF) and on the angular acceleration (IMU_DGYRO_CUTOFF).
//! - [`AlphaFilter`]: PX4's `AlphaFilter` set by cutoff frequency (time constant
//!   1/(2 pi fc), alpha = dt / (dt + tau)). Used on the yaw torque (MC_YAW_TQ_CUTOFF).
//! - [`BlockDerivative`]: PX4's `control::BlockDerivative` (difference quotient through a
//!   `BlockLowPass`, b = 2 pi fc dt, a = b / (1 + b)). Used for the velocity derivative that
//!   feeds the velocity D term (MPC_VELD_LP).

use std::f64::consts::PI;

/// 2nd-order Butterworth low-pass, PX4's `LowPassFilter2p`.
#[derive(Debug, Clone, PartialEq)]
pub struct LowPassFilter2p {
    sample_hz: f64,
    cutoff_hz: f64,
    b0: f64,
    b1: f64,
    b2: f64,
    a1: f64,
    a2: f64,
    delay_1: f64,
    delay_2: f64,
}

impl LowPassFilter2p {
    /// A filter for samples at `sample_hz` with -3 dB at `cutoff_hz`. A cutoff <= 0, at or
    /// above Nyquist, or non-finite rates make it a pass-through, as PX4 does.
    pub fn new(sample_hz: f64, cutoff_hz: f64) -> Self {
        let mut f = LowPassFilter2p {
            sample_hz,
            cutoff_hz,
            b0: 1.0,
            b1: 0.0,
            b2: 0.0,
            a1: 0.0,
            a2: 0.0,
            delay_1: 0.0,
            delay_2: 0.0,
        };
        f.set_cutoff_frequency(sample_hz, cutoff_hz);
        f
    }

    /// Recomputes the coefficients and clears the delay elements (PX4 does both).
    pub fn set_cutoff_frequency(&mut self, sample_hz: f64, cutoff_hz: f64) {
        self.sample_hz = sample_hz;
        self.cutoff_hz = cutoff_hz;
        self.delay_1 = 0.0;
        self.delay_2 = 0.0;
        let valid = sample_hz.is_finite()
            && cutoff_hz.is_finite()
            && sample_hz > 0.0
            && cutoff_hz > 0.0
            && cutoff_hz < 0.5 * sample_hz;
        if !valid {
            (self.b0, self.b1, self.b2, self.a1, self.a2) = (1.0, 0.0, 0.0, 0.0, 0.0);
            return;
        }
        let ohm = (PI * cutoff_hz / sample_hz).tan();
        let cos45 = (PI / 4.0).cos();
        let c = 1.0 + 2.0 * cos45 * ohm + ohm * ohm;
        self.b0 = ohm * ohm / c;
        self.b1 = 2.0 * self.b0;
        self.b2 = self.b0;
        self.a1 = 2.0 * (ohm * ohm - 1.0) / c;
        self.a2 = (1.0 - 2.0 * cos45 * ohm + ohm * ohm) / c;
    }

    /// Filters one sample. A non-finite intermediate is replaced by the sample, as PX4 does.
    pub fn apply(&mut self, sample: f64) -> f64 {
        let mut d0 = sample - self.delay_1 * self.a1 - self.delay_2 * self.a2;
        if !d0.is_finite() {
            d0 = sample;
        }
        let out = d0 * self.b0 + self.delay_1 * self.b1 + self.delay_2 * self.b2;
        self.delay_2 = self.delay_1;
        self.delay_1 = d0;
        out
    }

    /// Sets the state to the steady state of a constant input `sample` and returns the output.
    pub fn reset(&mut self, sample: f64) -> f64 {
        let dval = sample / (self.b0 + self.b1 + self.b2);
        let d = if dval.is_finite() { dval } else { sample };
        self.delay_1 = d;
        self.delay_2 = d;
        self.apply(sample)
    }

    /// Sample rate the coefficients were computed for, Hz.
    pub fn sample_hz(&self) -> f64 {
        self.sample_hz
    }

    /// Cutoff frequency, Hz.
    pub fn cutoff_hz(&self) -> f64 {
        self.cutoff_hz
    }
}

/// First-order low-pass by cutoff frequency, PX4's `AlphaFilter` (state starts at 0).
#[derive(Debug, Clone, PartialEq)]
pub struct AlphaFilter {
    time_constant_s: f64,
    state: f64,
}

impl AlphaFilter {
    /// A cutoff <= 0 gives a pass-through (time constant 0).
    pub fn new(cutoff_hz: f64) -> Self {
        let time_constant_s = if cutoff_hz > 0.0 && cutoff_hz.is_finite() {
            1.0 / (2.0 * PI * cutoff_hz)
        } else {
            0.0
        };
        AlphaFilter {
            time_constant_s,
            state: 0.0,
        }
    }

    /// One step with alpha = dt / (tau + dt).
    pub fn update(&mut self, sample: f64, dt: f64) -> f64 {
        let denominator = self.time_constant_s + dt;
        let alpha = if denominator > f64::EPSILON {
            dt / denominator
        } else {
            1.0
        };
        self.state += alpha * (sample - self.state);
        self.state
    }

    /// Sets the state.
    pub fn reset(&mut self, value: f64) {
        self.state = value;
    }
}

/// Derivative of a signal through a first-order low-pass, PX4's `control::BlockDerivative`.
/// The first call after construction or [`BlockDerivative::reset`] returns 0.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockDerivative {
    cutoff_hz: f64,
    previous_input: f64,
    low_pass_state: f64,
    initialized: bool,
}

impl BlockDerivative {
    pub fn new(cutoff_hz: f64) -> Self {
        BlockDerivative {
            cutoff_hz,
            previous_input: 0.0,
            low_pass_state: f64::NAN,
            initialized: false,
        }
    }

    /// Filtered derivative of `input` over `dt`.
    pub fn update(&mut self, input: f64, dt: f64) -> f64 {
        let out = if self.initialized {
            self.low_pass((input - self.previous_input) / dt, dt)
        } else {
            self.low_pass(0.0, dt);
            self.initialized = true;
            0.0
        };
        self.previous_input = input;
        out
    }

    /// Forgets the history: the next update returns 0.
    pub fn reset(&mut self) {
        self.initialized = false;
        self.low_pass_state = f64::NAN;
    }

    fn low_pass(&mut self, input: f64, dt: f64) -> f64 {
        if !self.low_pass_state.is_finite() {
            self.low_pass_state = input;
        }
        let b = 2.0 * PI * self.cutoff_hz * dt;
        let a = b / (1.0 + b);
        self.low_pass_state = a * input + (1.0 - a) * self.low_pass_state;
        self.low_pass_state
    }
}

#[cfg(test)]
#[path = "filters_tests.rs"]
mod tests;
