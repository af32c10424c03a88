//! Constants derived once from [`WorldParams`] in the form the per-step code wants, and the
//! force laws: rotor wrench, cable, point contact. Pure functions, no allocation.

use nalgebra::{Vector2, Vector3};

use super::state::ContactSurface;
use super::world_params::WorldParams;

/// Index of the payload in per-body arrays (quads are 0 and 1).
pub(crate) const PAYLOAD: usize = 2;

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

/// One quad's rotors and motors.
#[derive(Debug, Clone)]
pub(crate) struct RotorModel {
    pub positions_frd: [Vector3<f64>; 4],
    pub spin: [f64; 4],
    pub thrust_coeff: f64,
    pub moment_constant: f64,
    pub max_speed: f64,
    pub tau_up: f64,
    pub tau_down: f64,
    pub drag: f64,
}

/// One cable's constants.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CableModel {
    pub rest_length: f64,
    pub stiffness: f64,
    pub damping: f64,
}

/// Contact constants (per point).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ContactModel {
    pub k_n: f64,
    pub c_n: f64,
    pub mu: f64,
    pub k_t: f64,
    pub c_t: f64,
    pub depth: f64,
}

/// The top face of a box as the contact code uses it (NED).
#[derive(Debug, Clone, Copy)]
pub(crate) struct BoxTop {
    pub min_x: f64,
    pub max_x: f64,
    pub min_y: f64,
    pub max_y: f64,
    pub top_z: f64,
}

/// Everything constant during a run; index 0, 1 = quads, 2 = payload.
#[derive(Debug, Clone)]
pub(crate) struct Model {
    pub mass: [f64; 3],
    pub inertia: [Vector3<f64>; 3],
    pub inv_inertia: [Vector3<f64>; 3],
    /// Contact points of each body, body FRD.
    pub points_frd: [[Vector3<f64>; 4]; 3],
    pub rotors: [RotorModel; 2],
    /// Cable anchors on quad i, body FRD.
    pub quad_anchor_frd: [Vector3<f64>; 2],
    /// Cable anchors on the payload, payload body FRD.
    pub payload_anchor_frd: [Vector3<f64>; 2],
    pub cables: [CableModel; 2],
    pub contact: ContactModel,
    pub boxes: Vec<BoxTop>,
    /// Smallest NED z of any contact surface (ground or box top): nothing touches above it.
    pub highest_surface_z: f64,
    pub gravity: f64,
}

impl Model {
    /// Derives the constants; `params` must have been validated.
    pub fn new(params: &WorldParams) -> Model {
        let q = &params.quads;
        let p = &params.payload;
        let inertia = [
            v3(q[0].inertia_diag_kg_m2),
            v3(q[1].inertia_diag_kg_m2),
            v3(p.inertia_diag_kg_m2()),
        ];
        let rotors = [0, 1].map(|i| RotorModel {
            positions_frd: q[i].rotor_positions_frd_m.map(v3),
            spin: q[i].rotor_spin,
            thrust_coeff: q[i].thrust_coeff_n_per_rad2_s2,
            moment_constant: q[i].moment_constant_m,
            max_speed: q[i].max_rotor_speed_rad_s,
            tau_up: q[i].motor_tau_up_s,
            tau_down: q[i].motor_tau_down_s,
            drag: q[i].linear_drag_n_s_per_m,
        });
        let c = &params.contact;
        Model {
            mass: [q[0].mass_kg, q[1].mass_kg, p.mass_kg],
            inv_inertia: inertia.map(|v| v.map(|x| 1.0 / x)),
            inertia,
            points_frd: [
                q[0].gear_points_frd_m.map(v3),
                q[1].gear_points_frd_m.map(v3),
                p.contact_points_frd_m.map(v3),
            ],
            rotors,
            quad_anchor_frd: [v3(q[0].cable_anchor_frd_m), v3(q[1].cable_anchor_frd_m)],
            payload_anchor_frd: p.anchors_frd_m.map(v3),
            cables: params.cables.clone().map(|c| CableModel {
                rest_length: c.rest_length_m,
                stiffness: c.stiffness_n_per_m,
                damping: c.damping_n_s_per_m,
            }),
            contact: ContactModel {
                k_n: c.normal_stiffness_n_per_m,
                c_n: c.normal_damping_n_s_per_m,
                mu: c.friction_mu,
                k_t: c.tangential_stiffness_n_per_m,
                c_t: c.tangential_damping_n_s_per_m,
                depth: c.box_top_depth_m,
            },
            boxes: params
                .boxes
                .iter()
                .map(|b| BoxTop {
                    min_x: b.center_ned[0] - b.half_extents[0],
                    max_x: b.center_ned[0] + b.half_extents[0],
                    min_y: b.center_ned[1] - b.half_extents[1],
                    max_y: b.center_ned[1] + b.half_extents[1],
                    top_z: b.top_z_ned(),
                })
                .collect(),
            highest_surface_z: params
                .boxes
                .iter()
                .map(|b| b.top_z_ned())
                .fold(0.0, f64::min),
            gravity: params.gravity_m_s2,
        }
    }
}

/// Total thrust force and torque of a quad's rotors, both body FRD.
///
/// Rotor j at `r_j` pushes `(0, 0, -t_j)` with `t_j = c_t w_j^2`, giving `r_j x (0,0,-t_j) =
/// (-r_y t_j, r_x t_j, 0)` plus the reaction `(0, 0, spin_j c_m t_j)`.
pub(crate) fn rotor_wrench(r: &RotorModel, speeds: &[f64; 4]) -> (Vector3<f64>, Vector3<f64>) {
    let mut thrust = 0.0;
    let mut torque = Vector3::zeros();
    for ((w, p), spin) in speeds.iter().zip(&r.positions_frd).zip(&r.spin) {
        let t = r.thrust_coeff * w * w;
        thrust += t;
        torque.x -= p.y * t;
        torque.y += p.x * t;
        torque.z += spin * r.moment_constant * t;
    }
    (Vector3::new(0.0, 0.0, -thrust), torque)
}

/// A cable between a drone anchor and a payload anchor.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CableEval {
    pub tension: f64,
    pub length: f64,
    pub stretch: f64,
    pub stretch_rate: f64,
    /// Unit vector from the drone anchor to the payload anchor, NED.
    pub dir: Vector3<f64>,
}

/// Tension-only spring-damper: `max(0, k s + c s')` while the stretch `s > 0`, else 0.
pub(crate) fn cable_eval(
    c: &CableModel,
    quad_anchor_ned: &Vector3<f64>,
    quad_anchor_vel_ned: &Vector3<f64>,
    payload_anchor_ned: &Vector3<f64>,
    payload_anchor_vel_ned: &Vector3<f64>,
) -> CableEval {
    let delta = payload_anchor_ned - quad_anchor_ned;
    let length = delta.norm();
    let dir = if length > 1e-12 {
        delta / length
    } else {
        Vector3::zeros()
    };
    let stretch_rate = dir.dot(&(payload_anchor_vel_ned - quad_anchor_vel_ned));
    let stretch = length - c.rest_length;
    let tension = if stretch > 0.0 {
        (c.stiffness * stretch + c.damping * stretch_rate).max(0.0)
    } else {
        0.0
    };
    CableEval {
        tension,
        length,
        stretch,
        stretch_rate,
        dir,
    }
}

/// The surface a point at `p` (NED) penetrates most, and by how much (m, > 0).
pub(crate) fn find_surface(
    p: &Vector3<f64>,
    boxes: &[BoxTop],
    depth: f64,
) -> Option<(ContactSurface, f64)> {
    let mut best = if p.z > 0.0 {
        Some((ContactSurface::Ground, p.z))
    } else {
        None
    };
    for (i, b) in boxes.iter().enumerate() {
        let pen = p.z - b.top_z;
        if pen > 0.0
            && pen < depth
            && p.x >= b.min_x
            && p.x <= b.max_x
            && p.y >= b.min_y
            && p.y <= b.max_y
            && best.is_none_or(|(_, d)| pen > d)
        {
            best = Some((ContactSurface::Box(i), pen));
        }
    }
    best
}

/// A contact point touching a surface.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PointContact {
    pub surface: ContactSurface,
    /// Normal force, N, >= 0 (pushes along -z NED).
    pub normal_force: f64,
    /// Friction force, NED x and y, N.
    pub friction: Vector2<f64>,
    /// True when the anchored spring asked for more than mu N (the point slides).
    pub saturated: bool,
}

impl PointContact {
    /// The contact force on the body at the point, NED, N.
    pub fn force_ned(&self) -> Vector3<f64> {
        Vector3::new(self.friction.x, self.friction.y, -self.normal_force)
    }
}

/// Contact force at a body point at `p` moving with `v` (NED), whose friction anchor is at
/// `anchor_xy` (NED x, y). `None` if the point touches nothing.
pub(crate) fn point_contact(
    c: &ContactModel,
    boxes: &[BoxTop],
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    anchor_xy: &Vector2<f64>,
) -> Option<PointContact> {
    let (surface, penetration) = find_surface(p, boxes, c.depth)?;
    let normal_force = (c.k_n * penetration + c.c_n * v.z).max(0.0);
    let trial = -c.k_t * (p.xy() - anchor_xy) - c.c_t * v.xy();
    let limit = c.mu * normal_force;
    let magnitude = trial.norm();
    let saturated = magnitude > limit;
    let friction = if saturated {
        if magnitude > 0.0 {
            trial * (limit / magnitude)
        } else {
            Vector2::zeros()
        }
    } else {
        trial
    };
    Some(PointContact {
        surface,
        normal_force,
        friction,
        saturated,
    })
}
