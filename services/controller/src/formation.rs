//! The nominal static tension T_d of the two-drone formation: the force each drone exerts on
//! its cable (NED, N) when both drones sit at their nominal setpoints and the payload hangs at
//! rest.
//!
//! Model: the payload is level, with its two cable anchors ±`payload_anchor_half_span_m` along
//! the horizontal line joining the drones (own side towards the own drone); each drone's anchor
//! sits `anchor_offset_frd_m[2]` below its setpoint (a level drone; the horizontal offsets are
//! ignored, they are zero on the X500). Cables are inextensible (1500 N/m stretches them by
//! ~3 mm) and tension-only. Shifting each drone anchor by the payload half span towards the
//! other ("effective anchors" A and B) turns the payload into a point P = the midpoint of its
//! anchors, with |A − P| <= L and |B − P| <= L. P hangs where it is lowest (the potential),
//! solved in the vertical plane through the drone anchors:
//! - the bottom of one disk lies inside the other: that cable alone holds m_p g, the other is 0;
//! - otherwise both are taut at the lower crossing of the two circles and the 2x2 statics give
//!   the magnitudes;
//! - |A − B| > 2L: the cables cannot reach; the chord is shrunk to
//!   [`NEAR_HORIZONTAL_CHORD`] · 2L (cables ~78° from vertical at equal heights) and the
//!   result is flagged [`FormationRegime::TooFar`].

use nalgebra::{Vector2, Vector3};
use rt_config::VehicleConfig;

/// In the too-far regime, the fraction of 2L the anchor chord is shrunk to.
pub const NEAR_HORIZONTAL_CHORD: f64 = 0.98;

/// Which cables carry the payload in the static solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FormationRegime {
    /// Both cables taut.
    BothTaut,
    /// The own cable alone holds the payload (the peer is much lower, or the drones are closer
    /// than the anchor span allows); the own T_d is (0, 0, −m_p g).
    OwnCableOnly,
    /// The peer's cable alone holds the payload; the own T_d is zero.
    PeerCableOnly,
    /// The setpoints are farther apart than the cables reach: the near-horizontal limit.
    TooFar,
}

/// The static solution for one pair of setpoints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FormationTension {
    /// Force the own drone exerts on its cable, NED, N (z < 0 for a hanging load).
    pub own_ned_n: [f64; 3],
    /// Force the peer exerts on its cable, NED, N.
    pub peer_ned_n: [f64; 3],
    /// Midpoint of the payload's two anchors at rest, NED, m.
    pub payload_anchor_mid_ned_m: [f64; 3],
    pub regime: FormationRegime,
}

/// T_d for the drone at `own_setpoint_ned_m` carrying the payload with the drone at
/// `peer_setpoint_ned_m` (both nominal setpoints, NED, m). Pure; no allocation. Non-finite
/// inputs give a non-finite result (the caller checks).
pub fn static_tension(
    own_setpoint_ned_m: &[f64; 3],
    peer_setpoint_ned_m: &[f64; 3],
    vehicle: &VehicleConfig,
) -> FormationTension {
    let own = Vector3::from(*own_setpoint_ned_m);
    let peer = Vector3::from(*peer_setpoint_ned_m);
    let horizontal = Vector3::new(peer.x - own.x, peer.y - own.y, 0.0);
    let d = horizontal.norm();
    // Drones one above the other: any horizontal direction does; north is as good as any.
    let e = if d > 1e-9 {
        horizontal / d
    } else {
        Vector3::x()
    };
    let a = vehicle.payload_anchor_half_span_m;
    let len = vehicle.cable_length_m;
    let below = vehicle.anchor_offset_frd_m[2];
    let weight = vehicle.payload_mass_kg * vehicle.gravity_m_s2;
    // Plane coordinates (s along e from the own drone, z NED) of the effective anchors.
    let mut pa = Vector2::new(a, own.z + below);
    let mut pb = Vector2::new(d - a, peer.z + below);
    let mut regime = FormationRegime::BothTaut;
    let chord = (pb - pa).norm();
    if chord > 2.0 * len {
        regime = FormationRegime::TooFar;
        let mid = (pa + pb) / 2.0;
        let half = (pb - pa) * (NEAR_HORIZONTAL_CHORD * len / chord);
        pa = mid - half;
        pb = mid + half;
    }
    let down = Vector2::new(0.0, len);
    let (p, t_a, t_b) = if chord < 1e-9 {
        // Coincident effective anchors: the cables hang together and share the load.
        (pa + down, 0.5 * weight, 0.5 * weight)
    } else if regime != FormationRegime::TooFar && (pa + down - pb).norm() <= len {
        regime = FormationRegime::OwnCableOnly;
        (pa + down, weight, 0.0)
    } else if regime != FormationRegime::TooFar && (pb + down - pa).norm() <= len {
        regime = FormationRegime::PeerCableOnly;
        (pb + down, 0.0, weight)
    } else {
        let ab = pb - pa;
        let c = ab.norm() / 2.0;
        let h = (len * len - c * c).max(0.0).sqrt();
        // The perpendicular to AB pointing down (z > 0); AB is not vertical here.
        let n = Vector2::new(-ab.y, ab.x) * (ab.x.signum() / ab.norm());
        let p = (pa + pb) / 2.0 + n * h;
        let (ua, ub) = ((pa - p) / len, (pb - p) / len);
        // ua t_a + ub t_b = (0, −m_p g): the cables hold the weight up (−z).
        let det = ua.x * ub.y - ub.x * ua.y;
        let t_a = (weight * ub.x / det).max(0.0);
        let t_b = (-weight * ua.x / det).max(0.0);
        (p, t_a, t_b)
    };
    let to_ned = |v: Vector2<f64>| e * v.x + Vector3::z() * v.y;
    // The drone pulls its cable from the payload towards itself: along (anchor − P).
    let own_t = to_ned((pa - p) / len) * t_a;
    let peer_t = to_ned((pb - p) / len) * t_b;
    let mid = Vector3::new(own.x, own.y, 0.0) + e * p.x + Vector3::z() * p.y;
    FormationTension {
        own_ned_n: own_t.into(),
        peer_ned_n: peer_t.into(),
        payload_anchor_mid_ned_m: mid.into(),
        regime,
    }
}

#[cfg(test)]
#[path = "formation_tests.rs"]
mod tests;
