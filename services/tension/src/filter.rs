//! Moving average over the last `window` vectors, in a fixed ring (no allocation).

/// Largest window the fixed ring holds.
pub const MAX_WINDOW: usize = 64;

/// Moving average of `[f64; N]` vectors. A window of 4 at 240 Hz delays by 1.5 samples
/// (6.25 ms): the paper's "~6 ms" filter budget.
#[derive(Debug, Clone)]
pub struct MovingAverage<const N: usize> {
    ring: [[f64; N]; MAX_WINDOW],
    sum: [f64; N],
    window: usize,
    len: usize,
    head: usize,
    pushes_since_resum: usize,
}

impl<const N: usize> MovingAverage<N> {
    /// `window` is clamped to 1..=MAX_WINDOW (the config validates it first).
    pub fn new(window: usize) -> Self {
        Self {
            ring: [[0.0; N]; MAX_WINDOW],
            sum: [0.0; N],
            window: window.clamp(1, MAX_WINDOW),
            len: 0,
            head: 0,
            pushes_since_resum: 0,
        }
    }

    pub fn window(&self) -> usize {
        self.window
    }

    /// True once `window` values have been pushed since the last reset.
    pub fn is_full(&self) -> bool {
        self.len == self.window
    }

    pub fn reset(&mut self) {
        self.len = 0;
        self.head = 0;
        self.sum = [0.0; N];
    }

    /// Adds `x` and returns the mean of the values in the window (fewer while warming up).
    pub fn push(&mut self, x: [f64; N]) -> [f64; N] {
        if self.len == self.window {
            let old = self.ring[self.head];
            for (s, o) in self.sum.iter_mut().zip(old) {
                *s -= o;
            }
        } else {
            self.len += 1;
        }
        self.ring[self.head] = x;
        for (s, v) in self.sum.iter_mut().zip(x) {
            *s += v;
        }
        self.head = (self.head + 1) % self.window;
        // Running sums drift by rounding over millions of samples: re-add now and then.
        self.pushes_since_resum += 1;
        if self.pushes_since_resum >= 4096 {
            self.pushes_since_resum = 0;
            self.sum = [0.0; N];
            for v in &self.ring[..self.len] {
                for (s, x) in self.sum.iter_mut().zip(v) {
                    *s += x;
                }
            }
        }
        let n = self.len as f64;
        self.sum.map(|s| s / n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averages_the_last_window() {
        let mut m = MovingAverage::<1>::new(4);
        assert_eq!(m.push([4.0]), [4.0]);
        assert!(!m.is_full());
        m.push([8.0]);
        m.push([0.0]);
        assert_eq!(m.push([4.0]), [4.0]);
        assert!(m.is_full());
        assert_eq!(m.push([12.0]), [6.0]); // (8 + 0 + 4 + 12) / 4
    }

    #[test]
    fn ramp_lags_by_half_the_window_minus_one() {
        // A ramp x_k = k through a window-4 average reads k - 1.5: 1.5 samples of lag.
        let mut m = MovingAverage::<1>::new(4);
        let mut out = 0.0;
        for k in 0..100 {
            out = m.push([k as f64])[0];
        }
        assert!((99.0 - out - 1.5).abs() < 1e-12);
    }

    #[test]
    fn long_runs_do_not_drift() {
        let mut m = MovingAverage::<1>::new(3);
        for k in 0..100_000 {
            m.push([1e6 + (k % 7) as f64 * 0.1]);
        }
        let out = m.push([1.0])[0];
        let exact = (m.ring[..3].iter().map(|v| v[0]).sum::<f64>()) / 3.0;
        assert!((out - exact).abs() < 1e-6, "{out} vs {exact}");
    }
}
