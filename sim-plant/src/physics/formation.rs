//! Closed-form initial states: the payload hanging at rest below two level quads.

use nalgebra::Vector3;

use super::state::{BodyState, QuadState, WorldState};
use super::world_params::WorldParams;

/// The static equilibrium of a symmetric formation (see [`hanging_formation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HangingFormation {
    /// Quads level and at rest, rotor speeds at the static hover; payload at rest.
    pub state: WorldState,
    /// Tension in each cable, N: `m_p g / (2 cos theta)`.
    pub tension_n: f64,
    /// Angle of each cable from the vertical, rad.
    pub cable_angle_rad: f64,
    /// Anchor-to-anchor length of each (stretched) cable, m.
    pub cable_length_m: f64,
}

/// The payload hanging at rest between two level quads whose centres of mass are at
/// `center_ned -/+ (0, quad_spacing_m / 2, 0)` (quad 0 on the -y side, as payload anchor 0).
///
/// Solves `T cos(theta) = m_p g / 2`, `l = L + T / k`, `sin(theta) = w / l` (w: horizontal
/// anchor offset) by fixed-point iteration. Assumes the formation is symmetric: uses quad 0,
/// cable 0 and payload anchor 0 for both sides. If the anchors are farther apart than the
/// cables can reach with the payload's weight, the cables are left near horizontal
/// (theta close to 90 degrees): check `cable_angle_rad`. Rotor speeds are those that carry
/// the quad plus half the payload (the horizontal pull is left unbalanced).
pub fn hanging_formation(
    params: &WorldParams,
    center_ned: Vector3<f64>,
    quad_spacing_m: f64,
) -> HangingFormation {
    let q = &params.quads[0];
    let c = &params.cables[0];
    let pa = params.payload.anchors_frd_m[0];
    let g = params.gravity_m_s2;
    let half_weight = 0.5 * params.payload.mass_kg * g;
    let quad_anchor_y = -0.5 * quad_spacing_m + q.cable_anchor_frd_m[1];
    let width = (quad_anchor_y - pa[1]).abs();
    let mut length = c.rest_length_m.max(width * 1.0001);
    let mut cos_theta = 1.0;
    for _ in 0..200 {
        cos_theta = (1.0 - (width / length).powi(2)).max(1e-6).sqrt();
        let tension = half_weight / cos_theta;
        length = (c.rest_length_m + tension / c.stiffness_n_per_m).max(width * 1.0001);
    }
    let tension = half_weight / cos_theta;
    let quad_anchor_z = center_ned.z + q.cable_anchor_frd_m[2];
    let payload_z = quad_anchor_z + length * cos_theta - pa[2];
    let quad_at = |sign: f64| QuadState {
        body: BodyState::at_rest(center_ned + Vector3::new(0.0, sign * 0.5 * quad_spacing_m, 0.0)),
        rotor_speed: [q.hover_rotor_speed(q.mass_kg + half_weight / g, g); 4],
    };
    HangingFormation {
        state: WorldState {
            time_s: 0.0,
            quads: [quad_at(-1.0), quad_at(1.0)],
            payload: BodyState::at_rest(Vector3::new(
                center_ned.x + q.cable_anchor_frd_m[0] - pa[0],
                center_ned.y,
                payload_z,
            )),
        },
        tension_n: tension,
        cable_angle_rad: cos_theta.acos(),
        cable_length_m: length,
    }
}
