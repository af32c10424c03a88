//! Config of the vehicle and of the tension-aware cascade controller (paper IV, gains V.C).

use serde::{Deserialize, Serialize};

/// The drone and its load, as the controller and the bridge need them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct VehicleConfig {
    /// Mass of the drone with battery and sensor, kg (X500: 2.0 body + 4 x 0.016 rotors).
    pub mass_kg: f64,
    /// PX4's MPC_THR_HOVER for this airframe: normalised thrust that hovers `mass_kg`
    /// (0.6 in PX4's gz x500 airframe).
    pub hover_throttle: f64,
    /// Gravity, m/s².
    pub gravity_m_s2: f64,
    /// Payload mass, kg (shared by the two cables).
    pub payload_mass_kg: f64,
    /// Cable rest length, m.
    pub cable_length_m: f64,
    /// Cable anchor below the drone's centre of mass, body FRD, m.
    pub anchor_offset_frd_m: [f64; 3],
    /// Half the distance between the payload's two cable anchors, m.
    pub payload_anchor_half_span_m: f64,
}

impl Default for VehicleConfig {
    fn default() -> Self {
        Self {
            mass_kg: 2.064,
            hover_throttle: 0.6,
            gravity_m_s2: 9.80665,
            payload_mass_kg: 1.0,
            cable_length_m: 1.5,
            anchor_offset_frd_m: [0.0, 0.0, 0.08],
            payload_anchor_half_span_m: 0.1,
        }
    }
}

/// The cascade's gains (diagonals, x y z in NED) and limits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControllerConfig {
    /// Loop rate, Hz (the paper's outer loop: 100 Hz).
    pub rate_hz: f64,
    /// `odometry`: run when a vehicle state arrives (with the timer as a fallback);
    /// `timer`: run on an absolute-deadline timer.
    pub trigger: ControllerTrigger,
    /// Position P, 1/s.
    pub k_p: [f64; 3],
    /// Tension PID on e_T = T_d - T_f shifting the setpoint: m/N, m/(N s), m s/N.
    pub k_tp: [f64; 3],
    pub k_ti: [f64; 3],
    pub k_td: [f64; 3],
    /// Velocity PID: 1/s, 1/s², dimensionless.
    pub k_vp: [f64; 3],
    pub k_vi: [f64; 3],
    pub k_vd: [f64; 3],
    /// Cut-off of the "light" low-pass on the measured tension, Hz.
    pub tension_cutoff_hz: f64,
    /// Cut-off of the low-pass on the velocity for the D term, Hz.
    pub velocity_cutoff_hz: f64,
    /// Largest setpoint shift the tension loop may make, per axis, m (anti-windup bound).
    pub max_tension_shift_m: [f64; 3],
    /// Largest velocity setpoint, horizontal and vertical, m/s.
    pub max_velocity_xy_m_s: f64,
    pub max_velocity_z_m_s: f64,
    /// Bound of the velocity integrator's contribution, per axis, m/s².
    pub max_velocity_integral_m_s2: [f64; 3],
    /// Largest tilt of the thrust vector from vertical, deg.
    pub max_tilt_deg: f64,
    /// Collective thrust limits, N.
    pub min_thrust_n: f64,
    pub max_thrust_n: f64,
    /// A tension sample older than this is not used (position-only control), s.
    pub tension_max_age_s: f64,
    /// Odometry older than this is flagged, s.
    pub odometry_max_age_s: f64,
    /// A mission setpoint older than this is flagged, s.
    pub mission_max_age_s: f64,
    /// Time constant with which the tension shift decays to zero while the mission has the
    /// tension loop off, s.
    pub tension_shift_decay_s: f64,
    /// Anti-windup of the tension integral: while the measured tension is below this fraction
    /// of T_d's magnitude the cable is taken as slack (the position cannot change the tension
    /// linearly, like a saturated actuator) and e_T is not integrated; the P part still acts.
    pub slack_tension_ratio: f64,
    /// Which law flies the drone: `proposed` (the paper's cascade) or `geometric` (tracking
    /// law with direct compensation of the cable force, the paper's baseline).
    pub law: ControllerLaw,
    /// Where the cable force comes from: `sensor` (TENSION), `estimator` (TENSION_ESTIMATE)
    /// or `truth` (TENSION_TRUTH, simulation only).
    pub tension_source: TensionSource,
    /// Gains of the geometric law.
    pub geometric: GeometricConfig,
}

/// The control law of [`ControllerConfig::law`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ControllerLaw {
    #[default]
    Proposed,
    Geometric,
}

/// The tension topic of [`ControllerConfig::tension_source`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum TensionSource {
    /// The force sensor (the `tension` service).
    #[default]
    Sensor,
    /// The model-based external-force estimator (the `force-estimator` service).
    Estimator,
    /// The plant's true anchor force (simulation only).
    Truth,
}

impl ControllerLaw {
    pub fn as_str(self) -> &'static str {
        match self {
            ControllerLaw::Proposed => "proposed",
            ControllerLaw::Geometric => "geometric",
        }
    }
}

impl TensionSource {
    pub fn as_str(self) -> &'static str {
        match self {
            TensionSource::Sensor => "sensor",
            TensionSource::Estimator => "estimator",
            TensionSource::Truth => "truth",
        }
    }
}

/// Gains of the geometric tracking law F = m (K_p e_p + K_v e_v + a_ref − g e3) − f_ext
/// (diagonals, x y z in NED). Defaults: the cascade's equivalent proportional gains,
/// K_p = K_vP ∘ K_P = (2.16, 2.16, 4.2) 1/s², K_v = K_vP = (2.7, 2.7, 6.0) 1/s (a = K_vP (K_P e_p
/// − v) is the cascade without its integrals and derivative); no integral, as in the law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeometricConfig {
    /// Position gain, 1/s².
    pub kp: [f64; 3],
    /// Velocity gain, 1/s.
    pub kv: [f64; 3],
}

impl Default for GeometricConfig {
    fn default() -> Self {
        Self {
            kp: [2.16, 2.16, 4.2],
            kv: [2.7, 2.7, 6.0],
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ControllerTrigger {
    #[default]
    Odometry,
    Timer,
}

impl Default for ControllerConfig {
    fn default() -> Self {
        Self {
            rate_hz: 100.0,
            trigger: ControllerTrigger::Odometry,
            k_p: [0.8, 0.8, 0.7],
            k_tp: [0.22, 0.22, 0.06],
            k_ti: [0.08, 0.08, 0.18],
            k_td: [0.02, 0.02, 0.0],
            k_vp: [2.7, 2.7, 6.0],
            k_vi: [1.9, 1.9, 3.0],
            k_vd: [0.3, 0.3, 0.5],
            tension_cutoff_hz: 10.0,
            velocity_cutoff_hz: 10.0,
            max_tension_shift_m: [0.5, 0.5, 0.5],
            max_velocity_xy_m_s: 3.0,
            max_velocity_z_m_s: 1.5,
            max_velocity_integral_m_s2: [3.0, 3.0, 6.0],
            max_tilt_deg: 35.0,
            min_thrust_n: 2.0,
            max_thrust_n: 32.0,
            tension_max_age_s: 0.05,
            odometry_max_age_s: 0.1,
            mission_max_age_s: 0.2,
            tension_shift_decay_s: 1.0,
            slack_tension_ratio: 0.3,
            law: ControllerLaw::Proposed,
            tension_source: TensionSource::Sensor,
            geometric: GeometricConfig::default(),
        }
    }
}

fn finite(key: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("key `{key}` = {v}: must be finite"))
    }
}

fn positive(key: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("key `{key}` = {v}: must be finite and > 0"))
    }
}

fn non_negative(key: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(format!("key `{key}` = {v}: must be finite and >= 0"))
    }
}

fn each(key: &str, v: &[f64; 3], check: fn(&str, f64) -> Result<(), String>) -> Result<(), String> {
    v.iter()
        .enumerate()
        .try_for_each(|(i, x)| check(&format!("{key}[{i}]"), *x))
}

impl VehicleConfig {
    /// Checks every key; the error names the first bad one (`vehicle.mass_kg`, ...).
    pub fn validate(&self) -> Result<(), String> {
        positive("vehicle.mass_kg", self.mass_kg)?;
        if !(self.hover_throttle.is_finite()
            && self.hover_throttle > 0.0
            && self.hover_throttle <= 1.0)
        {
            return Err(format!(
                "key `vehicle.hover_throttle` = {}: must lie in (0, 1]",
                self.hover_throttle
            ));
        }
        positive("vehicle.gravity_m_s2", self.gravity_m_s2)?;
        non_negative("vehicle.payload_mass_kg", self.payload_mass_kg)?;
        positive("vehicle.cable_length_m", self.cable_length_m)?;
        each(
            "vehicle.anchor_offset_frd_m",
            &self.anchor_offset_frd_m,
            finite,
        )?;
        non_negative(
            "vehicle.payload_anchor_half_span_m",
            self.payload_anchor_half_span_m,
        )
    }
}

impl ControllerConfig {
    /// Checks every key; the error names the first bad one (`controller.k_p[2]`, ...).
    pub fn validate(&self) -> Result<(), String> {
        positive("controller.rate_hz", self.rate_hz)?;
        for (key, gains) in [
            ("controller.k_p", &self.k_p),
            ("controller.k_tp", &self.k_tp),
            ("controller.k_ti", &self.k_ti),
            ("controller.k_td", &self.k_td),
            ("controller.k_vp", &self.k_vp),
            ("controller.k_vi", &self.k_vi),
            ("controller.k_vd", &self.k_vd),
            ("controller.geometric.kp", &self.geometric.kp),
            ("controller.geometric.kv", &self.geometric.kv),
            ("controller.max_tension_shift_m", &self.max_tension_shift_m),
            (
                "controller.max_velocity_integral_m_s2",
                &self.max_velocity_integral_m_s2,
            ),
        ] {
            each(key, gains, non_negative)?;
        }
        positive("controller.tension_cutoff_hz", self.tension_cutoff_hz)?;
        positive("controller.velocity_cutoff_hz", self.velocity_cutoff_hz)?;
        positive("controller.max_velocity_xy_m_s", self.max_velocity_xy_m_s)?;
        positive("controller.max_velocity_z_m_s", self.max_velocity_z_m_s)?;
        if !(self.max_tilt_deg.is_finite() && self.max_tilt_deg > 0.0 && self.max_tilt_deg <= 80.0)
        {
            return Err(format!(
                "key `controller.max_tilt_deg` = {}: must lie in (0, 80]",
                self.max_tilt_deg
            ));
        }
        non_negative("controller.min_thrust_n", self.min_thrust_n)?;
        positive("controller.max_thrust_n", self.max_thrust_n)?;
        if self.min_thrust_n >= self.max_thrust_n {
            return Err(format!(
                "key `controller.min_thrust_n` = {}: must be below controller.max_thrust_n = {}",
                self.min_thrust_n, self.max_thrust_n
            ));
        }
        positive("controller.tension_max_age_s", self.tension_max_age_s)?;
        positive("controller.odometry_max_age_s", self.odometry_max_age_s)?;
        positive("controller.mission_max_age_s", self.mission_max_age_s)?;
        positive(
            "controller.tension_shift_decay_s",
            self.tension_shift_decay_s,
        )?;
        if !(0.0..1.0).contains(&self.slack_tension_ratio) {
            return Err(format!(
                "key `controller.slack_tension_ratio` = {}: must lie in [0, 1)",
                self.slack_tension_ratio
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        VehicleConfig::default().validate().unwrap();
        ControllerConfig::default().validate().unwrap();
    }

    #[test]
    fn errors_name_the_key() {
        let mut c = ControllerConfig::default();
        c.k_p[2] = -1.0;
        let e = c.validate().unwrap_err();
        assert!(e.contains("controller.k_p[2]"), "{e}");
        let c = ControllerConfig {
            min_thrust_n: 40.0,
            ..Default::default()
        };
        assert!(c
            .validate()
            .unwrap_err()
            .contains("controller.min_thrust_n"));
        let c = ControllerConfig {
            max_tilt_deg: 90.0,
            ..Default::default()
        };
        assert!(c
            .validate()
            .unwrap_err()
            .contains("controller.max_tilt_deg"));
        let mut v = VehicleConfig::default();
        v.anchor_offset_frd_m[1] = f64::NAN;
        let e = v.validate().unwrap_err();
        assert!(e.contains("vehicle.anchor_offset_frd_m[1]"), "{e}");
        let v = VehicleConfig {
            hover_throttle: 1.5,
            ..Default::default()
        };
        assert!(v.validate().unwrap_err().contains("vehicle.hover_throttle"));
    }
}
