//! Parameters of the world: contacts, obstacles, integrator, and the whole plant.

use serde::Deserialize;

use super::params::{
    finite, non_negative, positive, CableParams, ParamsError, PayloadParams, QuadParams,
};

/// Contact of body points with the ground and box tops: a normal spring-damper acting on
/// penetration only, and Coulomb friction with sticking through an anchored tangential spring
/// ("bristle"). All values are per contact point.
///
/// Defaults: the payload (1 kg on 4 points) rests with 0.12 mm penetration, vertical damping
/// ratio ~1.2 (no bounce), and the stiffest rocking mode (~440 rad/s, overdamped) stays well
/// inside RK4's stability region at 0.5 ms.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ContactParams {
    /// Normal stiffness per point, N/m of penetration.
    pub normal_stiffness_n_per_m: f64,
    /// Normal damping per point, N s/m (the normal force is clamped at >= 0: no suction).
    pub normal_damping_n_s_per_m: f64,
    /// Coulomb friction coefficient (static = kinetic).
    pub friction_mu: f64,
    /// Stiffness of the tangential anchor spring per point, N/m: elastic deflection while sticking.
    pub tangential_stiffness_n_per_m: f64,
    /// Damping of the tangential anchor spring per point, N s/m.
    pub tangential_damping_n_s_per_m: f64,
    /// A point inside a box's xy footprint is pushed up by the box top only while it is less
    /// than this far below the top, m. Deeper points feel nothing (box sides are not modelled).
    pub box_top_depth_m: f64,
}

impl ContactParams {
    /// Checks every value; `key` prefixes the names in the error.
    pub fn validate(&self, key: &str) -> Result<(), ParamsError> {
        positive(
            format!("{key}.normal_stiffness_n_per_m"),
            self.normal_stiffness_n_per_m,
        )?;
        non_negative(
            format!("{key}.normal_damping_n_s_per_m"),
            self.normal_damping_n_s_per_m,
        )?;
        non_negative(format!("{key}.friction_mu"), self.friction_mu)?;
        positive(
            format!("{key}.tangential_stiffness_n_per_m"),
            self.tangential_stiffness_n_per_m,
        )?;
        non_negative(
            format!("{key}.tangential_damping_n_s_per_m"),
            self.tangential_damping_n_s_per_m,
        )?;
        positive(format!("{key}.box_top_depth_m"), self.box_top_depth_m)
    }
}

impl Default for ContactParams {
    fn default() -> Self {
        ContactParams {
            normal_stiffness_n_per_m: 2.0e4,
            normal_damping_n_s_per_m: 170.0,
            friction_mu: 0.5,
            tangential_stiffness_n_per_m: 2.0e4,
            tangential_damping_n_s_per_m: 140.0,
            box_top_depth_m: 0.05,
        }
    }
}

/// An axis-aligned box obstacle. Only its top face (z = `center_ned[2] - half_extents[2]`)
/// carries contact; its sides are not modelled.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxObstacle {
    /// Centre, NED, m.
    pub center_ned: [f64; 3],
    /// Half edge lengths along NED x, y, z, m.
    pub half_extents: [f64; 3],
}

impl BoxObstacle {
    /// NED z of the top face, m (the smallest z of the box).
    pub fn top_z_ned(&self) -> f64 {
        self.center_ned[2] - self.half_extents[2]
    }

    /// Checks every value; `key` prefixes the names in the error.
    pub fn validate(&self, key: &str) -> Result<(), ParamsError> {
        finite(format!("{key}.center_ned"), &self.center_ned)?;
        for (j, &v) in self.half_extents.iter().enumerate() {
            positive(format!("{key}.half_extents[{j}]"), v)?;
        }
        Ok(())
    }
}

/// How [`super::World::step`] integrates. See the module doc for the measured comparison.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Classical fourth-order Runge-Kutta; friction anchors updated once per step.
    #[default]
    Rk4,
    /// Semi-implicit (symplectic) Euler: velocities first, then positions with the new ones.
    SemiImplicitEuler,
}

/// Everything the physics needs: two quads, the payload, two cables, contacts, obstacles.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WorldParams {
    /// Quad 0 and quad 1; cable i joins quad i to payload anchor i.
    pub quads: [QuadParams; 2],
    pub payload: PayloadParams,
    pub cables: [CableParams; 2],
    pub contact: ContactParams,
    /// Box obstacles (read at construction; the list cannot change afterwards).
    pub boxes: Vec<BoxObstacle>,
    /// Gravity along +z NED, m/s^2.
    pub gravity_m_s2: f64,
    pub integrator: Integrator,
    /// Longest internal step, s: a longer `step` is split into equal sub-steps no longer than
    /// this (contacts need it; the default suits 2 kHz stepping).
    pub max_substep_s: f64,
}

impl Default for WorldParams {
    fn default() -> Self {
        WorldParams {
            quads: [QuadParams::x500(), QuadParams::x500()],
            payload: PayloadParams::default(),
            cables: [CableParams::default(), CableParams::default()],
            contact: ContactParams::default(),
            boxes: Vec::new(),
            gravity_m_s2: 9.81,
            integrator: Integrator::Rk4,
            max_substep_s: 0.0005,
        }
    }
}

impl WorldParams {
    /// Checks every value; the error names the parameter path, e.g. `cables[1].stiffness_n_per_m`.
    pub fn validate(&self) -> Result<(), ParamsError> {
        for (i, q) in self.quads.iter().enumerate() {
            q.validate(&format!("quads[{i}]"))?;
        }
        self.payload.validate("payload")?;
        for (i, c) in self.cables.iter().enumerate() {
            c.validate(&format!("cables[{i}]"))?;
        }
        self.contact.validate("contact")?;
        for (i, b) in self.boxes.iter().enumerate() {
            b.validate(&format!("boxes[{i}]"))?;
        }
        non_negative("gravity_m_s2", self.gravity_m_s2)?;
        positive("max_substep_s", self.max_substep_s)
    }
}
