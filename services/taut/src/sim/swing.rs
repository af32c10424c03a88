//! Geometry shared by the flight metrics and the report: the payload's swing angle.

use nalgebra::{UnitQuaternion, Vector3};
use shared_types::PlantTruth;

/// A unit quaternion from (w, x, y, z).
pub fn quat(wxyz: [f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        wxyz[0], wxyz[1], wxyz[2], wxyz[3],
    ))
}

/// The pendulum angle of the payload about the line through the two cable anchors, degrees:
/// the angle between the anchors-to-payload plane and the vertical plane through that line.
pub fn swing_deg(t: &PlantTruth, anchor_frd_m: [f64; 3]) -> f64 {
    let anchor = |k: usize| {
        let b = &t.drones[k].body;
        Vector3::from(b.position_ned_m) + quat(b.attitude_wxyz) * Vector3::from(anchor_frd_m)
    };
    let (a1, a2) = (anchor(0), anchor(1));
    let Some(u) = (a2 - a1).try_normalize(1e-6) else {
        return f64::NAN;
    };
    let d = Vector3::from(t.payload.position_ned_m) - 0.5 * (a1 + a2);
    let d_perp = d - d.dot(&u) * u;
    let down = Vector3::z();
    let v = down - down.dot(&u) * u;
    let (Some(d_perp), Some(v)) = (d_perp.try_normalize(1e-9), v.try_normalize(1e-9)) else {
        return f64::NAN;
    };
    d_perp.cross(&v).norm().atan2(d_perp.dot(&v)).to_degrees()
}
