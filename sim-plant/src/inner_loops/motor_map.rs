//! Plant-side map from PX4's normalized motor thrust u in [0, 1] to commanded rotor speed.
//!
//! PX4's position controller turns a specific thrust a into throttle = hover_throttle * a / g
//! (MODEL.md). The plant uses the same map in reverse and linear in u:
//!
//! `T_i = u_i * m_nominal * g / (4 * hover_throttle)`,  `omega_i = sqrt(T_i / c_t)`,
//! clamped to [0, omega_max].
//!
//! So u = hover_throttle on all four motors holds exactly m_nominal * g, and u = 1 gives
//! m g / (4 * 0.6) = 8.44 N per rotor (993 rad/s) with the defaults, just below the X500's
//! 1000 rad/s limit. Torque commands then scale the same way (a normalized torque is a
//! difference of u, hence of thrust). The rotor lag and the thrust c_t omega^2 are the
//! physics' business; this map only inverts the thrust curve.

use serde::Deserialize;

use super::errors::{check_positive, check_range, ParamsError};

/// Motor map parameters; defaults match the plant's X500 (MODEL.md).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MotorMapParams {
    /// Throttle that hovers the nominal mass (MPC_THR_HOVER of the gz x500). Default 0.6.
    pub hover_throttle: f64,
    /// Mass the hover throttle holds, kg: 2.0 body + 4 x 0.016 rotors. Default 2.064.
    pub nominal_mass_kg: f64,
    /// Gravity of the plant, m/s^2. Default 9.81.
    pub gravity_m_s2: f64,
    /// Rotor thrust coefficient c_t, N/(rad/s)^2. Default 8.54858e-6.
    pub thrust_coefficient: f64,
    /// Upper limit of the commanded rotor speed, rad/s. Default 1000.
    pub max_rotor_speed_rad_s: f64,
}

impl Default for MotorMapParams {
    fn default() -> Self {
        MotorMapParams {
            hover_throttle: 0.6,
            nominal_mass_kg: 2.064,
            gravity_m_s2: 9.81,
            thrust_coefficient: 8.54858e-6,
            max_rotor_speed_rad_s: 1000.0,
        }
    }
}

impl MotorMapParams {
    /// Hover throttle in (0, 1], everything else finite and positive.
    pub fn validate(&self) -> Result<(), ParamsError> {
        check_range("motor_map.hover_throttle", self.hover_throttle, 1e-3, 1.0)?;
        check_positive("motor_map.nominal_mass_kg", self.nominal_mass_kg)?;
        check_positive("motor_map.gravity_m_s2", self.gravity_m_s2)?;
        check_positive("motor_map.thrust_coefficient", self.thrust_coefficient)?;
        check_positive(
            "motor_map.max_rotor_speed_rad_s",
            self.max_rotor_speed_rad_s,
        )
    }
}

/// The u -> rotor speed map.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorMap {
    /// Rotor thrust at u = 1, N.
    thrust_at_full_n: f64,
    thrust_coefficient: f64,
    max_rotor_speed_rad_s: f64,
    non_finite_inputs: u64,
}

impl MotorMap {
    pub fn new(params: &MotorMapParams) -> Result<Self, ParamsError> {
        params.validate()?;
        Ok(MotorMap {
            thrust_at_full_n: params.nominal_mass_kg * params.gravity_m_s2
                / (4.0 * params.hover_throttle),
            thrust_coefficient: params.thrust_coefficient,
            max_rotor_speed_rad_s: params.max_rotor_speed_rad_s,
            non_finite_inputs: 0,
        })
    }

    /// Thrust one rotor is asked for at normalized thrust `u` (clamped to [0, 1]), N.
    pub fn rotor_thrust_n(&self, u: f64) -> f64 {
        u.clamp(0.0, 1.0) * self.thrust_at_full_n
    }

    /// Commanded rotor speeds, rad/s, PX4 motor order. A non-finite u commands 0 (motor
    /// stopped, as PX4's output driver does with a NaN) and is counted.
    pub fn rotor_speeds(&mut self, u: &[f64; 4]) -> [f64; 4] {
        let mut omega = [0.0; 4];
        for (w, ui) in omega.iter_mut().zip(u) {
            if !ui.is_finite() {
                self.non_finite_inputs += 1;
                continue;
            }
            let t = self.rotor_thrust_n(*ui);
            *w = (t / self.thrust_coefficient)
                .sqrt()
                .min(self.max_rotor_speed_rad_s);
        }
        omega
    }

    /// Non-finite u values seen (each commanded 0).
    pub fn non_finite_inputs(&self) -> u64 {
        self.non_finite_inputs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hover_throttle_holds_the_nominal_weight() {
        let p = MotorMapParams::default();
        let mut m = MotorMap::new(&p).unwrap();
        let w = m.rotor_speeds(&[0.6; 4]);
        let total: f64 = w.iter().map(|w| p.thrust_coefficient * w * w).sum();
        assert!((total - 2.064 * 9.81).abs() < 1e-9, "{total}");
        // Hover near 770 rad/s (MODEL.md): sqrt(2.064 * 9.81 / 4 / 8.54858e-6) = 769.5.
        assert!((w[0] - 769.5).abs() < 0.1, "{w:?}");
        // u = 1: 8.437 N per rotor, 993.4 rad/s, under the 1000 rad/s limit.
        let full = m.rotor_speeds(&[1.0; 4])[0];
        assert!((full - 993.4).abs() < 0.1, "{full}");
    }

    #[test]
    fn clamps_and_counts_bad_inputs() {
        let mut m = MotorMap::new(&MotorMapParams {
            max_rotor_speed_rad_s: 900.0,
            ..MotorMapParams::default()
        })
        .unwrap();
        let w = m.rotor_speeds(&[-0.5, 2.0, f64::NAN, 0.0]);
        assert_eq!(w, [0.0, 900.0, 0.0, 0.0]);
        assert_eq!(m.non_finite_inputs(), 1);
        let bad = MotorMapParams {
            hover_throttle: 0.0,
            ..MotorMapParams::default()
        };
        assert_eq!(
            MotorMap::new(&bad).unwrap_err().key,
            "motor_map.hover_throttle"
        );
    }
}
