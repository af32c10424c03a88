//! How well each force source matches the plant's true anchor force (the study's
//! "force-estimate RMSE against truth"). Pure, cheap: three running sums per drone.
//!
//! Definitions (what `summary.json` reports under `drones[k].force_rmse`):
//! - Truth: the cable's true pull on the drone at its anchor (`PlantTruth` /
//!   TENSION_TRUTH), the newest one when a sample arrives (fast mode: at most 2 ms old;
//!   the error therefore includes each source's own delay, as the controller sees it).
//! - `sensor_frd_n`, `estimator_frd_n`: every TENSION / TENSION_ESTIMATE sample's
//!   `force_body_n` against the truth, body FRD (the sources' own frame: no attitude enters).
//! - `used_ned_n`: at every controller step that used a fresh tension sample, the pull the
//!   law acted on (−T_f, the filtered force, NED) against the true pull rotated by the true
//!   attitude (R · anchor force, NED, from the newest PlantTruth).
//! - Only while the drone is airborne: its true height more than [`AIRBORNE_HEIGHT_M`] above
//!   where it stood at the first truth sample (so the estimator's ground-reaction "force"
//!   before lift-off is not counted, but everything in flight is).
//! - Per axis and the norm: sqrt(mean(e_x²)), ..., sqrt(mean(|e|²)), N.

use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;
use shared_types::{AttitudeSetpoint, PlantTruth, TensionSample};

/// A drone counts as airborne this far above its first truth position, m.
pub const AIRBORNE_HEIGHT_M: f64 = 0.1;

/// The measured force sources compared with the truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceSource {
    /// The force sensor's TENSION.
    Sensor,
    /// The estimator's TENSION_ESTIMATE.
    Estimator,
}

/// RMSE per axis and of the norm, N, over `samples` samples.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct AxisRmse {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub norm: f64,
    pub samples: u64,
}

/// One drone's force RMSEs against the truth (None: no sample while airborne).
#[derive(Debug, Clone, Copy, Serialize, Default, PartialEq)]
pub struct ForceRmse {
    /// The sensor's force, body FRD.
    pub sensor_frd_n: Option<AxisRmse>,
    /// The estimator's force, body FRD.
    pub estimator_frd_n: Option<AxisRmse>,
    /// The pull the controller acted on (−T_f), NED.
    pub used_ned_n: Option<AxisRmse>,
}

#[derive(Debug, Clone, Copy, Default)]
struct Acc {
    sq: Vector3<f64>,
    n: u64,
}

impl Acc {
    fn add(&mut self, e: &Vector3<f64>) {
        if e.iter().all(|v| v.is_finite()) {
            self.sq += e.component_mul(e);
            self.n += 1;
        }
    }

    fn rmse(&self) -> Option<AxisRmse> {
        (self.n > 0).then(|| {
            let m = self.sq / self.n as f64;
            AxisRmse {
                x: m.x.sqrt(),
                y: m.y.sqrt(),
                z: m.z.sqrt(),
                norm: m.sum().sqrt(),
                samples: self.n,
            }
        })
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct DroneForces {
    start_z_m: Option<f64>,
    airborne: bool,
    /// Newest true pull, body FRD, and the true attitude of the newest PlantTruth.
    truth_frd_n: Option<Vector3<f64>>,
    attitude: Option<UnitQuaternion<f64>>,
    /// Sensor, estimator, used.
    acc: [Acc; 3],
}

/// The running sums of both drones.
#[derive(Debug, Clone, Default)]
pub struct ForceErrors {
    drones: [DroneForces; 2],
}

fn quat(wxyz: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        wxyz[0], wxyz[1], wxyz[2], wxyz[3],
    ))
}

impl ForceErrors {
    /// A ground-truth sample: airborne state, attitude and (until TENSION_TRUTH samples
    /// come) the true force.
    pub fn on_truth(&mut self, t: &PlantTruth) {
        for (d, truth) in self.drones.iter_mut().zip(&t.drones) {
            let z = truth.body.position_ned_m[2];
            let start = *d.start_z_m.get_or_insert(z);
            d.airborne = z < start - AIRBORNE_HEIGHT_M;
            d.attitude = Some(quat(truth.body.attitude_wxyz));
            d.truth_frd_n = Some(Vector3::from(truth.anchor_force_frd_n));
        }
    }

    /// A TENSION_TRUTH sample of drone `k` (fresher than PlantTruth's).
    pub fn on_truth_tension(&mut self, k: usize, s: &TensionSample) {
        self.drones[k].truth_frd_n = Some(Vector3::from(s.force_body_n));
    }

    /// A sensor or estimator sample of drone `k`.
    pub fn on_sample(&mut self, k: usize, source: ForceSource, s: &TensionSample) {
        let d = &mut self.drones[k];
        let (true, Some(truth)) = (d.airborne, d.truth_frd_n) else {
            return;
        };
        let i = match source {
            ForceSource::Sensor => 0,
            ForceSource::Estimator => 1,
        };
        d.acc[i].add(&(Vector3::from(s.force_body_n) - truth));
    }

    /// A controller output of drone `k`: counted if a fresh tension sample entered it.
    pub fn on_setpoint(&mut self, k: usize, sp: &AttitudeSetpoint) {
        let d = &mut self.drones[k];
        let (true, Some(truth), Some(q)) = (d.airborne, d.truth_frd_n, d.attitude) else {
            return;
        };
        if sp.tension_origin_ns == 0 {
            return;
        }
        let used_pull_ned = -Vector3::from(sp.tension_filtered_ned_n);
        d.acc[2].add(&(used_pull_ned - q * truth));
    }

    pub fn rmse(&self, k: usize) -> ForceRmse {
        let a = &self.drones[k].acc;
        ForceRmse {
            sensor_frd_n: a[0].rmse(),
            estimator_frd_n: a[1].rmse(),
            used_ned_n: a[2].rmse(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth_at(z: f64, pull_frd: [f64; 3]) -> PlantTruth {
        let mut t = PlantTruth::default();
        for d in &mut t.drones {
            d.body.position_ned_m = [0.0, 0.0, z];
            d.body.attitude_wxyz = [1.0, 0.0, 0.0, 0.0];
            d.anchor_force_frd_n = pull_frd;
        }
        t
    }

    fn sample(frd: [f64; 3]) -> TensionSample {
        TensionSample {
            force_body_n: frd,
            ..Default::default()
        }
    }

    #[test]
    fn counts_only_airborne_and_gives_per_axis_and_norm() {
        let mut f = ForceErrors::default();
        f.on_truth(&truth_at(0.0, [0.0, 0.0, 5.0]));
        // On the ground: not counted.
        f.on_sample(0, ForceSource::Estimator, &sample([0.0, 0.0, -20.0]));
        assert_eq!(f.rmse(0).estimator_frd_n, None);
        f.on_truth(&truth_at(-1.0, [0.0, 0.0, 5.0]));
        f.on_truth_tension(0, &sample([0.0, 0.0, 6.0]));
        // Errors (3, 0, -2) and (-3, 0, 2): RMSE x 3, z 2, norm sqrt(13).
        f.on_sample(0, ForceSource::Sensor, &sample([3.0, 0.0, 4.0]));
        f.on_sample(0, ForceSource::Sensor, &sample([-3.0, 0.0, 8.0]));
        let r = f.rmse(0).sensor_frd_n.unwrap();
        assert_eq!((r.x, r.y, r.z, r.samples), (3.0, 0.0, 2.0, 2));
        assert!((r.norm - 13f64.sqrt()).abs() < 1e-12);
        // Used force: −T_f against the true pull (level: NED = FRD); without a fresh tension
        // sample the step is not counted.
        let mut sp = AttitudeSetpoint {
            tension_filtered_ned_n: [0.0, 0.0, -5.0],
            ..Default::default()
        };
        f.on_setpoint(0, &sp);
        assert_eq!(f.rmse(0).used_ned_n, None);
        sp.tension_origin_ns = 1;
        f.on_setpoint(0, &sp);
        assert_eq!(f.rmse(0).used_ned_n.unwrap().z, 1.0);
        assert_eq!(f.rmse(1), ForceRmse::default());
    }
}
