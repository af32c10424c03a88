use super::*;
use rt_config::{EstimatorConfig, VehicleConfig};

const G: f64 = 9.80665;
const C_T: f64 = 8.54858e-6;
/// IMU period of the tests: 900 Hz, the paper's accelerometer rate.
const IMU_NS: u64 = 1_111_111;

fn estimator() -> ForceEstimator {
    ForceEstimator::new(&VehicleConfig::default(), &EstimatorConfig::default()).unwrap()
}

fn mass() -> f64 {
    VehicleConfig::default().mass_kg
}

fn imu(t_ns: u64, seq: u64, sf: [f64; 3]) -> ImuSample {
    let mut s = ImuSample {
        px4_time_us: t_ns / 1000,
        specific_force_frd_m_s2: sf,
        ..Default::default()
    };
    s.header.t_origin_ns = t_ns;
    s.header.sequence = seq;
    s
}

/// Four equal rotor speeds giving `thrust_n` in total.
fn motors(t_ns: u64, thrust_n: f64) -> MotorSpeeds {
    let w = (thrust_n / (4.0 * C_T)).sqrt();
    let mut m = MotorSpeeds {
        rotor_speed_rad_s: [w; 4],
        ..Default::default()
    };
    m.header.t_origin_ns = t_ns;
    m
}

#[test]
fn hover_without_load_estimates_zero() {
    let mut e = estimator();
    let t0 = 1_000_000_000;
    e.on_motor_speeds(&motors(t0, mass() * G));
    for i in 0..900 {
        let out = e.on_imu(&imu(t0 + i * IMU_NS, i, [0.0, 0.0, -G]));
        for v in out.force_body_n {
            assert!(v.abs() < 1e-9, "{:?}", out.force_body_n);
        }
        if i > 10 && i < 800 {
            // Motor speeds are at most 0.1 s old until i = 90; then stale.
            assert_eq!(
                out.flags & tension_flags::STALE_INPUT != 0,
                i as f64 * 1.111 > 100.0
            );
        }
    }
}

#[test]
fn hanging_load_at_rest_reads_its_weight_exactly() {
    let mut e = estimator();
    let t0 = 5_000_000_000;
    let load = 5.0;
    let mut last = TensionSample::default();
    for i in 0..100 {
        let t = t0 + i * IMU_NS;
        if i % 15 == 0 {
            e.on_motor_speeds(&motors(t, mass() * G + load));
        }
        last = e.on_imu(&imu(t, i, [0.0, 0.0, -G]));
        assert!((last.force_body_n[2] - load).abs() < 1e-9, "{last:?}");
        assert_eq!(last.force_body_n[0], 0.0);
        assert_eq!(last.force_body_n[1], 0.0);
    }
    // Seeded, 3 time constants of 10 Hz (48 ms = 43 samples) later no longer warming up.
    assert_eq!(last.flags, 0);
    assert_eq!(last.header.t_origin_ns, t0 + 99 * IMU_NS);
    assert_eq!(last.raw_sequence, 99);
}

#[test]
fn thrust_step_with_its_acceleration_step_has_no_transient() {
    let mut e = estimator();
    let t0 = 1_000_000_000;
    let load = 3.0;
    let m = mass();
    e.on_motor_speeds(&motors(t0, m * G + load));
    for i in 0..50 {
        e.on_imu(&imu(t0 + i * IMU_NS, i, [0.0, 0.0, -G]));
    }
    // +6 N of thrust: the drone accelerates up by 6 / m; the accelerometer sees it at once.
    let t1 = t0 + 50 * IMU_NS;
    e.on_motor_speeds(&motors(t1, m * G + load + 6.0));
    let mut worst: f64 = 0.0;
    for i in 50..300 {
        let out = e.on_imu(&imu(t0 + i * IMU_NS, i, [0.0, 0.0, -G - 6.0 / m]));
        worst = worst.max((out.force_body_n[2] - load).abs());
    }
    assert!(worst < 1e-9, "transient {worst} N");
    // The same step with the motor speeds 10 ms late (the real hold): a visible transient.
    let mut late = estimator();
    late.on_motor_speeds(&motors(t0, m * G + load));
    for i in 0..50 {
        late.on_imu(&imu(t0 + i * IMU_NS, i, [0.0, 0.0, -G]));
    }
    let mut worst_late: f64 = 0.0;
    for i in 50..300 {
        if i == 59 {
            late.on_motor_speeds(&motors(t0 + i * IMU_NS, m * G + load + 6.0));
        }
        let out = late.on_imu(&imu(t0 + i * IMU_NS, i, [0.0, 0.0, -G - 6.0 / m]));
        worst_late = worst_late.max((out.force_body_n[2] - load).abs());
    }
    // 10 ms of a −6 N error through a 10 Hz low-pass: 6 (1 − e^(−2π·10·0.01)) ≈ 2.8 N.
    assert!(
        (worst_late - 2.80).abs() < 0.1,
        "late transient {worst_late} N"
    );
}

#[test]
fn lateral_pull_reads_in_body_frd() {
    // Level, a 2 N pull north (body x forward = north at yaw 0): thrust m g, the drone
    // accelerates at 2 / m north: sf = (2/m, 0, -g).
    let mut e = estimator();
    let m = mass();
    e.on_motor_speeds(&motors(0, m * G));
    let out = e.on_imu(&imu(1_000, 0, [2.0 / m, 0.0, -G]));
    assert!((out.force_body_n[0] - 2.0).abs() < 1e-9);
    assert!(out.force_body_n[2].abs() < 1e-9);
}

#[test]
fn stale_or_missing_motor_speeds_are_flagged() {
    let mut e = estimator();
    let out = e.on_imu(&imu(1_000_000, 0, [0.0, 0.0, -G]));
    assert_ne!(
        out.flags & tension_flags::STALE_INPUT,
        0,
        "no motor speeds yet"
    );
    assert!(
        (out.force_body_n[2] + mass() * G).abs() < 1e-9,
        "thrust taken as 0"
    );
    e.on_motor_speeds(&motors(2_000_000, mass() * G));
    let out = e.on_imu(&imu(2_500_000, 1, [0.0, 0.0, -G]));
    assert_eq!(out.flags & tension_flags::STALE_INPUT, 0);
    // 0.1 s + 1 ns after the motor speeds: stale.
    let out = e.on_imu(&imu(102_000_001, 2, [0.0, 0.0, -G]));
    assert_ne!(out.flags & tension_flags::STALE_INPUT, 0);
    assert_eq!(e.counters().stale_motor_estimates, 2);
}

#[test]
fn gaps_reseed_and_non_finite_samples_hold() {
    let mut e = estimator();
    e.on_motor_speeds(&motors(0, mass() * G));
    e.on_imu(&imu(1_000_000, 0, [0.0, 0.0, -G]));
    let out = e.on_imu(&imu(2_000_000, 5, [0.0, 0.0, -G]));
    assert_ne!(out.flags & tension_flags::INPUT_GAP, 0, "sequence jump");
    let held = out.force_body_n;
    let out = e.on_imu(&imu(3_000_000, 6, [f64::NAN, 0.0, -G]));
    assert_ne!(out.flags & tension_flags::NON_FINITE, 0);
    assert_eq!(out.force_body_n, held);
    // 0.2 s of silence: re-seeded (the new value at once) and warming up again.
    e.on_motor_speeds(&motors(200_000_000, mass() * G + 4.0));
    let out = e.on_imu(&imu(203_000_000, 7, [0.0, 0.0, -G]));
    assert_ne!(out.flags & tension_flags::INPUT_GAP, 0);
    assert_ne!(out.flags & tension_flags::FILTER_WARMUP, 0);
    assert!((out.force_body_n[2] - 4.0).abs() < 1e-9);
}

#[test]
fn bad_config_names_its_key() {
    let cfg = EstimatorConfig {
        motor_speeds_max_age_s: -1.0,
        ..Default::default()
    };
    let e = ForceEstimator::new(&VehicleConfig::default(), &cfg).unwrap_err();
    assert!(e.to_string().contains("estimator.motor_speeds_max_age_s"));
}
