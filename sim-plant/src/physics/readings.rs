//! What the world reports about its current state: cables, contacts, sensors, energy.

use nalgebra::Vector3;

use super::dynamics::{point_kinematics, rotation};
use super::model::{cable_eval, find_surface, point_contact, PAYLOAD};
use super::state::{
    BodyState, CableReading, ContactReading, ContactSurface, Energy, FrictionState,
};
use super::world::World;

impl World {
    fn body(&self, b: usize) -> &BodyState {
        if b == PAYLOAD {
            &self.state.payload
        } else {
            &self.state.quads[b].body
        }
    }

    /// Cable `i` (joining quad `i` to payload anchor `i`) at the current state.
    /// Panics if `i > 1`.
    pub fn cable(&self, i: usize) -> CableReading {
        let q = self.body(i);
        let p = &self.state.payload;
        let (qa, qv) = point_kinematics(
            &q.position_ned,
            &q.velocity_ned,
            &rotation(&q.attitude.into_inner()),
            &q.rate_frd,
            &self.model.quad_anchor_frd[i],
        );
        let (pa, pv) = point_kinematics(
            &p.position_ned,
            &p.velocity_ned,
            &rotation(&p.attitude.into_inner()),
            &p.rate_frd,
            &self.model.payload_anchor_frd[i],
        );
        let c = cable_eval(&self.model.cables[i], &qa, &qv, &pa, &pv);
        let on_quad = c.dir * c.tension;
        CableReading {
            tension_n: c.tension,
            length_m: c.length,
            stretch_m: c.stretch,
            stretch_rate_m_s: c.stretch_rate,
            direction_ned: c.dir,
            force_on_quad_ned: on_quad,
            force_on_payload_ned: -on_quad,
            slack: c.tension <= 0.0,
        }
    }

    /// Force the cable exerts on quad `i` at its anchor, in quad `i`'s body FRD, N (what its
    /// force sensor is loaded with). Panics if `i > 1`.
    pub fn anchor_force_frd(&self, i: usize) -> Vector3<f64> {
        self.state.quads[i]
            .body
            .attitude
            .inverse_transform_vector(&self.cable(i).force_on_quad_ned)
    }

    /// What quad `i`'s accelerometer reads: `R^T (a - g)` in body FRD, m/s^2, with `a` the
    /// mean NED acceleration over the last step (a delta-velocity IMU) and `g = (0, 0, g)`.
    /// At rest it reads `(0, 0, -g)`. Panics if `i > 1`.
    pub fn specific_force_frd(&self, i: usize) -> Vector3<f64> {
        let g = Vector3::new(0.0, 0.0, self.model.gravity);
        self.state.quads[i]
            .body
            .attitude
            .inverse_transform_vector(&(self.last_accel_ned[i] - g))
    }

    /// Mean NED acceleration of the payload over the last step, m/s^2.
    pub fn payload_acceleration_ned(&self) -> Vector3<f64> {
        self.last_accel_ned[PAYLOAD]
    }

    /// The payload's contact with the ground or a box top at the current state.
    pub fn payload_contact(&self) -> ContactReading {
        let p = &self.state.payload;
        let rot = rotation(&p.attitude.into_inner());
        let mut reading = ContactReading {
            in_contact: false,
            surface: None,
            points_in_contact: 0,
            normal_force_n: 0.0,
            friction_force_ned: Vector3::zeros(),
            friction: FrictionState::Free,
        };
        let mut largest = -1.0;
        let mut slipping = false;
        for j in 0..4 {
            let r = &self.model.points_frd[PAYLOAD][j];
            let (pos, vel) =
                point_kinematics(&p.position_ned, &p.velocity_ned, &rot, &p.rate_frd, r);
            let anchor = &self.anchors[PAYLOAD][j].xy;
            let Some(pc) =
                point_contact(&self.model.contact, &self.model.boxes, &pos, &vel, anchor)
            else {
                continue;
            };
            reading.in_contact = true;
            reading.points_in_contact += 1;
            reading.normal_force_n += pc.normal_force;
            reading.friction_force_ned.x += pc.friction.x;
            reading.friction_force_ned.y += pc.friction.y;
            slipping |= pc.saturated && pc.normal_force > 0.0;
            if pc.normal_force > largest {
                largest = pc.normal_force;
                reading.surface = Some(pc.surface);
            }
        }
        if reading.in_contact {
            reading.friction = if slipping {
                FrictionState::Slipping
            } else {
                FrictionState::Sticking
            };
        }
        reading
    }

    /// True when any landing-gear point of quad `i` touches the ground or a box top.
    /// Panics if `i > 1`.
    pub fn quad_on_ground(&self, i: usize) -> bool {
        self.quad_contact_surface(i).is_some()
    }

    /// The surface under quad `i`'s deepest landing-gear point, if any. Panics if `i > 1`.
    pub fn quad_contact_surface(&self, i: usize) -> Option<ContactSurface> {
        let q = &self.state.quads[i].body;
        let rot = rotation(&q.attitude.into_inner());
        let mut best: Option<(ContactSurface, f64)> = None;
        for r in &self.model.points_frd[i] {
            let p = q.position_ned + rot * r;
            if let Some((s, pen)) = find_surface(&p, &self.model.boxes, self.model.contact.depth) {
                if best.is_none_or(|(_, d)| pen > d) {
                    best = Some((s, pen));
                }
            }
        }
        best.map(|(s, _)| s)
    }

    /// Mechanical energy at the current state (J): kinetic, gravitational (zero at z = 0),
    /// cable and contact springs.
    pub fn energy(&self) -> Energy {
        let g = self.model.gravity;
        let c = &self.model.contact;
        let mut kinetic = 0.0;
        let mut potential = 0.0;
        let mut contact = 0.0;
        for b in 0..3 {
            let body = self.body(b);
            let m = self.model.mass[b];
            let w = &body.rate_frd;
            kinetic += 0.5 * m * body.velocity_ned.norm_squared()
                + 0.5 * w.dot(&self.model.inertia[b].component_mul(w));
            potential -= m * g * body.position_ned.z;
            if b < 2 && self.pinned[b] {
                continue;
            }
            let rot = rotation(&body.attitude.into_inner());
            for j in 0..4 {
                let p = body.position_ned + rot * self.model.points_frd[b][j];
                if let Some((_, pen)) = find_surface(&p, &self.model.boxes, c.depth) {
                    let d = p.xy() - self.anchors[b][j].xy;
                    contact += 0.5 * c.k_n * pen * pen + 0.5 * c.k_t * d.norm_squared();
                }
            }
        }
        let mut cable_elastic = 0.0;
        for i in 0..2 {
            let s = self.cable(i).stretch_m;
            if s > 0.0 {
                cable_elastic += 0.5 * self.model.cables[i].stiffness * s * s;
            }
        }
        Energy {
            kinetic_j: kinetic,
            potential_j: potential,
            cable_elastic_j: cable_elastic,
            contact_elastic_j: contact,
            total_j: kinetic + potential + cable_elastic + contact,
        }
    }
}
