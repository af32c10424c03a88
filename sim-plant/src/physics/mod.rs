//! Rigid-body physics of the plant: two X500 quadrotors, a 1 kg box payload hanging from two
//! tension-only cables, gravity, and contact of every body with the ground and box tops.
//!
//! Frames: NED inertial (z down, gravity `+g` along z), body FRD; attitudes rotate FRD to NED.
//! Body index 0, 1 = quads, 2 = payload; cable i joins quad i's anchor to payload anchor i.
//!
//! # Equations (paper section II, plus contacts)
//!
//! `m a = R f_rotors + m g e3 + T + F_contact + F_ext (- c_drag v)` and
//! `I w' = tau_rotors + r x (R^T T) + sum r_c x (R^T F_c) - w x I w` per body (the payload has
//! no rotors). Rotor thrust `c_t w^2` along -z body; the reaction torque about +z body is
//! `spin c_m thrust` (+1 for CCW rotors 1, 2). Motor speeds follow a first-order lag toward the
//! command, solved in closed form per step (`tau` up or down chosen at the start of the step).
//! Rotor inertia and gyroscopic effects are not modelled.
//!
//! Cables: `s = |p_payload_anchor - p_quad_anchor| - L`; tension `max(0, k s + c s')` for
//! `s > 0`, else 0 (slack); the force on the quad is `T e` with `e` the unit vector from its
//! anchor to the payload's, the payload gets `-T e`. Cables have no mass and do not collide.
//!
//! # Contacts
//!
//! Four contact points per body (landing gear; payload bottom corners) against the plane
//! z = 0 and the top faces of axis-aligned boxes. A point inside a box's xy footprint and less
//! than `box_top_depth_m` below its top is pushed up; box sides are not modelled (a body
//! flying into a side passes through), nor body-body contact; a quad has contact points on its
//! landing gear only (upside down it sinks through the ground to its gear: crashes are out of
//! scope). Normal force
//! `max(0, k_n pen + c_n pen')` along -z. Friction is stick-slip with an anchored tangential
//! spring per point: the trial force `-k_t (p_xy - anchor) - c_t v_xy` is used while its size
//! is below `mu N` (sticking: no creep, only the spring's elastic deflection), else it is scaled
//! to `mu N` (sliding). The anchors are held fixed during a step and updated after it: a point
//! whose anchor spring alone exceeds `mu N` has its anchor dragged to where it gives exactly
//! `mu N`; a point that leaves contact re-anchors where it next touches.
//!
//! # Integrator
//!
//! Default: classical RK4 at `max_substep_s` = 0.5 ms (longer `step`s are split), the rotor
//! speeds exact at the RK4 stage times, friction anchors updated once per sub-step,
//! quaternions renormalised after every sub-step. The stiffest modes are the payload rocking on
//! its contact points (~440 rad/s, overdamped, fastest eigenvalue about -1500 1/s: h |lambda|
//! ~0.75, inside RK4's real-axis limit of 2.78) and the cables (55-85 rad/s: h w ~0.04).
//!
//! Measured on the undamped 3-degree free swing of the payload between two pinned quads
//! (`tests/physics_closed_form.rs`, 20 s at h = 0.5 ms), worst |E(t) - E(0)| relative to the
//! swing energy: RK4 3e-10 %, semi-implicit (symplectic) Euler 0.07 % (bounded oscillation, no
//! secular drift). Both give the swing period within 0.02 % of the double-pendulum formula
//! (the residue is the finite-amplitude correction, theta^2/16). Cost of a hanging-payload
//! hover step (`examples/physics_speed.rs`, release, this shared 2-core machine): RK4 1.2-1.7
//! us, semi-implicit Euler 0.6-1.0 us. RK4 is the default: its error is orders of magnitude smaller
//! (contact and cable transients, energy), and it fits the 3 us budget;
//! `Integrator::SemiImplicitEuler` stays selectable for comparison.
//!
//! Everything is deterministic; `World::step` does not allocate.

mod dynamics;
pub mod formation;
mod model;
pub mod params;
mod readings;
pub mod state;
pub mod world;
pub mod world_params;

pub use formation::{hanging_formation, HangingFormation};
pub use params::{CableParams, ParamsError, PayloadParams, QuadParams};
pub use state::{
    BodyId, BodyState, CableReading, ContactReading, ContactSurface, Energy, FrictionState,
    QuadState, WorldState,
};
pub use world::{World, WorldError, MAX_SUBSTEPS_PER_STEP};
pub use world_params::{BoxObstacle, ContactParams, Integrator, WorldParams};

#[cfg(test)]
mod tests;
