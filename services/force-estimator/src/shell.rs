//! The estimator service `<uav>-force-estimator`: subscribes IMU and MOTOR_SPEEDS (from the PX4
//! bridge), publishes TENSION_ESTIMATE, one sample per IMU sample, until SIGINT/SIGTERM.
//! Motor speeds are drained before the IMU samples of the same wake-up, so an estimate uses
//! the newest speeds received. `cfg.services.force_estimator` is applied first.

use std::time::Duration;

use rt_config::Config;
use shared_types::{names, ImuSample, MotorSpeeds, TensionSample};
use taut_ipc::{stop_requested, Ipc};

use crate::ForceEstimator;

/// Runs the estimator service until a stop signal.
pub fn run(cfg: &Config) -> Result<(), String> {
    let report = rt_config::rt::apply(&cfg.services.force_estimator)
        .map_err(|e| format!("force-estimator: {e}"))?;
    eprintln!("[force-estimator] real-time: {report}");
    let mut estimator =
        ForceEstimator::new(&cfg.vehicle, &cfg.estimator).map_err(|e| e.to_string())?;
    let ipc = Ipc::new(
        &format!("{}-force-estimator", cfg.uav),
        &cfg.ipc_root,
        &cfg.uav,
    )
    .map_err(|e| e.to_string())?;
    let e = |e: taut_ipc::IpcError| e.to_string();
    let imus = ipc.subscriber::<ImuSample>(names::IMU).map_err(e)?;
    let motors = ipc
        .subscriber::<MotorSpeeds>(names::MOTOR_SPEEDS)
        .map_err(e)?;
    let mut output = ipc
        .publisher::<TensionSample>(names::TENSION_ESTIMATE)
        .map_err(e)?;
    let mut errors = 0u64;
    while !stop_requested() {
        if imus.wait(Duration::from_millis(100)).is_err() && !stop_requested() {
            errors += 1;
        }
        if motors
            .drain(&mut |m: MotorSpeeds| estimator.on_motor_speeds(&m))
            .is_err()
        {
            errors += 1;
        }
        let mut publish_errors = 0u64;
        let drained = imus.drain(&mut |s: ImuSample| {
            if output.publish(estimator.on_imu(&s)).is_err() {
                publish_errors += 1;
            }
        });
        errors += publish_errors + u64::from(drained.is_err());
    }
    let c = estimator.counters();
    eprintln!(
        "[force-estimator] stopped: imu={} motors={} stale_motor_estimates={} non_finite_imu={} \
         non_finite_motors={} imu_gaps={} ipc_errors={errors}",
        c.imu_samples,
        c.motor_samples,
        c.stale_motor_estimates,
        c.non_finite_imu,
        c.non_finite_motors,
        c.imu_gaps
    );
    Ok(())
}
