//! PX4's multicopter control allocation (control_allocator, sequential desaturation).
//!
//! Followed: PX4-Autopilot src/modules/control_allocator/
//! - ActuatorEffectiveness/ActuatorEffectivenessRotors.cpp: per rotor, thrust `ct axis` and
//!   moment `ct (p x axis) - ct km axis` with axis = (0, 0, -1) (up) and km > 0 for CCW.
//! - ControlAllocation/ControlAllocationPseudoInverse.cpp: mix = pinv(B); roll and pitch
//!   columns scaled by `sqrt(|col|^2 / (n_nonzero / 2))` (the larger of the two for both),
//!   yaw by its largest element, thrust by the mean norm of the rotors' thrust rows; entries
//!   below 1e-3 set to 0. For a symmetric quad X this gives roll/pitch entries +-1/sqrt(2),
//!   yaw +-1 and thrust -1 whatever ct and km are.
//! - ControlAllocation/ControlAllocationSequentialDesaturation.cpp: MC_AIRMODE 0 mixes
//!   roll, pitch and thrust, reduces thrust only, then reduces roll, then pitch, then adds
//!   yaw (allowed 15 % over the top) and reduces yaw, then thrust only. Airmode 1 and 2 are
//!   ported too. Each desaturation step is PX4's: gain to unsaturate, then half of the
//!   remaining gain; actuators with |desaturation vector| < 0.2 are not used.
//! - ControlAllocation.cpp and ControlAllocator.cpp: clip to [0, 1]; allocated control
//!   `(B u) .* scale`; per torque axis, saturation flags from the sign of the unallocated
//!   part when |unallocated torque|^2 >= 1e-6 (MulticopterRateControl reads them back).
//!
//! Inputs are normalized torque (body FRD) and collective thrust t in [0, 1] (PX4's thrust
//! setpoint z = -t); output per motor normalized thrust in [0, 1], in PX4 motor order.

use nalgebra::{Matrix4, SMatrix, Vector3, Vector4};
use serde::Deserialize;

use super::errors::{check_finite3, check_range, ParamsError, StepError};

/// One rotor of the effectiveness model.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotorGeometry {
    /// Rotor position in body FRD, m (CA_ROTORn_PX/PY/PZ).
    pub position_frd_m: [f64; 3],
    /// Yaw moment per thrust, m, signed: > 0 for a CCW rotor (reaction torque +km T about
    /// body z), < 0 for CW (CA_ROTORn_KM).
    pub moment_ratio_m: f64,
}

/// PX4's MC_AIRMODE.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Airmode {
    /// 0: thrust is never raised to unsaturate (default).
    Disabled,
    /// 1: roll and pitch may raise thrust.
    RollPitch,
    /// 2: roll, pitch and yaw may raise thrust.
    RollPitchYaw,
}

/// Allocation parameters; defaults are the X500 geometry of the plant (MODEL.md).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AllocationParams {
    /// Rotors in PX4 motor order. Default quad X: motor 1 (+0.174, +0.174) CCW, motor 2
    /// (-0.174, -0.174) CCW, motor 3 (+0.174, -0.174) CW, motor 4 (-0.174, +0.174) CW,
    /// km +-0.016 m.
    pub rotors: [RotorGeometry; 4],
    /// MC_AIRMODE. Default disabled.
    pub airmode: Airmode,
}

impl Default for AllocationParams {
    fn default() -> Self {
        let rotor = |x: f64, y: f64, km: f64| RotorGeometry {
            position_frd_m: [x, y, 0.0],
            moment_ratio_m: km,
        };
        let (a, km) = (0.174, 0.016);
        AllocationParams {
            rotors: [
                rotor(a, a, km),
                rotor(-a, -a, km),
                rotor(a, -a, -km),
                rotor(-a, a, -km),
            ],
            airmode: Airmode::Disabled,
        }
    }
}

impl AllocationParams {
    /// Positions and moment ratios finite; the geometry must control roll, pitch, yaw and
    /// thrust independently (checked in [`ControlAllocation::new`]).
    pub fn validate(&self) -> Result<(), ParamsError> {
        for r in &self.rotors {
            for p in r.position_frd_m {
                check_range("allocation.rotors.position_frd_m", p, -10.0, 10.0)?;
            }
            check_range(
                "allocation.rotors.moment_ratio_m",
                r.moment_ratio_m,
                -1.0,
                1.0,
            )?;
        }
        Ok(())
    }
}

/// One allocation result.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AllocationOutput {
    /// Per-motor normalized thrust in [0, 1], PX4 motor order.
    pub motor_thrust: [f64; 4],
    /// Torque axes (roll, pitch, yaw) whose positive request was not fully met.
    pub saturation_positive: [bool; 3],
    /// Torque axes whose negative request was not fully met.
    pub saturation_negative: [bool; 3],
    /// Requested minus allocated normalized torque, body FRD.
    pub unallocated_torque: Vector3<f64>,
    /// Allocated collective thrust, normalized (the request was t).
    pub allocated_thrust: f64,
}

/// Axis indices of the reduced control vector (PX4's THRUST_X/Y are identically zero for
/// upward rotors and are dropped after the pseudo-inverse).
const ROLL: usize = 0;
const PITCH: usize = 1;
const YAW: usize = 2;
const THRUST_Z: usize = 3;

/// Sequential-desaturation allocator for four rotors.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlAllocation {
    /// Normalized mix, rows motors, columns roll, pitch, yaw, thrust z.
    mix: Matrix4<f64>,
    /// Effectiveness scaled to normalized control units: rows roll, pitch, yaw, thrust z.
    effectiveness: Matrix4<f64>,
    airmode: Airmode,
}

impl ControlAllocation {
    pub fn new(params: &AllocationParams) -> Result<Self, ParamsError> {
        params.validate()?;
        // Effectiveness, rows roll, pitch, yaw, Fx, Fy, Fz. PX4 scales by CA_ROTOR_CT; the
        // normalization cancels it, so ct = 1.
        let mut b = SMatrix::<f64, 6, 4>::zeros();
        let axis = Vector3::new(0.0, 0.0, -1.0);
        for (i, r) in params.rotors.iter().enumerate() {
            let p = Vector3::from(r.position_frd_m);
            let moment = p.cross(&axis) - r.moment_ratio_m * axis;
            for j in 0..3 {
                b[(j, i)] = moment[j];
                b[(j + 3, i)] = axis[j];
            }
        }
        let singular = || ParamsError {
            key: "allocation.rotors",
            msg: "geometry cannot control roll, pitch, yaw and thrust independently".into(),
        };
        let mut mix6 = b.pseudo_inverse(1e-9).map_err(|_| singular())?;
        let scale = normalization_scale(&mix6);
        for (col, s) in scale.iter().enumerate() {
            if *s > f64::EPSILON {
                let c = mix6.column(col) / *s;
                mix6.set_column(col, &c);
            }
        }
        mix6.apply(|m| {
            if m.abs() < 1e-3 {
                *m = 0.0;
            }
        });
        let cols = [ROLL, PITCH, YAW, 5];
        let mix = Matrix4::from_fn(|i, j| mix6[(i, cols[j])]);
        let effectiveness = Matrix4::from_fn(|i, j| b[(cols[i], j)] * scale[cols[i]]);
        // The normalized mix must invert the normalized effectiveness on these four axes.
        if (effectiveness * mix - Matrix4::identity()).abs().max() > 1e-6 {
            return Err(singular());
        }
        Ok(ControlAllocation {
            mix,
            effectiveness,
            airmode: params.airmode,
        })
    }

    /// The normalized mix, rows motors, columns (roll, pitch, yaw, thrust z).
    pub fn mix(&self) -> &Matrix4<f64> {
        &self.mix
    }

    /// Allocates normalized torque (body FRD) and collective thrust `thrust` in [0, 1].
    pub fn update(
        &mut self,
        torque_frd: &Vector3<f64>,
        thrust: f64,
    ) -> Result<AllocationOutput, StepError> {
        check_finite3("torque_frd", torque_frd)?;
        if !thrust.is_finite() {
            return Err(StepError::NonFinite { name: "thrust" });
        }
        let control = Vector4::new(torque_frd.x, torque_frd.y, torque_frd.z, -thrust);
        let mut u = match self.airmode {
            Airmode::Disabled => {
                let mut u = self.mix_without_yaw(&control);
                desaturate(&mut u, &self.col(THRUST_Z), true, 1.0);
                desaturate(&mut u, &self.col(ROLL), false, 1.0);
                desaturate(&mut u, &self.col(PITCH), false, 1.0);
                self.mix_yaw(&mut u, &control);
                u
            }
            Airmode::RollPitch => {
                let mut u = self.mix_without_yaw(&control);
                desaturate(&mut u, &self.col(THRUST_Z), false, 1.0);
                self.mix_yaw(&mut u, &control);
                u
            }
            Airmode::RollPitchYaw => {
                let mut u = self.mix * control;
                desaturate(&mut u, &self.col(THRUST_Z), false, 1.0);
                desaturate(&mut u, &self.col(YAW), false, 1.0);
                u
            }
        };
        u.apply(|x| *x = x.clamp(0.0, 1.0));

        let allocated = self.effectiveness * u;
        let unallocated = Vector3::new(
            control.x - allocated.x,
            control.y - allocated.y,
            control.z - allocated.z,
        );
        let mut out = AllocationOutput {
            motor_thrust: [u.x, u.y, u.z, u.w],
            unallocated_torque: unallocated,
            allocated_thrust: -allocated.w,
            ..AllocationOutput::default()
        };
        if unallocated.norm_squared() >= 1e-6 {
            // PX4 compares against FLT_EPSILON; so does this, to ignore rounding.
            let eps = f32::EPSILON as f64;
            for i in 0..3 {
                out.saturation_positive[i] = unallocated[i] > eps;
                out.saturation_negative[i] = unallocated[i] < -eps;
            }
        }
        Ok(out)
    }

    fn col(&self, axis: usize) -> Vector4<f64> {
        self.mix.column(axis).into_owned()
    }

    fn mix_without_yaw(&self, control: &Vector4<f64>) -> Vector4<f64> {
        self.col(ROLL) * control[ROLL]
            + self.col(PITCH) * control[PITCH]
            + self.col(THRUST_Z) * control[THRUST_Z]
    }

    /// PX4's `mixYaw`: add yaw, unsaturate with yaw allowing 15 % headroom at the top, then
    /// reduce thrust only.
    fn mix_yaw(&self, u: &mut Vector4<f64>, control: &Vector4<f64>) {
        *u += self.col(YAW) * control[YAW];
        desaturate(u, &self.col(YAW), false, 1.15);
        desaturate(u, &self.col(THRUST_Z), true, 1.0);
    }
}

/// PX4's `updateControlAllocationMatrixScale` for a 6-axis mix (rows actuators).
fn normalization_scale(mix: &SMatrix<f64, 4, 6>) -> [f64; 6] {
    let nonzero = |col: usize| (0..4).filter(|&i| mix[(i, col)].abs() > 1e-3).count();
    let rp_scale = |col: usize| {
        let n = nonzero(col);
        if n > 0 {
            (mix.column(col).norm_squared() / (n as f64 / 2.0)).sqrt()
        } else {
            1.0
        }
    };
    let roll_pitch = rp_scale(ROLL).max(rp_scale(PITCH));
    let yaw = mix.column(YAW).max();
    let mut norm_sum = 0.0;
    let mut n_thrust = 0;
    for i in 0..4 {
        let n = mix.fixed_view::<1, 3>(i, 3).norm();
        norm_sum += n;
        if n > f64::EPSILON {
            n_thrust += 1;
        }
    }
    let thrust = if n_thrust > 0 {
        norm_sum / n_thrust as f64
    } else {
        1.0
    };
    [roll_pitch, roll_pitch, yaw, thrust, thrust, thrust]
}

/// PX4's `computeDesaturationGain` for actuator limits [0, `max`].
fn desaturation_gain(vector: &Vector4<f64>, u: &Vector4<f64>, max: f64) -> f64 {
    let (mut k_min, mut k_max) = (0.0f64, 0.0f64);
    for i in 0..4 {
        if vector[i].abs() < 0.2 {
            continue;
        }
        for limit in [0.0, max] {
            let outside = if limit == 0.0 { u[i] < 0.0 } else { u[i] > max };
            if outside {
                let k = (limit - u[i]) / vector[i];
                k_min = k_min.min(k);
                k_max = k_max.max(k);
            }
        }
    }
    k_min + k_max
}

/// PX4's `desaturateActuators`: full gain, then half of what is left.
fn desaturate(u: &mut Vector4<f64>, vector: &Vector4<f64>, increase_only: bool, max: f64) {
    let gain = desaturation_gain(vector, u, max);
    if increase_only && gain < 0.0 {
        return;
    }
    *u += vector * gain;
    let gain = 0.5 * desaturation_gain(vector, u, max);
    *u += vector * gain;
}

#[cfg(test)]
#[path = "allocation_tests.rs"]
mod tests;
