//! The two dynamic blocks of the cascade: the tension shift of the position setpoint (paper
//! eq. 2) and the velocity PID (eq. 3). Plain `Copy` state so a step can work on a copy and
//! commit it only when everything came out finite.

use nalgebra::Vector3;

use crate::filters::LowPass3;

fn clamp_each(v: &Vector3<f64>, bound: &Vector3<f64>) -> Vector3<f64> {
    v.zip_map(bound, |x, b| x.clamp(-b, b))
}

/// How the tension loop ran in a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShiftMode {
    /// Tension fresh and the loop enabled: P + I − D.
    Active,
    /// Loop enabled but no fresh tension: P and D dropped, the integral frozen (the setpoint
    /// keeps the integral's shift instead of jumping back to ξ̄_d).
    Frozen,
    /// Loop disabled by the mission: the shift decays to zero.
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShiftGains {
    pub k_tp: Vector3<f64>,
    pub k_ti: Vector3<f64>,
    pub k_td: Vector3<f64>,
    /// Bound per axis of the integral contribution and of the total shift, m.
    pub max_shift_m: Vector3<f64>,
    pub decay_tau_s: f64,
    /// e_T is not integrated while |T_f| < slack_ratio · |T_d| (slack cable).
    pub slack_ratio: f64,
}

/// ξ_d − ξ̄_d = K_TP e_T + K_TI ∫e_T dt − K_TD dT_f/dt, e_T = T_d − T_f (NED).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TensionShift {
    /// T_f: the measured T (force the drone exerts on the cable), NED, N.
    pub filter: LowPass3,
    /// K_TI ∫e_T dt (or, while off, the decaying shift), m.
    pub integral_m: Vector3<f64>,
    /// The shift applied in the last step, m.
    pub shift_m: Vector3<f64>,
    pub mode: ShiftMode,
}

impl TensionShift {
    pub fn new(cutoff_hz: f64) -> Self {
        Self {
            filter: LowPass3::new(cutoff_hz),
            integral_m: Vector3::zeros(),
            shift_m: Vector3::zeros(),
            mode: ShiftMode::Off,
        }
    }

    /// Feeds the newest fresh measurement (`None`: none this step; the next one re-seeds the
    /// filter so a gap gives no derivative kick).
    pub fn measure(&mut self, tension_ned_n: Option<&Vector3<f64>>, dt_s: f64) {
        match tension_ned_n {
            Some(t) => {
                self.filter.update(t, dt_s);
            }
            None => self.filter.unprime(),
        }
    }

    /// One step of the shift. `integrate` false holds the integral (stale odometry).
    pub fn step(
        &mut self,
        mode: ShiftMode,
        desired_ned_n: &Vector3<f64>,
        integrate: bool,
        dt_s: f64,
        g: &ShiftGains,
    ) -> Vector3<f64> {
        let shift = match mode {
            ShiftMode::Active => {
                let measured = self.filter.value();
                let error = desired_ned_n - measured;
                // A slack cable is a saturated actuator: integrating its error would only wind
                // up a shift that stays once the cable is taut (e_T = 0 at any height then).
                let slack = measured.norm() < g.slack_ratio * desired_ned_n.norm();
                if integrate && !slack {
                    self.integral_m += g.k_ti.component_mul(&error) * dt_s;
                    self.integral_m = clamp_each(&self.integral_m, &g.max_shift_m);
                }
                let d = g.k_td.component_mul(&self.filter.derivative(dt_s));
                clamp_each(
                    &(g.k_tp.component_mul(&error) + self.integral_m - d),
                    &g.max_shift_m,
                )
            }
            ShiftMode::Frozen => self.integral_m,
            ShiftMode::Off => {
                if self.mode != ShiftMode::Off {
                    // Bumpless: decay from the shift last applied, P and D included.
                    self.integral_m = self.shift_m;
                }
                self.integral_m *= (-dt_s / g.decay_tau_s).exp();
                self.integral_m
            }
        };
        self.mode = mode;
        self.shift_m = shift;
        shift
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityGains {
    pub k_vp: Vector3<f64>,
    pub k_vi: Vector3<f64>,
    pub k_vd: Vector3<f64>,
    /// Bound per axis of K_vI ∫e_v dt, m/s².
    pub max_integral_m_s2: Vector3<f64>,
}

/// a_d = K_vP e_v + K_vI ∫e_v dt − K_vD dv_f/dt (NED).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityPid {
    pub filter: LowPass3,
    /// K_vI ∫e_v dt, m/s².
    pub integral_m_s2: Vector3<f64>,
}

impl VelocityPid {
    pub fn new(cutoff_hz: f64) -> Self {
        Self {
            filter: LowPass3::new(cutoff_hz),
            integral_m_s2: Vector3::zeros(),
        }
    }

    /// The desired acceleration from the velocity error (uses the integral so far; call
    /// [`Self::integrate`] once the output's saturation is known).
    pub fn output(
        &mut self,
        error: &Vector3<f64>,
        velocity: &Vector3<f64>,
        dt_s: f64,
        g: &VelocityGains,
    ) -> Vector3<f64> {
        self.filter.update(velocity, dt_s);
        g.k_vp.component_mul(error) + self.integral_m_s2
            - g.k_vd.component_mul(&self.filter.derivative(dt_s))
    }

    /// Integrates `error` except on the axes in `blocked` (conditional integration against
    /// a saturated output), then clamps.
    pub fn integrate(
        &mut self,
        error: &Vector3<f64>,
        blocked: [bool; 3],
        dt_s: f64,
        g: &VelocityGains,
    ) {
        for i in 0..3 {
            if !blocked[i] {
                self.integral_m_s2[i] += g.k_vi[i] * error[i] * dt_s;
            }
        }
        self.integral_m_s2 = clamp_each(&self.integral_m_s2, &g.max_integral_m_s2);
    }
}
