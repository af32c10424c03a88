//! The paper's baseline: a geometric tracking law with direct compensation of the cable force
//! (MODEL.md "Baselines", `controller.law = "geometric"`).
//!
//! Thrust vector, NED:  F = m (K_p e_p + K_v e_v + a_ref − g e3) − f_ext,  g = +g e3,
//! e_p = ξ̄_d − ξ and e_v = v̄_d − v against the mission's nominal setpoint and its velocity,
//! a_ref the mission's acceleration feed-forward, f_ext the cable's pull on the drone (NED).
//! With the crate's sign convention (T = −f_ext, the force the drone exerts on the cable),
//! −f_ext = T_f: the same lightly filtered T_f the proposed law uses (`tension_cutoff_hz`).
//!
//! Choices (the paper gives the law only):
//! - The attitude comes from F's direction and the yaw setpoint, with the proposed law's
//!   mapping and limits (vertical priority, `max_tilt_deg`, thrust limits) through
//!   [`map_acceleration`] fed a = F/m + g e3.
//! - Thrust = the projection of F on the CURRENT body thrust axis, u = −F · (R e3) (Lee et al.'s
//!   choice: a drone still turning does not push hard in the wrong direction), clamped to the
//!   thrust limits. Level, it equals the proposed law's −F_z / (cos φ cos θ) = −F_z.
//! - f_ext is compensated while the mission has the tension loop on (as the proposed law's
//!   shift); with the loop off it is zero (take-off with slack cables, and the estimator's
//!   ground-reaction spike before lift-off, are not compensated). A stale tension sample holds
//!   the last T_f (the counterpart of the proposed law's frozen integral).
//! - No integral: the law has none, so a biased f_ext shows as a steady position error.

use nalgebra::{UnitQuaternion, Vector3};

use crate::mapping::{map_acceleration, Mapped, MappingParams, ThrustLimit};

/// Diagonal gains of the law, NED axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometricGains {
    /// K_p, 1/s².
    pub kp: Vector3<f64>,
    /// K_v, 1/s.
    pub kv: Vector3<f64>,
}

/// The reference the law tracks, NED.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reference {
    pub position_m: Vector3<f64>,
    pub velocity_m_s: Vector3<f64>,
    pub acceleration_m_s2: Vector3<f64>,
    pub yaw_rad: f64,
}

/// One command of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometricCommand {
    /// K_p e_p + K_v e_v + a_ref, NED, m/s² (without gravity and f_ext).
    pub tracking_m_s2: Vector3<f64>,
    /// Attitude, thrust and the force after the limits.
    pub mapped: Mapped,
}

/// K_p e_p + K_v e_v + a_ref, NED, m/s².
pub fn tracking_acceleration(
    g: &GeometricGains,
    reference: &Reference,
    position_m: &Vector3<f64>,
    velocity_m_s: &Vector3<f64>,
) -> Vector3<f64> {
    g.kp.component_mul(&(reference.position_m - position_m))
        + g.kv.component_mul(&(reference.velocity_m_s - velocity_m_s))
        + reference.acceleration_m_s2
}

/// F = m (tracking − g e3) − f_ext mapped to attitude and thrust; `f_ext_ned_n` is the
/// cable's pull on the drone, NED, N; `current` the vehicle's attitude (body FRD -> NED).
pub fn command(
    g: &GeometricGains,
    reference: &Reference,
    position_m: &Vector3<f64>,
    velocity_m_s: &Vector3<f64>,
    f_ext_ned_n: &Vector3<f64>,
    current: &UnitQuaternion<f64>,
    p: &MappingParams,
) -> GeometricCommand {
    let tracking_m_s2 = tracking_acceleration(g, reference, position_m, velocity_m_s);
    // map_acceleration forms m a − m g e3: hand it a = tracking − f_ext / m.
    let a = tracking_m_s2 - f_ext_ned_n / p.mass_kg;
    let mut mapped = map_acceleration(&a, reference.yaw_rad, current, p);
    let thrust_axis_ned = current * Vector3::z();
    let raw = -mapped.force_ned_n.dot(&thrust_axis_ned);
    mapped.thrust_n = raw.clamp(p.min_thrust_n, p.max_thrust_n);
    mapped.thrust_limit = if raw > p.max_thrust_n {
        ThrustLimit::Max
    } else if raw < p.min_thrust_n || mapped.thrust_limit == ThrustLimit::Min {
        // Also when the force itself was floored (a downward F asked).
        ThrustLimit::Min
    } else {
        ThrustLimit::None
    };
    GeometricCommand {
        tracking_m_s2,
        mapped,
    }
}

#[cfg(test)]
#[path = "geometric_tests.rs"]
mod tests;
