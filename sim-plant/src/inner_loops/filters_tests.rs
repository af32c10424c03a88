use super::*;

/// Steady-state amplitude ratio of the filter for a sine at `freq_hz`, sampled at `fs`.
fn amplitude_ratio(fs: f64, fc: f64, freq_hz: f64) -> f64 {
    let mut f = LowPassFilter2p::new(fs, fc);
    let n = (fs * 2.0) as usize; // 2 s: transient long gone
    let mut peak: f64 = 0.0;
    for k in 0..n {
        let y = f.apply((2.0 * PI * freq_hz * k as f64 / fs).sin());
        if k > n / 2 {
            peak = peak.max(y.abs());
        }
    }
    peak
}

#[test]
fn lpf2p_is_minus_3_db_at_cutoff() {
    for (fs, fc) in [(400.0, 40.0), (400.0, 20.0), (1000.0, 30.0)] {
        let r = amplitude_ratio(fs, fc, fc);
        let db = 20.0 * r.log10();
        assert!(
            (r - 0.5f64.sqrt()).abs() < 0.05 * 0.5f64.sqrt(),
            "fs {fs} fc {fc}: {r}"
        );
        assert!((db + 3.01).abs() < 0.2, "fs {fs} fc {fc}: {db} dB");
    }
    // Passband and stopband: ~1 at fc/10, -40 dB/decade above (Butterworth, order 2).
    let low = amplitude_ratio(400.0, 40.0, 4.0);
    assert!((low - 1.0).abs() < 0.005, "{low}");
    let high = amplitude_ratio(1000.0, 20.0, 200.0);
    assert!(high < 0.012, "{high}"); // analog value 1/101 ~ 0.0099; bilinear warps lower
}

#[test]
fn lpf2p_unit_dc_gain_and_reset_to_steady_state() {
    let mut f = LowPassFilter2p::new(400.0, 40.0);
    let first = f.reset(2.5);
    assert!((first - 2.5).abs() < 1e-12);
    for _ in 0..10 {
        assert!((f.apply(2.5) - 2.5).abs() < 1e-12);
    }
    // From zero a step converges to the step.
    let mut g = LowPassFilter2p::new(400.0, 40.0);
    let mut y = 0.0;
    for _ in 0..400 {
        y = g.apply(1.0);
    }
    assert!((y - 1.0).abs() < 1e-9);
}

#[test]
fn lpf2p_disabled_is_pass_through() {
    for fc in [0.0, -1.0, 200.0, f64::NAN] {
        let mut f = LowPassFilter2p::new(400.0, fc);
        assert_eq!(f.apply(3.0), 3.0);
        assert_eq!(f.apply(-1.0), -1.0);
    }
}

#[test]
fn alpha_filter_has_first_order_step_response() {
    // tau = 1/(2 pi 2 Hz) = 79.6 ms; after one tau the discrete response is ~ 1 - 1/e.
    let mut f = AlphaFilter::new(2.0);
    let dt = 0.0025;
    let tau = 1.0 / (2.0 * PI * 2.0);
    let steps = (tau / dt).round() as usize;
    let mut y = 0.0;
    for _ in 0..steps {
        y = f.update(1.0, dt);
    }
    assert!((y - (1.0 - (-1.0f64).exp())).abs() < 0.02, "{y}");
    let mut pass = AlphaFilter::new(0.0);
    assert_eq!(pass.update(5.0, dt), 5.0);
}

#[test]
fn block_derivative_of_a_ramp_is_its_slope() {
    let mut d = BlockDerivative::new(5.0);
    let dt = 0.01;
    assert_eq!(d.update(0.0, dt), 0.0);
    let mut y = 0.0;
    for k in 1..300 {
        y = d.update(2.0 * k as f64 * dt, dt);
    }
    assert!((y - 2.0).abs() < 1e-6, "{y}");
    d.reset();
    assert_eq!(d.update(100.0, dt), 0.0);
}
