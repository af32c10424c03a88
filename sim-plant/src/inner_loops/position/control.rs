//! The position controller's state and step (see the parent module for the PX4 sources).

use nalgebra::{Vector2, Vector3};

use super::super::control_math::thrust_to_attitude;
use super::super::control_math::{add_if_not_nan3, constrain_xy, limit_tilt, set_zero_if_nan3};
use super::super::errors::{check_dt, ParamsError, StepError};
use super::super::filters::BlockDerivative;
use super::{PositionControlOutput, PositionControlParams, TrajectorySetpoint, PX4_ONE_G};

/// MulticopterPositionControl's bounds on dt, s.
const DT_MIN_S: f64 = 0.002;
const DT_MAX_S: f64 = 0.04;

/// PX4's position and velocity controller with its velocity-derivative filters.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionControl {
    gain_pos_p: Vector3<f64>,
    gain_vel_p: Vector3<f64>,
    gain_vel_i: Vector3<f64>,
    gain_vel_d: Vector3<f64>,
    lim_vel_horizontal: f64,
    lim_vel_up: f64,
    lim_vel_down: f64,
    lim_tilt_rad: f64,
    thr_min: f64,
    thr_max: f64,
    thr_xy_margin: f64,
    hover_throttle: f64,
    /// Velocity integral, NED, m/s^2.
    vel_int: Vector3<f64>,
    vel_deriv: [BlockDerivative; 3],
    landed: bool,
}

/// Intermediate values of one step, committed only when the step is valid.
struct Step {
    vel_sp: Vector3<f64>,
    acc_sp: Vector3<f64>,
    thr_sp: Vector3<f64>,
    vel_int: Vector3<f64>,
}

impl PositionControl {
    pub fn new(params: &PositionControlParams) -> Result<Self, ParamsError> {
        params.validate()?;
        let p = params;
        Ok(PositionControl {
            gain_pos_p: Vector3::new(p.xy_p, p.xy_p, p.z_p),
            gain_vel_p: Vector3::new(p.xy_vel_p_acc, p.xy_vel_p_acc, p.z_vel_p_acc),
            gain_vel_i: Vector3::new(p.xy_vel_i_acc, p.xy_vel_i_acc, p.z_vel_i_acc),
            gain_vel_d: Vector3::new(p.xy_vel_d_acc, p.xy_vel_d_acc, p.z_vel_d_acc),
            lim_vel_horizontal: p.xy_vel_max_m_s,
            lim_vel_up: p.z_vel_max_up_m_s,
            lim_vel_down: p.z_vel_max_dn_m_s,
            lim_tilt_rad: p.tilt_max_air_deg.to_radians(),
            thr_min: p.thr_min,
            thr_max: p.thr_max,
            thr_xy_margin: p.thr_xy_margin,
            hover_throttle: p.hover_throttle,
            vel_int: Vector3::zeros(),
            vel_deriv: std::array::from_fn(|_| BlockDerivative::new(p.veld_lp_hz)),
            landed: false,
        })
    }

    /// While landed (not yet flying) PX4 replaces the setpoint by a 100 m/s^2 downward
    /// acceleration, lowers the thrust floor to 0 and keeps the integrators at 0.
    pub fn set_landed(&mut self, landed: bool) {
        self.landed = landed;
    }

    /// Clears the velocity integral.
    pub fn reset_integral(&mut self) {
        self.vel_int = Vector3::zeros();
    }

    /// Velocity integral, NED, m/s^2.
    pub fn integral(&self) -> Vector3<f64> {
        self.vel_int
    }

    /// One step from the estimate (NED position and velocity, NaN where invalid; yaw, rad)
    /// and the trajectory setpoint. On error nothing but the derivative filters moved.
    pub fn update(
        &mut self,
        dt: f64,
        position_ned_m: &Vector3<f64>,
        velocity_ned_m_s: &Vector3<f64>,
        yaw_rad: f64,
        setpoint: &TrajectorySetpoint,
    ) -> Result<PositionControlOutput, StepError> {
        check_dt(dt)?;
        if !yaw_rad.is_finite() {
            return Err(StepError::NonFinite { name: "yaw_rad" });
        }
        let dt = dt.clamp(DT_MIN_S, DT_MAX_S);
        let mut vel_dot = Vector3::zeros();
        for i in 0..3 {
            if velocity_ned_m_s[i].is_finite() {
                vel_dot[i] = self.vel_deriv[i].update(velocity_ned_m_s[i], dt);
            } else {
                vel_dot[i] = f64::NAN;
                self.vel_deriv[i].reset();
            }
        }

        let mut sp = *setpoint;
        let mut thr_min = self.thr_min.max(1e-3);
        if self.landed {
            sp = TrajectorySetpoint::empty();
            sp.acceleration_ned_m_s2 = Vector3::new(0.0, 0.0, 100.0);
            thr_min = 1e-3;
            self.vel_int = Vector3::zeros();
        }
        input_valid(&sp, position_ned_m, velocity_ned_m_s, &vel_dot)?;

        let vel_sp = self.position_control(&sp, position_ned_m);
        let step = self.velocity_control(
            dt,
            vel_sp,
            sp.acceleration_ned_m_s2,
            velocity_ned_m_s,
            &vel_dot,
            thr_min,
        );
        let finite = |v: &Vector3<f64>| v.iter().all(|x| x.is_finite());
        if !(finite(&step.acc_sp) && finite(&step.thr_sp)) {
            return Err(StepError::InvalidSetpoint {
                reason: "no finite acceleration (a controlled axis has no valid estimate)",
            });
        }
        self.vel_int = step.vel_int;

        let yaw_sp = if sp.yaw_rad.is_finite() {
            sp.yaw_rad
        } else {
            yaw_rad
        };
        let yaw_rate = if sp.yaw_rate_rad_s.is_finite() {
            sp.yaw_rate_rad_s
        } else {
            0.0
        };
        let (attitude_sp, thrust) = thrust_to_attitude(&step.thr_sp, yaw_sp);
        Ok(PositionControlOutput {
            attitude_sp,
            thrust,
            yaw_rate_ff_rad_s: yaw_rate,
            thrust_ned: step.thr_sp,
            acceleration_sp_ned_m_s2: step.acc_sp,
            velocity_sp_ned_m_s: step.vel_sp,
        })
    }

    /// PX4's `_positionControl`: velocity setpoint, NED (NaN where not controlled).
    fn position_control(&self, sp: &TrajectorySetpoint, pos: &Vector3<f64>) -> Vector3<f64> {
        let mut vel_sp_position = (sp.position_ned_m - pos).component_mul(&self.gain_pos_p);
        let mut vel_sp = sp.velocity_ned_m_s;
        add_if_not_nan3(&mut vel_sp, &vel_sp_position);
        set_zero_if_nan3(&mut vel_sp_position);
        let ff = vel_sp - vel_sp_position;
        let xy = constrain_xy(
            &vel_sp_position.xy(),
            &Vector2::new(ff.x, ff.y),
            self.lim_vel_horizontal,
        );
        vel_sp.x = xy.x;
        vel_sp.y = xy.y;
        // NaN stays NaN through clamp: an uncontrolled z velocity is not invented.
        vel_sp.z = vel_sp.z.clamp(-self.lim_vel_up, self.lim_vel_down);
        vel_sp
    }

    /// PX4's `_velocityControl` with `_accelerationControl`.
    fn velocity_control(
        &self,
        dt: f64,
        vel_sp: Vector3<f64>,
        acc_ff: Vector3<f64>,
        vel: &Vector3<f64>,
        vel_dot: &Vector3<f64>,
        thr_min: f64,
    ) -> Step {
        let mut vel_error = vel_sp - vel;
        let acc_sp_velocity = vel_error.component_mul(&self.gain_vel_p) + self.vel_int
            - vel_dot.component_mul(&self.gain_vel_d);
        let mut acc_sp = acc_ff;
        add_if_not_nan3(&mut acc_sp, &acc_sp_velocity);
        let mut thr_sp = self.acceleration_control(&acc_sp, thr_min);

        // Vertical anti-windup against the thrust limits (NED: thrust z is negative).
        if (thr_sp.z >= -thr_min && vel_error.z >= 0.0)
            || (thr_sp.z <= -self.thr_max && vel_error.z <= 0.0)
        {
            vel_error.z = 0.0;
        }
        // Vertical priority, keeping a horizontal margin.
        let thr_xy = Vector2::new(thr_sp.x, thr_sp.y);
        let thr_xy_norm = thr_xy.norm();
        let thr_max_sq = self.thr_max * self.thr_max;
        let allocated_xy = thr_xy_norm.min(self.thr_xy_margin);
        thr_sp.z = thr_sp
            .z
            .max(-(thr_max_sq - allocated_xy * allocated_xy).sqrt());
        let thr_max_xy_sq = thr_max_sq - thr_sp.z * thr_sp.z;
        let thr_max_xy = if thr_max_xy_sq > 0.0 {
            thr_max_xy_sq.sqrt()
        } else {
            0.0
        };
        if thr_xy_norm > thr_max_xy {
            let limited = thr_xy / thr_xy_norm * thr_max_xy;
            thr_sp.x = limited.x;
            thr_sp.y = limited.y;
        }

        // Horizontal tracking anti-windup (Rundqwist): feed back what the limits took away.
        let acc_xy_produced = Vector2::new(thr_sp.x, thr_sp.y) * (PX4_ONE_G / self.hover_throttle);
        let arw_gain = 2.0 / self.gain_vel_p.x;
        let acc_xy = Vector2::new(acc_sp.x, acc_sp.y);
        let acc_limited_xy = if acc_xy.norm_squared() > acc_xy_produced.norm_squared() {
            acc_xy_produced
        } else {
            acc_xy
        };
        vel_error.x -= arw_gain * (acc_xy.x - acc_limited_xy.x);
        vel_error.y -= arw_gain * (acc_xy.y - acc_limited_xy.y);
        set_zero_if_nan3(&mut vel_error);
        let mut vel_int = self.vel_int + vel_error.component_mul(&self.gain_vel_i) * dt;
        vel_int.z = vel_int.z.abs().min(PX4_ONE_G).copysign(vel_int.z);
        Step {
            vel_sp,
            acc_sp,
            thr_sp,
            vel_int,
        }
    }

    /// PX4's `_accelerationControl`: thrust vector, normalized, NED.
    fn acceleration_control(&self, acc_sp: &Vector3<f64>, thr_min: f64) -> Vector3<f64> {
        let up = Vector3::z();
        let mut body_z = Vector3::new(-acc_sp.x, -acc_sp.y, PX4_ONE_G).normalize();
        limit_tilt(&mut body_z, &up, self.lim_tilt_rad);
        let mut collective = acc_sp.z * (self.hover_throttle / PX4_ONE_G) - self.hover_throttle;
        collective /= up.dot(&body_z);
        collective = collective.min(-thr_min);
        body_z * collective
    }
}

/// PX4's `_inputValid`.
fn input_valid(
    sp: &TrajectorySetpoint,
    pos: &Vector3<f64>,
    vel: &Vector3<f64>,
    vel_dot: &Vector3<f64>,
) -> Result<(), StepError> {
    let (p, v, a) = (
        &sp.position_ned_m,
        &sp.velocity_ned_m_s,
        &sp.acceleration_ned_m_s2,
    );
    let bad = |reason| Err(StepError::InvalidSetpoint { reason });
    for i in 0..3 {
        if !(p[i].is_finite() || v[i].is_finite() || a[i].is_finite()) {
            return bad("an axis has no position, velocity or acceleration setpoint");
        }
    }
    if p.x.is_finite() != p.y.is_finite()
        || v.x.is_finite() != v.y.is_finite()
        || a.x.is_finite() != a.y.is_finite()
    {
        return bad("x and y setpoints must come in pairs");
    }
    for i in 0..3 {
        if p[i].is_finite() && !pos[i].is_finite() {
            return bad("position setpoint without a valid position estimate");
        }
        if v[i].is_finite() && !(vel[i].is_finite() && vel_dot[i].is_finite()) {
            return bad("velocity setpoint without a valid velocity estimate");
        }
    }
    Ok(())
}
