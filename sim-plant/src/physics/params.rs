//! Parameters of the plant's rigid bodies: the X500 quadrotors and the payload.
//!
//! Every struct has a default (X500 and the paper's 1 kg payload), parses from TOML/JSON with
//! `deny_unknown_fields`, and names what it got wrong in [`ParamsError`]. Vectors are
//! `[f64; 3]` in the frame their name says (nalgebra here has no serde support).

use serde::Deserialize;

/// A parameter value the physics cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("physics parameter `{key}` = {value}: {requirement}")]
pub struct ParamsError {
    /// Path of the parameter, e.g. `quads[1].mass_kg`.
    pub key: String,
    /// The offending value, printed.
    pub value: String,
    /// What it should have been.
    pub requirement: &'static str,
}

impl ParamsError {
    fn new(key: String, value: impl std::fmt::Debug, requirement: &'static str) -> Self {
        ParamsError {
            key,
            value: format!("{value:?}"),
            requirement,
        }
    }
}

/// `Ok` if `v` is finite and > 0.
pub(crate) fn positive(key: impl Into<String>, v: f64) -> Result<(), ParamsError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(ParamsError::new(key.into(), v, "must be finite and > 0"))
    }
}

/// `Ok` if `v` is finite and >= 0.
pub(crate) fn non_negative(key: impl Into<String>, v: f64) -> Result<(), ParamsError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(ParamsError::new(key.into(), v, "must be finite and >= 0"))
    }
}

/// `Ok` if every component is finite.
pub(crate) fn finite(key: impl Into<String>, v: &[f64]) -> Result<(), ParamsError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ParamsError::new(key.into(), v, "must be finite"))
    }
}

/// One quadrotor (Holybro X500 v2 as in PX4's Gazebo model, MODEL.md).
///
/// Thrust of rotor j is `c_t omega_j^2` along -z body; its reaction torque about +z body is
/// `spin_j c_m thrust_j` (spin +1 for a CCW rotor: seen from above it pushes the body clockwise,
/// which is +yaw in FRD). Rotor gyroscopic effects and rotor inertia are not modelled.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct QuadParams {
    /// Total mass, kg (2.0 body + 4 x 0.016 rotors).
    pub mass_kg: f64,
    /// Principal moments of inertia about body FRD x, y, z, kg m^2.
    pub inertia_diag_kg_m2: [f64; 3],
    /// Rotor hub positions in body FRD, m, in PX4 quad-X motor order 1..4.
    pub rotor_positions_frd_m: [[f64; 3]; 4],
    /// Spin direction per rotor: +1 CCW seen from above, -1 CW.
    pub rotor_spin: [f64; 4],
    /// Thrust coefficient c_t, N per (rad/s)^2.
    pub thrust_coeff_n_per_rad2_s2: f64,
    /// Rotor moment constant c_m (reaction torque / thrust), m.
    pub moment_constant_m: f64,
    /// Rotor speed limit, rad/s; commands are clamped to [0, this].
    pub max_rotor_speed_rad_s: f64,
    /// First-order motor time constant when speeding up, s.
    pub motor_tau_up_s: f64,
    /// First-order motor time constant when slowing down, s.
    pub motor_tau_down_s: f64,
    /// Cable anchor offset from the centre of mass, body FRD, m.
    pub cable_anchor_frd_m: [f64; 3],
    /// Landing-gear contact points, body FRD, m.
    pub gear_points_frd_m: [[f64; 3]; 4],
    /// Linear aerodynamic drag, N per m/s of NED velocity (0: none).
    pub linear_drag_n_s_per_m: f64,
}

impl QuadParams {
    /// The Holybro X500 of PX4's Gazebo model.
    pub fn x500() -> Self {
        const A: f64 = 0.174;
        const G: f64 = 0.12;
        QuadParams {
            mass_kg: 2.0 + 4.0 * 0.016,
            inertia_diag_kg_m2: [0.02167, 0.02167, 0.04],
            rotor_positions_frd_m: [[A, A, 0.0], [-A, -A, 0.0], [A, -A, 0.0], [-A, A, 0.0]],
            rotor_spin: [1.0, 1.0, -1.0, -1.0],
            thrust_coeff_n_per_rad2_s2: 8.54858e-6,
            moment_constant_m: 0.016,
            max_rotor_speed_rad_s: 1000.0,
            motor_tau_up_s: 0.0125,
            motor_tau_down_s: 0.025,
            cable_anchor_frd_m: [0.0, 0.0, 0.08],
            gear_points_frd_m: [[G, G, G], [G, -G, G], [-G, G, G], [-G, -G, G]],
            linear_drag_n_s_per_m: 0.0,
        }
    }

    /// Rotor speed (rad/s, equal on all four) whose thrust carries `supported_mass_kg` against
    /// gravity `g_m_s2`.
    pub fn hover_rotor_speed(&self, supported_mass_kg: f64, g_m_s2: f64) -> f64 {
        (supported_mass_kg * g_m_s2 / (4.0 * self.thrust_coeff_n_per_rad2_s2)).sqrt()
    }

    /// Checks every value; `key` prefixes the names in the error (e.g. `quads[0]`).
    pub fn validate(&self, key: &str) -> Result<(), ParamsError> {
        positive(format!("{key}.mass_kg"), self.mass_kg)?;
        for (j, &v) in self.inertia_diag_kg_m2.iter().enumerate() {
            positive(format!("{key}.inertia_diag_kg_m2[{j}]"), v)?;
        }
        for (j, p) in self.rotor_positions_frd_m.iter().enumerate() {
            finite(format!("{key}.rotor_positions_frd_m[{j}]"), p)?;
        }
        for (j, &s) in self.rotor_spin.iter().enumerate() {
            if s != 1.0 && s != -1.0 {
                return Err(ParamsError::new(
                    format!("{key}.rotor_spin[{j}]"),
                    s,
                    "must be +1 (CCW) or -1 (CW)",
                ));
            }
        }
        positive(
            format!("{key}.thrust_coeff_n_per_rad2_s2"),
            self.thrust_coeff_n_per_rad2_s2,
        )?;
        non_negative(format!("{key}.moment_constant_m"), self.moment_constant_m)?;
        positive(
            format!("{key}.max_rotor_speed_rad_s"),
            self.max_rotor_speed_rad_s,
        )?;
        positive(format!("{key}.motor_tau_up_s"), self.motor_tau_up_s)?;
        positive(format!("{key}.motor_tau_down_s"), self.motor_tau_down_s)?;
        finite(
            format!("{key}.cable_anchor_frd_m"),
            &self.cable_anchor_frd_m,
        )?;
        for (j, p) in self.gear_points_frd_m.iter().enumerate() {
            finite(format!("{key}.gear_points_frd_m[{j}]"), p)?;
        }
        non_negative(
            format!("{key}.linear_drag_n_s_per_m"),
            self.linear_drag_n_s_per_m,
        )
    }
}

impl Default for QuadParams {
    fn default() -> Self {
        QuadParams::x500()
    }
}

/// The payload: a solid box (the paper's two 0.5 kg ballasts, 1 kg in all).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PayloadParams {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Box edge lengths along body FRD x, y, z, m; the inertia is that of a solid box.
    pub box_size_m: [f64; 3],
    /// Cable anchor points in payload body FRD, m: `[0]` takes cable 0 (drone 0), `[1]` cable 1.
    pub anchors_frd_m: [[f64; 3]; 2],
    /// Contact points in payload body FRD, m (default: the four bottom corners).
    pub contact_points_frd_m: [[f64; 3]; 4],
}

impl PayloadParams {
    /// Principal moments of inertia of the solid box about body x, y, z, kg m^2.
    pub fn inertia_diag_kg_m2(&self) -> [f64; 3] {
        let [a, b, c] = self.box_size_m;
        let m = self.mass_kg / 12.0;
        [
            m * (b * b + c * c),
            m * (a * a + c * c),
            m * (a * a + b * b),
        ]
    }

    /// Checks every value; `key` prefixes the names in the error.
    pub fn validate(&self, key: &str) -> Result<(), ParamsError> {
        positive(format!("{key}.mass_kg"), self.mass_kg)?;
        for (j, &v) in self.box_size_m.iter().enumerate() {
            positive(format!("{key}.box_size_m[{j}]"), v)?;
        }
        for (j, p) in self.anchors_frd_m.iter().enumerate() {
            finite(format!("{key}.anchors_frd_m[{j}]"), p)?;
        }
        for (j, p) in self.contact_points_frd_m.iter().enumerate() {
            finite(format!("{key}.contact_points_frd_m[{j}]"), p)?;
        }
        Ok(())
    }
}

impl Default for PayloadParams {
    fn default() -> Self {
        PayloadParams {
            mass_kg: 1.0,
            box_size_m: [0.2, 0.2, 0.1],
            anchors_frd_m: [[0.0, -0.1, -0.05], [0.0, 0.1, -0.05]],
            contact_points_frd_m: [
                [0.1, 0.1, 0.05],
                [0.1, -0.1, 0.05],
                [-0.1, 0.1, 0.05],
                [-0.1, -0.1, 0.05],
            ],
        }
    }
}

/// One cable: tension-only spring-damper between a drone anchor and a payload anchor.
///
/// With stretch `s = d - L`: tension `max(0, k s + c s')` while `s > 0`, zero when slack.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CableParams {
    /// Unstretched length L, m.
    pub rest_length_m: f64,
    /// Axial stiffness k, N/m (a ~1 mm nylon line: EA ~2.3 kN over 1.5 m).
    pub stiffness_n_per_m: f64,
    /// Axial damping c, N s/m.
    pub damping_n_s_per_m: f64,
}

impl CableParams {
    /// Checks every value; `key` prefixes the names in the error.
    pub fn validate(&self, key: &str) -> Result<(), ParamsError> {
        positive(format!("{key}.rest_length_m"), self.rest_length_m)?;
        positive(format!("{key}.stiffness_n_per_m"), self.stiffness_n_per_m)?;
        non_negative(format!("{key}.damping_n_s_per_m"), self.damping_n_s_per_m)
    }
}

impl Default for CableParams {
    fn default() -> Self {
        CableParams {
            rest_length_m: 1.5,
            stiffness_n_per_m: 1500.0,
            damping_n_s_per_m: 5.0,
        }
    }
}
