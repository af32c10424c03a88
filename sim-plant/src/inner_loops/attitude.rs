//! PX4's multicopter attitude controller (mc_att_control, `AttitudeControl::update`).
//!
//! Followed: PX4-Autopilot src/modules/mc_att_control/AttitudeControl/AttitudeControl.cpp.
//! The stored copy of that file is a newer revision with a reference model (MC_REF_FF); its
//! own comment says that with the model off it is "an exact legacy baseline", and that
//! legacy law is what v1.16 runs and what is ported here:
//!
//! 1. Tilt first: `qd_red` is the shortest rotation taking the current body z axis to the
//!    desired one (world frame), applied to the current attitude.
//! 2. The remaining yaw rotation `qd_dyaw = qd_red^-1 qd` is scaled by MC_YAW_WEIGHT and
//!    recombined: `qd = qd_red * (cos(w acos(dyaw_w)), 0, 0, sin(w asin(dyaw_z)))`.
//! 3. Error quaternion `qe = q^-1 qd`, error vector `2 imag(canonical(qe))` (body FRD),
//!    rate setpoint = error * (MC_ROLL_P, MC_PITCH_P, MC_YAW_P / MC_YAW_WEIGHT): the yaw
//!    gain is divided by the weight so that a pure yaw error still sees MC_YAW_P.
//! 4. Yaw-rate feed-forward along the world z axis expressed in body FRD, then per-axis
//!    limits MC_ROLLRATE_MAX, MC_PITCHRATE_MAX, MC_YAWRATE_MAX.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::Deserialize;

use super::errors::{check_finite_quat, check_positive, check_range, ParamsError, StepError};

/// Attitude controller parameters; defaults are PX4 v1.16's.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AttitudeControlParams {
    /// MC_ROLL_P, 1/s. Default 6.5.
    pub roll_p: f64,
    /// MC_PITCH_P, 1/s. Default 6.5.
    pub pitch_p: f64,
    /// MC_YAW_P, 1/s. Default 2.8.
    pub yaw_p: f64,
    /// MC_YAW_WEIGHT, 0..1: how much of the yaw error is corrected together with the tilt.
    /// Default 0.4.
    pub yaw_weight: f64,
    /// MC_ROLLRATE_MAX, deg/s. Default 220.
    pub rollrate_max_deg_s: f64,
    /// MC_PITCHRATE_MAX, deg/s. Default 220.
    pub pitchrate_max_deg_s: f64,
    /// MC_YAWRATE_MAX, deg/s. Default 200.
    pub yawrate_max_deg_s: f64,
}

impl Default for AttitudeControlParams {
    fn default() -> Self {
        AttitudeControlParams {
            roll_p: 6.5,
            pitch_p: 6.5,
            yaw_p: 2.8,
            yaw_weight: 0.4,
            rollrate_max_deg_s: 220.0,
            pitchrate_max_deg_s: 220.0,
            yawrate_max_deg_s: 200.0,
        }
    }
}

impl AttitudeControlParams {
    /// Gains and limits finite and positive, yaw weight in [0, 1].
    pub fn validate(&self) -> Result<(), ParamsError> {
        check_positive("attitude.roll_p", self.roll_p)?;
        check_positive("attitude.pitch_p", self.pitch_p)?;
        check_positive("attitude.yaw_p", self.yaw_p)?;
        check_range("attitude.yaw_weight", self.yaw_weight, 0.0, 1.0)?;
        check_positive("attitude.rollrate_max_deg_s", self.rollrate_max_deg_s)?;
        check_positive("attitude.pitchrate_max_deg_s", self.pitchrate_max_deg_s)?;
        check_positive("attitude.yawrate_max_deg_s", self.yawrate_max_deg_s)
    }
}

/// The attitude P controller. Stateless between steps.
#[derive(Debug, Clone, PartialEq)]
pub struct AttitudeControl {
    /// Per-axis P gain, body FRD, with the yaw gain already divided by the yaw weight.
    proportional_gain: Vector3<f64>,
    yaw_weight: f64,
    /// Per-axis rate limit, body FRD, rad/s.
    rate_limit_rad_s: Vector3<f64>,
}

impl AttitudeControl {
    pub fn new(params: &AttitudeControlParams) -> Result<Self, ParamsError> {
        params.validate()?;
        let yaw_weight = params.yaw_weight;
        let mut gain = Vector3::new(params.roll_p, params.pitch_p, params.yaw_p);
        if yaw_weight > 1e-4 {
            gain.z /= yaw_weight;
        }
        Ok(AttitudeControl {
            proportional_gain: gain,
            yaw_weight,
            rate_limit_rad_s: Vector3::new(
                params.rollrate_max_deg_s,
                params.pitchrate_max_deg_s,
                params.yawrate_max_deg_s,
            )
            .map(f64::to_radians),
        })
    }

    /// Body-rate setpoint (FRD, rad/s) that turns `attitude` towards `attitude_sp` (both
    /// body FRD -> NED). `yaw_rate_ff_rad_s` is a yaw-rate feed-forward about the world
    /// (NED) z axis; NaN means none, as in PX4's `yaw_sp_move_rate`.
    pub fn update(
        &self,
        attitude: &UnitQuaternion<f64>,
        attitude_sp: &UnitQuaternion<f64>,
        yaw_rate_ff_rad_s: f64,
    ) -> Result<Vector3<f64>, StepError> {
        check_finite_quat("attitude", attitude)?;
        check_finite_quat("attitude_sp", attitude_sp)?;
        let q = attitude.quaternion();
        let qd_full = attitude_sp.quaternion();

        // Reduced desired attitude: only the tilt, yaw left as it is.
        let e_z = attitude * Vector3::z();
        let e_z_d = attitude_sp * Vector3::z();
        let mut qd_red = quaternion_between(&e_z, &e_z_d);
        if qd_red.i.abs() > 1.0 - 1e-5 || qd_red.j.abs() > 1.0 - 1e-5 {
            // Body z exactly opposite the desired one: full attitude control is fine there.
            qd_red = *qd_full;
        } else {
            qd_red *= q;
        }

        // The yaw still missing after the tilt, scaled by the yaw weight.
        let mut qd_dyaw = canonical(&(qd_red.conjugate() * qd_full));
        qd_dyaw.w = qd_dyaw.w.clamp(-1.0, 1.0);
        qd_dyaw.k = qd_dyaw.k.clamp(-1.0, 1.0);
        let w = self.yaw_weight;
        let yaw_part = Quaternion::new(
            (w * qd_dyaw.w.acos()).cos(),
            0.0,
            0.0,
            (w * qd_dyaw.k.asin()).sin(),
        );
        let qd = qd_red * yaw_part;

        // Error quaternion from q to qd; sin(alpha/2)-scaled axis as the error.
        let qe = canonical(&(q.conjugate() * qd));
        let eq = 2.0 * qe.imag();
        let mut rate_sp = eq.component_mul(&self.proportional_gain);

        if yaw_rate_ff_rad_s.is_finite() {
            // World z axis in body FRD, times the commanded yaw rate.
            rate_sp += (attitude.inverse() * Vector3::z()) * yaw_rate_ff_rad_s;
        }
        for i in 0..3 {
            let lim = self.rate_limit_rad_s[i];
            rate_sp[i] = rate_sp[i].clamp(-lim, lim);
        }
        Ok(rate_sp)
    }
}

/// PX4's `Quaternion(src, dst)`: the shortest rotation taking `src` to `dst`, with PX4's
/// choice of axis for the 180 degree case.
pub(crate) fn quaternion_between(src: &Vector3<f64>, dst: &Vector3<f64>) -> Quaternion<f64> {
    const EPS: f64 = 1e-5;
    let mut cr = src.cross(dst);
    let dot = src.dot(dst);
    let w;
    if cr.norm() < EPS && dot < 0.0 {
        let a = src.abs();
        let axis = if a.x < a.y {
            if a.x < a.z {
                Vector3::x()
            } else {
                Vector3::z()
            }
        } else if a.y < a.z {
            Vector3::y()
        } else {
            Vector3::z()
        };
        w = 0.0;
        cr = src.cross(&axis);
    } else {
        w = dot + (src.norm_squared() * dst.norm_squared()).sqrt();
    }
    let q = Quaternion::new(w, cr.x, cr.y, cr.z);
    let n = q.norm();
    if n > 0.0 {
        q / n
    } else {
        Quaternion::identity()
    }
}

/// PX4's `canonical()`: the sign of the first non-zero element (w, x, y, z) made positive.
pub(crate) fn canonical(q: &Quaternion<f64>) -> Quaternion<f64> {
    for v in [q.w, q.i, q.j, q.k] {
        if v.abs() > f64::EPSILON {
            return if v < 0.0 { -q } else { *q };
        }
    }
    *q
}

#[cfg(test)]
#[path = "attitude_tests.rs"]
mod tests;
