use super::*;

const PERIOD_NS: u64 = 10_000_000;

fn sample_std(values: &[f64]) -> f64 {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[test]
fn white_noise_std_matches_sigma_over_100k_samples() {
    let mut p = MocapPerturbation::new(PerturbationParams::default(), 7).unwrap();
    let truth = Vector3::new(1.0, -2.0, -1.5);
    let mut noise: [Vec<f64>; 3] = Default::default();
    for k in 0..100_000u64 {
        let s = p.poll(k * PERIOD_NS, &truth).expect("due every period");
        assert!((s.position_ned - (truth + s.white_noise_ned + s.bias_ned)).norm() < 1e-12);
        for (axis, values) in noise.iter_mut().enumerate() {
            values.push(s.white_noise_ned[axis]);
        }
    }
    for (axis, want) in [0.03, 0.03, 0.06].into_iter().enumerate() {
        let got = sample_std(&noise[axis]);
        println!("white noise axis {axis}: std {got:.5} m (want {want})");
        assert!(
            (got / want - 1.0).abs() < 0.05,
            "axis {axis}: {got} vs {want}"
        );
    }
}

/// 400 independent seeds, 60 s each: the bias stays at its stationary std, drifts by
/// 0.887 sigma over 30 s, and its autocorrelation at lag tau is exp(-1). Sampled at 25 Hz to
/// keep the debug build quick; the discretisation is exact for any period.
#[test]
fn bias_is_stationary_with_tau_correlation_across_seeds() {
    let sigma_b = [0.08, 0.08, 0.15];
    let (mut b0, mut b30, mut b60) = (Vec::new(), Vec::new(), Vec::new());
    let truth = Vector3::zeros();
    let params = PerturbationParams {
        rate_hz: 25.0,
        ..PerturbationParams::default()
    };
    for seed in 0..400u64 {
        let mut p = MocapPerturbation::new(params.clone(), 1000 + seed).unwrap();
        for k in 0..=1500u64 {
            let s = p.poll(k * 4 * PERIOD_NS, &truth).unwrap();
            let record = match k {
                0 => Some(&mut b0),
                750 => Some(&mut b30),
                1500 => Some(&mut b60),
                _ => None,
            };
            if let Some(v) = record {
                // Normalised by the axis std so the three axes pool into one sample.
                v.extend((0..3).map(|a| s.bias_ned[a] / sigma_b[a]));
            }
        }
    }
    let std0 = sample_std(&b0);
    let std60 = sample_std(&b60);
    let drift: Vec<f64> = b30.iter().zip(&b0).map(|(a, b)| a - b).collect();
    let drift_std = sample_std(&drift);
    let rho = correlation(&b0, &b60);
    println!(
        "bias/sigma_b: std at 0 s {std0:.3}, at 60 s {std60:.3}; 30 s drift std {drift_std:.3} \
         (want 0.887); autocorrelation at lag 60 s {rho:.3} (want {:.3})",
        (-1.0f64).exp()
    );
    assert!((std0 - 1.0).abs() < 0.15, "{std0}");
    assert!((std60 - 1.0).abs() < 0.15, "{std60}");
    let want_drift = (2.0 * (1.0 - (-0.5f64).exp())).sqrt();
    assert!((drift_std / want_drift - 1.0).abs() < 0.15, "{drift_std}");
    assert!((rho - (-1.0f64).exp()).abs() < 0.08, "{rho}");
}

#[test]
fn same_seed_repeats_and_different_seeds_differ() {
    let truth = Vector3::new(0.5, 0.5, -1.0);
    let run = |seed: u64| {
        let mut p = MocapPerturbation::new(PerturbationParams::default(), seed).unwrap();
        (0..50u64)
            .map(|k| p.poll(k * PERIOD_NS, &truth).unwrap().position_ned)
            .collect::<Vec<_>>()
    };
    assert_eq!(run(3), run(3));
    let (a, b) = (run(3), run(4));
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).norm() > 1e-9));
}

#[test]
fn disabled_returns_exact_truth() {
    let params = PerturbationParams {
        enabled: false,
        ..PerturbationParams::default()
    };
    let mut p = MocapPerturbation::new(params, 1).unwrap();
    for k in 0..100u64 {
        let truth = Vector3::new(k as f64 * 0.01, -0.3, -1.2);
        let s = p.poll(k * PERIOD_NS, &truth).unwrap();
        assert_eq!(s.position_ned, truth);
        assert_eq!(s.bias_ned, Vector3::zeros());
    }
}

#[test]
fn poll_delivers_at_the_rate_and_skips_missed_samples() {
    let mut p = MocapPerturbation::new(PerturbationParams::default(), 1).unwrap();
    let truth = Vector3::zeros();
    let t0 = 5_000_000_000;
    assert!(p.poll(t0, &truth).is_some(), "first poll is due");
    assert!(p.poll(t0 + PERIOD_NS - 1, &truth).is_none());
    assert!(p.poll(t0 + PERIOD_NS, &truth).is_some());
    // A caller 5 periods late gets one sample, and the next is due a period after it.
    let late = t0 + 6 * PERIOD_NS + 3;
    assert!(p.poll(late, &truth).is_some());
    assert!(p.poll(late + PERIOD_NS - 1, &truth).is_none());
    assert!(p.poll(late + PERIOD_NS, &truth).is_some());
    assert_eq!(p.samples(), 4);
    let nan = Vector3::new(f64::NAN, 0.0, 0.0);
    assert!(p.poll(late + 3 * PERIOD_NS, &nan).is_none());
    assert_eq!(p.rejected_inputs(), 1);
}

#[test]
fn validate_names_the_key() {
    let bad = PerturbationParams {
        bias_std_m: [0.08, -0.1, 0.15],
        ..PerturbationParams::default()
    };
    assert_eq!(bad.validate().unwrap_err().key, "bias_std_m");
    let bad = PerturbationParams {
        rate_hz: 0.0,
        ..PerturbationParams::default()
    };
    let err = MocapPerturbation::new(bad, 0).unwrap_err();
    assert_eq!(err.key, "rate_hz");
    assert!(err.to_string().contains("rate_hz"));
    let p: PerturbationParams = toml::from_str("enabled = false\nbias_tau_s = 30.0\n").unwrap();
    assert!(!p.enabled);
    assert_eq!(p.rate_hz, 100.0);
}
