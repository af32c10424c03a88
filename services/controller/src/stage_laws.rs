//! The two laws behind [`ControllerStage::step`]'s common checks: the paper's cascade and the
//! geometric baseline. Each takes the filtered tension already measured into the state.

use nalgebra::{UnitQuaternion, Vector3};
use shared_types::{MissionSetpoint, VehicleState};

use super::{ControllerStage, LoopState};
use crate::geometric::{self, Reference};
use crate::loops::ShiftMode;
use crate::mapping::{map_acceleration, Mapped, ThrustLimit};

/// What a law hands the common tail of a step.
pub(super) struct LawOutput {
    /// ξ_d (the proposed law's shifted setpoint; the geometric law's ξ̄_d), NED, m.
    pub setpoint: Vector3<f64>,
    /// The proposed law's a_d; the geometric law's K_p e_p + K_v e_v + a_ref, NED, m/s².
    pub acceleration: Vector3<f64>,
    pub mapped: Mapped,
    /// A fresh tension sample entered the command.
    pub tension_used: bool,
}

impl ControllerStage {
    /// The paper's cascade from the filtered tension on: shift, position P, velocity PID,
    /// mapping, and the velocity integration against saturation. `inputs` = (loop enabled,
    /// tension fresh, integrate, dt).
    pub(super) fn proposed(
        &self,
        s: &mut LoopState,
        (enabled, fresh, integrate, dt): (bool, bool, bool, f64),
        nominal: &Vector3<f64>,
        state: &VehicleState,
        q: &UnitQuaternion<f64>,
        yaw_d: f64,
    ) -> LawOutput {
        let mode = match (enabled, fresh) {
            (false, _) => ShiftMode::Off,
            (true, true) => ShiftMode::Active,
            (true, false) => ShiftMode::Frozen,
        };
        let desired_t = s.tension_desired_ned_n;
        let shift = s
            .shift
            .step(mode, &desired_t, integrate, dt, &self.shift_gains);
        let setpoint = nominal + shift;
        let position = Vector3::from(state.position_ned_m);
        let velocity = Vector3::from(state.velocity_ned_m_s);
        let v_d = self.velocity_setpoint(&(setpoint - position));
        let e_v = v_d - velocity;
        let a_d = s.velocity.output(&e_v, &velocity, dt, &self.velocity_gains);
        let mapped = map_acceleration(&a_d, yaw_d, q, &self.mapping);
        if integrate {
            // Conditional integration: no further push into a saturated output.
            let tilt = |i: usize| mapped.tilt_limited && e_v[i] * a_d[i] > 0.0;
            let thrust = match mapped.thrust_limit {
                ThrustLimit::Max => e_v.z < 0.0,
                ThrustLimit::Min => e_v.z > 0.0,
                ThrustLimit::None => false,
            };
            let blocked = [tilt(0), tilt(1), thrust];
            s.velocity
                .integrate(&e_v, blocked, dt, &self.velocity_gains);
        }
        LawOutput {
            setpoint,
            acceleration: a_d,
            mapped,
            tension_used: mode == ShiftMode::Active,
        }
    }

    /// The geometric baseline ([`geometric`]): f_ext = −T_f while the loop is on (held while
    /// the tension is stale), none while it is off.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn geometric_law(
        &self,
        s: &LoopState,
        (enabled, fresh): (bool, bool),
        nominal: &Vector3<f64>,
        mission: Option<&MissionSetpoint>,
        state: &VehicleState,
        q: &UnitQuaternion<f64>,
        yaw_d: f64,
    ) -> LawOutput {
        let reference = Reference {
            position_m: *nominal,
            velocity_m_s: mission.map_or(Vector3::zeros(), |m| m.velocity_ned_m_s.into()),
            acceleration_m_s2: mission.map_or(Vector3::zeros(), |m| m.acceleration_ned_m_s2.into()),
            yaw_rad: yaw_d,
        };
        let f_ext = if enabled {
            -s.shift.filter.value()
        } else {
            Vector3::zeros()
        };
        let c = geometric::command(
            &self.geometric,
            &reference,
            &Vector3::from(state.position_ned_m),
            &Vector3::from(state.velocity_ned_m_s),
            &f_ext,
            q,
            &self.mapping,
        );
        LawOutput {
            setpoint: *nominal,
            acceleration: c.tracking_m_s2,
            mapped: c.mapped,
            tension_used: enabled && fresh,
        }
    }
}

#[cfg(test)]
#[path = "stage_geometric_tests.rs"]
mod tests;
