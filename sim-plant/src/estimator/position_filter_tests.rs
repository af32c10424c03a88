use super::*;
use crate::estimator::{ImuModel, ImuParams, MocapPerturbation, PerturbationParams};

/// A truth trajectory with constant acceleration and a fixed, slightly tilted attitude.
struct Truth {
    p0: Vector3<f64>,
    v0: Vector3<f64>,
    a: Vector3<f64>,
    q: UnitQuaternion<f64>,
}

impl Truth {
    fn position(&self, t: f64) -> Vector3<f64> {
        self.p0 + self.v0 * t + self.a * (0.5 * t * t)
    }
    fn velocity(&self, t: f64) -> Vector3<f64> {
        self.v0 + self.a * t
    }
    fn specific_force_frd(&self) -> Vector3<f64> {
        self.q.inverse() * (self.a - Vector3::new(0.0, 0.0, GRAVITY_MPS2))
    }
}

struct Run {
    /// Per-sample position and velocity errors (estimate - truth) after the settling time.
    pos_err: Vec<Vector3<f64>>,
    vel_err: Vec<Vector3<f64>>,
}

/// Runs the estimator for `duration_s` with the IMU every `imu_ns` and the motion capture at
/// its own rate, fusing each mocap sample right after the IMU step that reaches its time.
fn run(
    truth: &Truth,
    est_params: EstimatorParams,
    imu_params: ImuParams,
    pert_params: PerturbationParams,
    imu_ns: u64,
    duration_s: f64,
    settle_s: f64,
) -> (Run, PositionEstimator) {
    let mut est = PositionEstimator::new(est_params, 1).unwrap();
    let mut imu = ImuModel::new(imu_params, 2).unwrap();
    let mut mocap = MocapPerturbation::new(pert_params, 3).unwrap();
    let mut out = Run {
        pos_err: Vec::new(),
        vel_err: Vec::new(),
    };
    let steps = (duration_s * 1e9 / imu_ns as f64) as u64;
    let rate = Vector3::new(0.01, -0.02, 0.03);
    for k in 0..=steps {
        let t_ns = k * imu_ns;
        let t = t_ns as f64 * 1e-9;
        if k > 0 {
            let sample = imu.measure(&truth.specific_force_frd(), &rate).unwrap();
            est.predict(t_ns, imu_ns as f64 * 1e-9, &sample, &truth.q);
        }
        if let Some(m) = mocap.poll(t_ns, &truth.position(t)) {
            est.correct(m.t_ns, &m.position_ned);
        }
        if t >= settle_s {
            let e = est.estimate();
            out.pos_err.push(e.position_ned - truth.position(t));
            out.vel_err.push(e.velocity_ned - truth.velocity(t));
        }
    }
    (out, est)
}

fn mean_std(values: &[Vector3<f64>], axis: usize) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().map(|v| v[axis]).sum::<f64>() / n;
    let var = values.iter().map(|v| (v[axis] - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

fn tilted() -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(0.05, -0.08, 0.7)
}

fn quiet() -> PerturbationParams {
    PerturbationParams {
        enabled: false,
        ..PerturbationParams::default()
    }
}

#[test]
fn noise_free_inputs_converge_to_truth() {
    let truth = Truth {
        p0: Vector3::new(1.0, -0.5, -1.2),
        v0: Vector3::new(0.5, -0.3, 0.2),
        a: Vector3::zeros(),
        q: tilted(),
    };
    // IMU at 200 Hz so every 10 ms mocap sample lands on an IMU step: no timing offset.
    let (r, est) = run(
        &truth,
        EstimatorParams::default(),
        ImuParams::ideal(),
        quiet(),
        5_000_000,
        15.0,
        10.0,
    );
    let max_p = r.pos_err.iter().map(|e| e.norm()).fold(0.0, f64::max);
    let max_v = r.vel_err.iter().map(|e| e.norm()).fold(0.0, f64::max);
    println!("noise-free, after 10 s: max |position error| {max_p:.2e} m, |velocity error| {max_v:.2e} m/s");
    assert!(max_p < 1e-4 && max_v < 1e-4, "{max_p} {max_v}");
    assert!(est.estimate().position_valid);
    assert_eq!(est.gated_innovations(), 0);
}

#[test]
fn white_noise_is_smoothed_and_velocity_is_unbiased() {
    let truth = Truth {
        p0: Vector3::new(0.0, 1.0, -1.5),
        v0: Vector3::zeros(),
        a: Vector3::zeros(),
        q: tilted(),
    };
    let white_only = PerturbationParams {
        bias_std_m: [0.0; 3],
        ..PerturbationParams::default()
    };
    let raw = white_only.white_noise_std_m;
    let matched = EstimatorParams {
        ev_pos_noise_std_m: raw,
        ..EstimatorParams::default()
    };
    for (label, params) in [
        ("EKF2 default R = 0.1 m", EstimatorParams::default()),
        ("R = Sigma", matched),
    ] {
        let (r, _) = run(
            &truth,
            params,
            ImuParams::default(),
            white_only.clone(),
            4_000_000,
            120.0,
            5.0,
        );
        for (axis, raw_std) in raw.iter().enumerate() {
            let (_, p_std) = mean_std(&r.pos_err, axis);
            let (v_mean, v_std) = mean_std(&r.vel_err, axis);
            let ratio = p_std / raw_std;
            println!(
                "{label}, axis {axis}: position error std {p_std:.4} m = {ratio:.3} x raw {}; \
                 velocity error mean {v_mean:+.4} std {v_std:.4} m/s",
                raw_std
            );
            assert!(ratio < 0.5, "axis {axis}: ratio {ratio}");
            assert!(
                v_mean.abs() < 0.01 && v_mean.abs() < 0.5 * v_std,
                "axis {axis}: {v_mean}"
            );
        }
    }
}

#[test]
fn constant_acceleration_is_tracked_without_lag() {
    let truth = Truth {
        p0: Vector3::new(-1.0, 0.0, -1.0),
        v0: Vector3::zeros(),
        a: Vector3::new(0.3, -0.2, -0.1),
        q: tilted(),
    };
    let (r, _) = run(
        &truth,
        EstimatorParams::default(),
        ImuParams::ideal(),
        quiet(),
        5_000_000,
        10.0,
        2.0,
    );
    let max_p = r.pos_err.iter().map(|e| e.norm()).fold(0.0, f64::max);
    println!("constant acceleration, exact inputs: max |position error| {max_p:.2e} m");
    assert!(max_p < 1e-6);

    // Realistic: 250 Hz IMU with noise, white mocap noise, mocap fused after the IMU step that
    // reaches its time (up to 2 ms early), 20 s of constant acceleration reaching ~6 m/s.
    let white_only = PerturbationParams {
        bias_std_m: [0.0; 3],
        ..PerturbationParams::default()
    };
    let (r, _) = run(
        &truth,
        EstimatorParams::default(),
        ImuParams::default(),
        white_only,
        4_000_000,
        20.0,
        5.0,
    );
    for axis in 0..3 {
        let (mean, std) = mean_std(&r.pos_err, axis);
        println!("constant acceleration, noisy: axis {axis} position error mean {mean:+.4} m (lag), std {std:.4} m");
        assert!(mean.abs() < 0.01, "axis {axis}: {mean}");
    }
}

#[test]
fn accelerometer_bias_gives_a_small_position_offset() {
    let truth = Truth {
        p0: Vector3::zeros(),
        v0: Vector3::zeros(),
        a: Vector3::zeros(),
        q: UnitQuaternion::identity(),
    };
    let biased = ImuParams {
        accel_bias_frd_mps2: [0.1, 0.0, 0.0],
        ..ImuParams::ideal()
    };
    let (r, _) = run(
        &truth,
        EstimatorParams::default(),
        biased,
        quiet(),
        5_000_000,
        30.0,
        20.0,
    );
    let (mean, _) = mean_std(&r.pos_err, 0);
    println!("0.1 m/s^2 accelerometer bias (not estimated): position offset {mean:+.4} m");
    assert!(mean > 0.0 && mean < 0.05, "{mean}");
}

#[test]
fn bad_inputs_are_rejected_and_outliers_gated() {
    let mut est = PositionEstimator::new(EstimatorParams::default(), 0).unwrap();
    let imu = ImuSample {
        specific_force_frd: Vector3::new(0.0, 0.0, -GRAVITY_MPS2),
        angular_rate_frd: Vector3::zeros(),
    };
    let q = UnitQuaternion::identity();
    est.predict(1_000, 0.004, &imu, &q);
    assert!(
        !est.estimate().position_valid,
        "no position before the first measurement"
    );
    assert!(!est.correct(2_000, &Vector3::new(f64::NAN, 0.0, 0.0)));
    assert!(est.correct(3_000, &Vector3::new(1.0, 2.0, -3.0)));
    let e = est.estimate();
    assert!(e.position_valid);
    assert_eq!(e.position_ned, Vector3::new(1.0, 2.0, -3.0));
    est.predict(4_000, f64::NAN, &imu, &q);
    est.predict(5_000, 0.0, &imu, &q);
    let nan_imu = ImuSample {
        specific_force_frd: Vector3::new(0.0, f64::INFINITY, 0.0),
        ..imu
    };
    est.predict(6_000, 0.004, &nan_imu, &q);
    assert_eq!(est.rejected_inputs(), 4);
    assert_eq!(est.estimate().position_ned, Vector3::new(1.0, 2.0, -3.0));
    // A 5 m jump on x is far outside the 5-sigma gate; y and z still fuse.
    assert!(!est.correct(7_000, &Vector3::new(6.0, 2.0, -3.0)));
    assert_eq!(est.gated_innovations(), 1);
    assert!((est.estimate().position_ned.x - 1.0).abs() < 1e-12);
    let bad = EstimatorParams {
        ev_pos_noise_std_m: [0.1, 0.0, 0.1],
        ..EstimatorParams::default()
    };
    assert_eq!(
        PositionEstimator::new(bad, 0).unwrap_err().key,
        "ev_pos_noise_std_m"
    );
}

#[test]
fn attitude_noise_is_small_rotation_about_truth() {
    let params = EstimatorParams {
        attitude_noise_std_rad: 0.01,
        ..EstimatorParams::default()
    };
    let mut est = PositionEstimator::new(params, 9).unwrap();
    let imu = ImuSample {
        specific_force_frd: Vector3::new(0.0, 0.0, -GRAVITY_MPS2),
        angular_rate_frd: Vector3::zeros(),
    };
    let q = tilted();
    let mut sum_sq = 0.0;
    for k in 1..=2000u64 {
        est.predict(k * 4_000_000, 0.004, &imu, &q);
        sum_sq += est.estimate().attitude.angle_to(&q).powi(2);
    }
    // Angle of a 3-D isotropic error with 0.01 rad per axis: rms 0.01 sqrt(3).
    let rms = (sum_sq / 2000.0).sqrt();
    assert!((rms / (0.01 * 3f64.sqrt()) - 1.0).abs() < 0.1, "{rms}");
}
