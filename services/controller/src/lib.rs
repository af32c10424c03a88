//! taut's tension-aware cascade controller (paper section IV, gains V.C), one per drone.
//!
//! Position P -> setpoint shifted by the cable tension -> velocity PID -> thrust and attitude,
//! at 100 Hz, handing PX4 an attitude quaternion and a collective thrust.
//!
//! # The sign of T, once for the crate
//!
//! T is the force the drone exerts **on the cable** = −(the cable's pull on the drone). The
//! tension stage publishes `TensionSample::force_body_n` = the pull on the drone in body FRD,
//! so `T_ned = −R(q) · force_body_n` with q the vehicle's attitude (body FRD -> NED). A hanging
//! load has T_z < 0 (NED: the drone pulls the cable up). With e_T = T_d − T_f and positive
//! gains: a slack cable (T_f = 0, T_d,z < 0) gives e_T,z < 0, the setpoint moves to more
//! negative z, the drone climbs until the cable takes its share; a stronger pull than nominal
//! (T_f,z more negative) gives e_T,z > 0 and the drone yields (descends towards the load);
//! laterally likewise, a stronger inward pull moves the setpoint inwards. The plant test
//! (`tests/plant_sign.rs`) checks that this sign stabilises and the opposite does not.
//!
//! # The pieces
//!
//! - [`formation`]: T_d, the static tension expected at the nominal setpoints.
//! - [`mapping`]: desired acceleration and yaw -> quaternion and thrust.
//! - [`geometric`]: the paper's baseline law (`controller.law = "geometric"`), F = m (K_p e_p +
//!   K_v e_v + a_ref − g e3) − f_ext, with the same mapping, limits and input checks.
//! - [`stage`]: [`ControllerStage`], one step from the newest inputs, with the input checks.
//! - [`shell`]: the service loop (iceoryx2 topics, triggers, latency record).
//!
//! # Choices where the paper is silent
//!
//! - Low-pass filters are first order, exact for a held input (α = 1 − exp(−2π f_c dt)), seeded
//!   by their first sample; derivatives act on the filtered measurement, not on the error.
//! - Anti-windup: the tension integral contribution and the total shift are clamped per axis to
//!   `max_tension_shift_m`; the velocity integral contribution to
//!   `max_velocity_integral_m_s2`, and an axis does not integrate while its error pushes a
//!   saturated output (tilt limit: x, y; thrust limit: z). Nothing integrates on odometry
//!   older than `odometry_max_age_s` (flagged STALE_ODOMETRY).
//! - Stale tension (older than `tension_max_age_s`) with the loop on: POSITION_ONLY, the P and
//!   D parts of the shift are dropped and the integral frozen, so the setpoint keeps the
//!   integral's shift rather than jumping back to ξ̄_d. When tension returns, the filter is
//!   re-seeded (no derivative kick).
//! - Tension loop off (mission without TENSION_ENABLED, or no fresh mission): e_T is not
//!   integrated; the shift last applied (P, I and D together, so it is bumpless) decays to zero
//!   with the time constant `tension_shift_decay_s`. Switching the loop on lets the P part in
//!   at once (a step of at most `max_tension_shift_m`).
//! - Not armed: everything reset, level at the current yaw, `min_thrust_n`, IDLE.
//! - No mission younger than `mission_max_age_s`: hold the position and yaw the vehicle had
//!   when the mission went stale (latched, not re-read every step), loop off, STALE_MISSION,
//!   and no ARM_REQUEST (it is only copied from a fresh mission).
//! - The mission's velocity and acceleration are feed-forward the paper does not use: ignored
//!   by the proposed law (the geometric law tracks them).
//! - Thrust u = −F_d,z / (cos φ cos θ) with the CURRENT roll and pitch, the cosine floored at
//!   0.5 ([`mapping::MIN_TILT_COSINE`]); tilt limited with vertical priority.
//! - Any non-finite input (or a quaternion of norm outside 0.5..2) or result: level at the last
//!   commanded yaw, thrust m g, NON_FINITE; the state is not touched at all (not even the time
//!   of the last step), so the next finite step is what it would have been without it.
//! - dt comes from consecutive `now_ns`, clamped to [`stage::MIN_DT_S`, `stage::MAX_DT_S`].

pub mod filters;
pub mod formation;
pub mod geometric;
pub mod loops;
pub mod mapping;
pub mod shell;
pub mod stage;

pub use formation::{static_tension, FormationRegime, FormationTension};
pub use stage::{ControllerCounters, ControllerParamsError, ControllerStage};
