//! First-order low-pass on a 3-vector, with the derivative of its output.

use nalgebra::Vector3;

/// y += α (x − y), α = 1 − exp(−2π f_c dt) (exact for a held input). The first sample after a
/// reset seeds the output, so there is no start-up transient and the derivative starts at 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowPass3 {
    cutoff_hz: f64,
    value: Vector3<f64>,
    previous: Vector3<f64>,
    primed: bool,
}

impl LowPass3 {
    pub fn new(cutoff_hz: f64) -> Self {
        Self {
            cutoff_hz,
            value: Vector3::zeros(),
            previous: Vector3::zeros(),
            primed: false,
        }
    }

    /// Feeds `x` after `dt_s`; returns the filtered value.
    pub fn update(&mut self, x: &Vector3<f64>, dt_s: f64) -> Vector3<f64> {
        if self.primed {
            let alpha = 1.0 - (-2.0 * std::f64::consts::PI * self.cutoff_hz * dt_s).exp();
            self.previous = self.value;
            self.value += (x - self.value) * alpha;
        } else {
            self.value = *x;
            self.previous = *x;
            self.primed = true;
        }
        self.value
    }

    /// d(output)/dt over the last update, 1/s times the unit of the input.
    pub fn derivative(&self, dt_s: f64) -> Vector3<f64> {
        (self.value - self.previous) / dt_s
    }

    pub fn value(&self) -> Vector3<f64> {
        self.value
    }

    /// The next sample seeds the output again (the last value stays readable).
    pub fn unprime(&mut self) {
        self.primed = false;
    }

    pub fn reset(&mut self) {
        *self = Self::new(self.cutoff_hz);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_response_reaches_63_percent_after_one_time_constant() {
        let mut f = LowPass3::new(10.0);
        f.update(&Vector3::zeros(), 0.01);
        let tau = 1.0 / (2.0 * std::f64::consts::PI * 10.0);
        let n = 100;
        let dt = tau / n as f64;
        for _ in 0..n {
            f.update(&Vector3::new(1.0, -2.0, 0.0), dt);
        }
        let expected = 1.0 - (-1.0f64).exp();
        assert!((f.value().x - expected).abs() < 1e-12);
        assert!((f.value().y + 2.0 * expected).abs() < 1e-12);
        // Derivative of the output: (1 − e^-1) ... slope e^-1 / tau at t = tau, within 1 %.
        let slope = (-1.0f64).exp() / tau;
        assert!((f.derivative(dt).x - slope).abs() / slope < 0.01);
    }

    #[test]
    fn first_sample_seeds_without_derivative_kick() {
        let mut f = LowPass3::new(10.0);
        f.update(&Vector3::new(5.0, 0.0, 0.0), 0.01);
        assert_eq!(f.value().x, 5.0);
        assert_eq!(f.derivative(0.01), Vector3::zeros());
        f.unprime();
        f.update(&Vector3::new(-3.0, 0.0, 0.0), 0.01);
        assert_eq!(f.value().x, -3.0);
        assert_eq!(f.derivative(0.01), Vector3::zeros());
    }
}
