//! Newton-Euler equations of the three bodies (paper eqs. 1-2 plus contacts) and the two
//! integrators. Body index 0, 1 = quads, 2 = payload.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector2, Vector3};

use super::model::{cable_eval, point_contact, rotor_wrench, Model, PAYLOAD};

/// The integrated part of the state (rotor speeds are advanced in closed form elsewhere).
/// Quaternions are kept raw during a step and renormalised at its end.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Phase {
    pub pos: [Vector3<f64>; 3],
    pub vel: [Vector3<f64>; 3],
    pub quat: [Quaternion<f64>; 3],
    pub rate: [Vector3<f64>; 3],
}

/// Time derivative of a [`Phase`] (position derivative is `vel`, taken from the phase).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Deriv {
    pub vel: [Vector3<f64>; 3],
    pub acc: [Vector3<f64>; 3],
    pub dquat: [Quaternion<f64>; 3],
    pub alpha: [Vector3<f64>; 3],
}

impl Phase {
    /// `self + h * d`.
    fn plus(&self, d: &Deriv, h: f64) -> Phase {
        let mut out = *self;
        for b in 0..3 {
            out.pos[b] += d.vel[b] * h;
            out.vel[b] += d.acc[b] * h;
            out.quat[b] += d.dquat[b] * h;
            out.rate[b] += d.alpha[b] * h;
        }
        out
    }
}

/// What drives the bodies besides their state, fixed during one step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Drive<'a> {
    /// External forces at each centre of mass, NED, N.
    pub external_force_ned: &'a [Vector3<f64>; 3],
    /// Pinned quads have zero derivative and feel no forces.
    pub pinned: [bool; 2],
    /// Friction anchors of each body's contact points, NED x, y.
    pub anchors_xy: &'a [[Vector2<f64>; 4]; 3],
}

/// Rotation matrix (body FRD -> NED) of a possibly slightly non-unit quaternion.
#[inline]
pub(crate) fn rotation(q: &Quaternion<f64>) -> Matrix3<f64> {
    UnitQuaternion::new_normalize(*q)
        .to_rotation_matrix()
        .into_inner()
}

/// Position and velocity (NED) of the body point at `r_frd`.
#[inline]
pub(crate) fn point_kinematics(
    pos: &Vector3<f64>,
    vel: &Vector3<f64>,
    rot: &Matrix3<f64>,
    rate_frd: &Vector3<f64>,
    r_frd: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    (pos + rot * r_frd, vel + rot * rate_frd.cross(r_frd))
}

/// The state derivative at `y` with rotor speeds `rotor_speed` (rad/s).
pub(crate) fn derivative(
    model: &Model,
    y: &Phase,
    rotor_speed: &[[f64; 4]; 2],
    drive: &Drive,
) -> Deriv {
    let rot = [
        rotation(&y.quat[0]),
        rotation(&y.quat[1]),
        rotation(&y.quat[2]),
    ];
    let mut torque = [Vector3::<f64>::zeros(); 3];
    let free = [!drive.pinned[0], !drive.pinned[1], true];
    let mut force: [Vector3<f64>; 3] = std::array::from_fn(|b| {
        Vector3::new(0.0, 0.0, model.mass[b] * model.gravity) + drive.external_force_ned[b]
    });
    for i in 0..2 {
        if !free[i] {
            continue;
        }
        let r = &model.rotors[i];
        let (thrust_frd, rotor_torque_frd) = rotor_wrench(r, &rotor_speed[i]);
        force[i] += rot[i] * thrust_frd - y.vel[i] * r.drag;
        torque[i] += rotor_torque_frd;
    }
    for i in 0..2 {
        let rq = &model.quad_anchor_frd[i];
        let rp = &model.payload_anchor_frd[i];
        let (qa, qv) = point_kinematics(&y.pos[i], &y.vel[i], &rot[i], &y.rate[i], rq);
        let (pa, pv) = point_kinematics(
            &y.pos[PAYLOAD],
            &y.vel[PAYLOAD],
            &rot[PAYLOAD],
            &y.rate[PAYLOAD],
            rp,
        );
        let c = cable_eval(&model.cables[i], &qa, &qv, &pa, &pv);
        if c.tension > 0.0 {
            let on_quad = c.dir * c.tension;
            force[i] += on_quad;
            torque[i] += rq.cross(&(rot[i].transpose() * on_quad));
            force[PAYLOAD] -= on_quad;
            torque[PAYLOAD] -= rp.cross(&(rot[PAYLOAD].transpose() * on_quad));
        }
    }
    for b in 0..3 {
        if !free[b] {
            continue;
        }
        for j in 0..4 {
            let r = &model.points_frd[b][j];
            let p = y.pos[b] + rot[b] * r;
            if p.z <= model.highest_surface_z {
                continue; // above every surface: skip the velocity and the box search
            }
            let v = y.vel[b] + rot[b] * y.rate[b].cross(r);
            if let Some(pc) = point_contact(
                &model.contact,
                &model.boxes,
                &p,
                &v,
                &drive.anchors_xy[b][j],
            ) {
                let f = pc.force_ned();
                force[b] += f;
                torque[b] += r.cross(&(rot[b].transpose() * f));
            }
        }
    }
    let mut d = Deriv {
        vel: y.vel,
        acc: [Vector3::zeros(); 3],
        dquat: [Quaternion::new(0.0, 0.0, 0.0, 0.0); 3],
        alpha: [Vector3::zeros(); 3],
    };
    for b in 0..3 {
        if !free[b] {
            d.vel[b] = Vector3::zeros();
            continue;
        }
        let w = &y.rate[b];
        let iw = model.inertia[b].component_mul(w);
        d.acc[b] = force[b] / model.mass[b];
        d.alpha[b] = model.inv_inertia[b].component_mul(&(torque[b] - w.cross(&iw)));
        d.dquat[b] = y.quat[b] * Quaternion::from_imag(*w) * 0.5;
    }
    d
}

/// One classical RK4 step of length `h`. `rotor_speed[k]` are the rotor speeds at the start,
/// middle and end of the step.
pub(crate) fn rk4_step(
    model: &Model,
    y: &Phase,
    h: f64,
    rotor_speed: &[[[f64; 4]; 2]; 3],
    drive: &Drive,
) -> Phase {
    let k1 = derivative(model, y, &rotor_speed[0], drive);
    let k2 = derivative(model, &y.plus(&k1, 0.5 * h), &rotor_speed[1], drive);
    let k3 = derivative(model, &y.plus(&k2, 0.5 * h), &rotor_speed[1], drive);
    let k4 = derivative(model, &y.plus(&k3, h), &rotor_speed[2], drive);
    let mut out = *y;
    let w = h / 6.0;
    for b in 0..3 {
        out.pos[b] += (k1.vel[b] + (k2.vel[b] + k3.vel[b]) * 2.0 + k4.vel[b]) * w;
        out.vel[b] += (k1.acc[b] + (k2.acc[b] + k3.acc[b]) * 2.0 + k4.acc[b]) * w;
        out.quat[b] += (k1.dquat[b] + (k2.dquat[b] + k3.dquat[b]) * 2.0 + k4.dquat[b]) * w;
        out.rate[b] += (k1.alpha[b] + (k2.alpha[b] + k3.alpha[b]) * 2.0 + k4.alpha[b]) * w;
    }
    out
}

/// One semi-implicit (symplectic) Euler step: velocities and rates from the forces at the
/// start, then positions and attitudes with the new velocities and rates (exact rotation).
pub(crate) fn semi_implicit_euler_step(
    model: &Model,
    y: &Phase,
    h: f64,
    rotor_speed: &[[f64; 4]; 2],
    drive: &Drive,
) -> Phase {
    let k = derivative(model, y, rotor_speed, drive);
    let mut out = *y;
    for b in 0..3 {
        if b < 2 && drive.pinned[b] {
            continue;
        }
        out.vel[b] += k.acc[b] * h;
        out.rate[b] += k.alpha[b] * h;
        out.pos[b] += out.vel[b] * h;
        let turn = UnitQuaternion::from_scaled_axis(out.rate[b] * h);
        out.quat[b] = y.quat[b] * turn.into_inner();
    }
    out
}
