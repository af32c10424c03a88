//! The plant's state and the readings the world reports about it.

use nalgebra::{UnitQuaternion, Vector3};

/// Kinematic state of one rigid body (its centre of mass).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyState {
    /// Centre of mass, NED, m.
    pub position_ned: Vector3<f64>,
    /// Centre-of-mass velocity, NED, m/s.
    pub velocity_ned: Vector3<f64>,
    /// Attitude: rotates body FRD vectors to NED (`v_ned = attitude * v_frd`).
    pub attitude: UnitQuaternion<f64>,
    /// Angular velocity in body FRD, rad/s.
    pub rate_frd: Vector3<f64>,
}

impl BodyState {
    /// At rest at `position_ned`, level (body axes along NED).
    pub fn at_rest(position_ned: Vector3<f64>) -> Self {
        BodyState {
            position_ned,
            velocity_ned: Vector3::zeros(),
            attitude: UnitQuaternion::identity(),
            rate_frd: Vector3::zeros(),
        }
    }

    pub(crate) fn is_finite(&self) -> bool {
        self.position_ned.iter().all(|v| v.is_finite())
            && self.velocity_ned.iter().all(|v| v.is_finite())
            && self.attitude.coords.iter().all(|v| v.is_finite())
            && self.rate_frd.iter().all(|v| v.is_finite())
    }
}

/// One quadrotor: its body and its four rotor speeds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadState {
    pub body: BodyState,
    /// Rotor speeds in PX4 motor order 1..4, rad/s (>= 0).
    pub rotor_speed: [f64; 4],
}

/// The whole plant at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldState {
    /// Simulated time, s.
    pub time_s: f64,
    pub quads: [QuadState; 2],
    pub payload: BodyState,
}

/// Which body an external force acts on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyId {
    Quad0,
    Quad1,
    Payload,
}

impl BodyId {
    /// `Quad0` or `Quad1` for index 0 or 1, `None` otherwise.
    pub fn quad(i: usize) -> Option<BodyId> {
        match i {
            0 => Some(BodyId::Quad0),
            1 => Some(BodyId::Quad1),
            _ => None,
        }
    }

    pub(crate) fn index(self) -> usize {
        match self {
            BodyId::Quad0 => 0,
            BodyId::Quad1 => 1,
            BodyId::Payload => 2,
        }
    }
}

/// One cable at the current state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CableReading {
    /// Tension, N (>= 0; 0 when slack).
    pub tension_n: f64,
    /// Anchor-to-anchor distance, m.
    pub length_m: f64,
    /// Distance minus rest length, m (negative when slack).
    pub stretch_m: f64,
    /// Rate of change of the distance, m/s.
    pub stretch_rate_m_s: f64,
    /// Unit vector from the drone's anchor to the payload's anchor, NED (zero if they coincide).
    pub direction_ned: Vector3<f64>,
    /// Force of the cable on the drone at its anchor, NED, N (`tension * direction`).
    pub force_on_quad_ned: Vector3<f64>,
    /// Force of the cable on the payload at its anchor, NED, N (`-force_on_quad_ned`).
    pub force_on_payload_ned: Vector3<f64>,
    /// True when the cable carries no tension.
    pub slack: bool,
}

/// What a body's contact points touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactSurface {
    /// The plane z = 0 NED.
    Ground,
    /// The top face of `WorldParams::boxes[i]`.
    Box(usize),
}

/// Friction regime of a body's contacts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionState {
    /// No point in contact.
    Free,
    /// Every contact point sticks (friction below mu N).
    Sticking,
    /// At least one contact point slides (friction at mu N).
    Slipping,
}

/// The payload's contact at the current state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactReading {
    /// True when at least one contact point penetrates a surface.
    pub in_contact: bool,
    /// Surface carrying the largest share of the normal force, if any.
    pub surface: Option<ContactSurface>,
    /// Number of contact points penetrating a surface.
    pub points_in_contact: usize,
    /// Sum of the normal forces, N (>= 0).
    pub normal_force_n: f64,
    /// Sum of the friction forces, NED (horizontal), N.
    pub friction_force_ned: Vector3<f64>,
    pub friction: FrictionState,
}

/// Mechanical energy of the plant, J. Rotor kinetic energy is not included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Energy {
    /// Translational plus rotational kinetic energy of the three bodies.
    pub kinetic_j: f64,
    /// Gravitational potential `sum m g (-z)` (zero at the ground).
    pub potential_j: f64,
    /// Elastic energy of the stretched cables `sum k s^2 / 2`.
    pub cable_elastic_j: f64,
    /// Elastic energy in the contact springs (normal and tangential anchors).
    pub contact_elastic_j: f64,
    /// Sum of the above.
    pub total_j: f64,
}
