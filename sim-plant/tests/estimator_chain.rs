//! The whole estimation chain for two drones with their own seeds: truth -> perturbed motion
//! capture (100 Hz) and noisy IMU (250 Hz) -> position estimator -> commander, hovering 30 s.

use nalgebra::{UnitQuaternion, Vector3};
use sim_plant::commander::{CommandLong, Commander, CommanderParams, ControlDemand, MavResult};
use sim_plant::estimator::{
    EstimatorParams, ImuModel, ImuParams, MocapPerturbation, PerturbationParams, PositionEstimator,
    GRAVITY_MPS2,
};

const IMU_NS: u64 = 4_000_000;

struct Drone {
    mocap: MocapPerturbation,
    imu: ImuModel,
    est: PositionEstimator,
    truth: Vector3<f64>,
    /// Estimate minus (truth + bias): what the filter adds on top of the mocap bias.
    residual: Vec<Vector3<f64>>,
    /// Estimate minus truth.
    error: Vec<Vector3<f64>>,
    bias: Vector3<f64>,
}

impl Drone {
    fn new(seed: u64, truth: Vector3<f64>) -> Drone {
        Drone {
            mocap: MocapPerturbation::new(PerturbationParams::default(), seed).unwrap(),
            imu: ImuModel::new(ImuParams::default(), seed + 100).unwrap(),
            est: PositionEstimator::new(EstimatorParams::default(), seed + 200).unwrap(),
            truth,
            residual: Vec::new(),
            error: Vec::new(),
            bias: Vector3::zeros(),
        }
    }

    fn step(&mut self, t_ns: u64, q: &UnitQuaternion<f64>) {
        let f_frd = q.inverse() * Vector3::new(0.0, 0.0, -GRAVITY_MPS2);
        if t_ns > 0 {
            let sample = self.imu.measure(&f_frd, &Vector3::zeros()).unwrap();
            self.est.predict(t_ns, IMU_NS as f64 * 1e-9, &sample, q);
        }
        if let Some(m) = self.mocap.poll(t_ns, &self.truth) {
            self.est.correct(m.t_ns, &m.position_ned);
            self.bias = m.bias_ned;
        }
        if t_ns >= 5_000_000_000 {
            let e = self.est.estimate();
            self.error.push(e.position_ned - self.truth);
            self.residual.push(e.position_ned - self.truth - self.bias);
        }
    }
}

fn rms(values: &[Vector3<f64>], axis: usize) -> f64 {
    (values.iter().map(|v| v[axis] * v[axis]).sum::<f64>() / values.len() as f64).sqrt()
}

#[test]
fn two_drones_hover_on_independent_biased_estimates() {
    let q = UnitQuaternion::from_euler_angles(0.0, 0.0, 1.0);
    let mut drones = [
        Drone::new(11, Vector3::new(0.5, -0.75, -1.5)),
        Drone::new(12, Vector3::new(0.5, 0.75, -1.5)),
    ];
    let mut commander = Commander::new(CommanderParams::default()).unwrap();
    let hold = CommandLong {
        command: 176,
        params: [1.0, 4.0, 3.0, 0.0, 0.0, 0.0, 0.0],
    };
    assert_eq!(commander.on_command(0, &hold), MavResult::Accepted);
    let mut demand = ControlDemand::MotorsOff;
    for k in 0..=(30_000_000_000 / IMU_NS) {
        let t_ns = k * IMU_NS;
        for d in drones.iter_mut() {
            d.step(t_ns, &q);
        }
        demand = commander.update(t_ns, &drones[0].est.estimate(), true);
    }
    assert_eq!(demand, ControlDemand::MotorsOff, "never armed");
    let white = PerturbationParams::default().white_noise_std_m;
    for (i, d) in drones.iter().enumerate() {
        for (axis, white_std) in white.iter().enumerate() {
            let (err, res) = (rms(&d.error, axis), rms(&d.residual, axis));
            println!(
                "drone {i} axis {axis}: bias {:+.3} m, estimate error rms {err:.3} m, \
                 residual beyond the bias rms {res:.4} m ({:.2} x white noise)",
                d.bias[axis],
                res / white_std
            );
            assert!(res < 0.5 * white_std, "drone {i} axis {axis}: {res}");
        }
        assert_eq!(d.est.gated_innovations(), 0);
    }
    assert!(
        (drones[0].bias - drones[1].bias).norm() > 1e-3,
        "independent seeds"
    );
}
