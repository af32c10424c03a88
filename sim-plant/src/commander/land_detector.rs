//! PX4's multicopter land detector (src/modules/land_detector/MulticopterLandDetector.cpp,
//! LandDetector.cpp), reduced to the inputs the plant has.
//!
//! Three stages, each a `systemlib::Hysteresis` that turns true only after its condition has
//! held for LNDMC_TRIG_TIME / 3 and turns false at once; each stage reads the previous step's
//! state of the one before it, so "landed" comes about LNDMC_TRIG_TIME (+2 steps) after the
//! conditions start to hold:
//!
//! - ground contact: low throttle (<= MPC_THR_MIN + 0.3 (MPC_THR_HOVER - MPC_THR_MIN)), no
//!   vertical movement (|vz| <= LNDMC_Z_VEL_MAX, x2.5 once maybe-landed), no horizontal movement
//!   (|v_xy| <= LNDMC_XY_VEL_MAX) and, in climb-rate-controlled modes, a commanded descent
//!   (until maybe-landed);
//! - maybe landed: minimal throttle (MPC_THR_MIN + 0.1 (hover - min) in climb-rate-controlled
//!   modes, MPC_MANTHR_MIN + 0.01 otherwise), no free fall, roll/pitch rate <= LNDMC_ROT_MAX
//!   (x2.5 once maybe-landed), ground contact;
//! - landed: maybe landed.
//!
//! Free fall: specific force below LNDMC_FFALL_THR (2 m/s^2) for LNDMC_FFALL_TTRI (0.3 s).
//! Disarmed, every stage reads true.
//!
//! The plant's reduction: in offboard the commander knows the throttle (the setpoint's
//! thrust) and uses it. In the position-controlled modes (Position, Hold, Land) PX4's
//! position controller makes the thrust, which the commander does not see; there the plant's
//! `ground_contact` hint (physics says the vehicle rests on something) stands in for the
//! low/minimal-throttle tests, since on the ground PX4's controller winds its thrust down.
//! Commanded descent is "in Land mode" (MPC_LAND_SPEED is above PX4's descent threshold).

use nalgebra::Vector3;
use serde::Deserialize;

use super::stream::secs_to_ns;

/// Land-detector parameters (PX4 defaults).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LandDetectorParams {
    /// LNDMC_TRIG_TIME, s: total time through the three stages. Default 1.0.
    pub trigger_time_s: f64,
    /// LNDMC_Z_VEL_MAX, m/s. Default 0.25.
    pub z_vel_max_mps: f64,
    /// LNDMC_XY_VEL_MAX, m/s. Default 1.5.
    pub xy_vel_max_mps: f64,
    /// LNDMC_ROT_MAX, deg/s. Default 20.
    pub rot_max_deg_s: f64,
    /// MPC_THR_MIN (normalised). Default 0.12.
    pub thr_min: f64,
    /// MPC_THR_HOVER (normalised). Default 0.5.
    pub thr_hover: f64,
    /// MPC_MANTHR_MIN (normalised). Default 0.08.
    pub man_thr_min: f64,
    /// LNDMC_FFALL_THR, m/s^2. Default 2.0.
    pub freefall_acc_mps2: f64,
    /// LNDMC_FFALL_TTRI, s. Default 0.3.
    pub freefall_time_s: f64,
}

impl Default for LandDetectorParams {
    fn default() -> Self {
        LandDetectorParams {
            trigger_time_s: 1.0,
            z_vel_max_mps: 0.25,
            xy_vel_max_mps: 1.5,
            rot_max_deg_s: 20.0,
            thr_min: 0.12,
            thr_hover: 0.5,
            man_thr_min: 0.08,
            freefall_acc_mps2: 2.0,
            freefall_time_s: 0.3,
        }
    }
}

impl LandDetectorParams {
    /// Every value with its key, for validation.
    pub(crate) fn entries(&self) -> [(&'static str, f64); 9] {
        [
            ("land_detector.trigger_time_s", self.trigger_time_s),
            ("land_detector.z_vel_max_mps", self.z_vel_max_mps),
            ("land_detector.xy_vel_max_mps", self.xy_vel_max_mps),
            ("land_detector.rot_max_deg_s", self.rot_max_deg_s),
            ("land_detector.thr_min", self.thr_min),
            ("land_detector.thr_hover", self.thr_hover),
            ("land_detector.man_thr_min", self.man_thr_min),
            ("land_detector.freefall_acc_mps2", self.freefall_acc_mps2),
            ("land_detector.freefall_time_s", self.freefall_time_s),
        ]
    }
}

/// PX4's `systemlib::Hysteresis` with a delay only on the false -> true transition.
#[derive(Debug, Clone, Copy)]
struct Hysteresis {
    state: bool,
    requested: bool,
    requested_at_ns: u64,
    delay_to_true_ns: u64,
}

impl Hysteresis {
    fn new(state: bool, delay_to_true_ns: u64) -> Self {
        Hysteresis {
            state,
            requested: state,
            requested_at_ns: 0,
            delay_to_true_ns,
        }
    }

    fn update(&mut self, condition: bool, t_ns: u64) {
        if condition != self.state {
            if condition != self.requested {
                self.requested = condition;
                self.requested_at_ns = t_ns;
            }
        } else {
            self.requested = self.state;
        }
        if self.requested != self.state {
            let elapsed = t_ns.saturating_sub(self.requested_at_ns);
            if !self.requested || elapsed >= self.delay_to_true_ns {
                self.state = self.requested;
            }
        }
    }
}

/// What the land detector looks at in one step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LandInputs {
    pub armed: bool,
    /// The mode flies PX4's position controller (climb rate controlled).
    pub climb_rate_controlled: bool,
    /// A descent is commanded (Land mode).
    pub in_descend: bool,
    /// Throttle (normalised collective thrust) when the commander sets it, else `None`.
    pub throttle: Option<f64>,
    /// Physics says the vehicle rests on something.
    pub ground_contact_hint: bool,
    pub velocity_ned: Vector3<f64>,
    pub rate_frd: Vector3<f64>,
    pub specific_force_frd: Vector3<f64>,
}

/// The three-stage detector plus free fall.
#[derive(Debug, Clone)]
pub struct LandDetector {
    params: LandDetectorParams,
    freefall: Hysteresis,
    ground_contact: Hysteresis,
    maybe_landed: Hysteresis,
    landed: Hysteresis,
}

impl LandDetector {
    /// A detector in PX4's initial state: landed, maybe landed, ground contact; no free fall.
    pub fn new(params: LandDetectorParams) -> Self {
        let stage_ns = secs_to_ns(params.trigger_time_s / 3.0);
        let freefall_ns = secs_to_ns(params.freefall_time_s);
        LandDetector {
            params,
            freefall: Hysteresis::new(false, freefall_ns),
            ground_contact: Hysteresis::new(true, stage_ns),
            maybe_landed: Hysteresis::new(true, stage_ns),
            landed: Hysteresis::new(true, stage_ns),
        }
    }

    /// The detector of a vehicle already flying (a scenario that starts in the air): not
    /// landed, no ground contact.
    pub fn airborne(params: LandDetectorParams) -> Self {
        let mut d = Self::new(params);
        for h in [&mut d.ground_contact, &mut d.maybe_landed, &mut d.landed] {
            *h = Hysteresis::new(false, h.delay_to_true_ns);
        }
        d
    }

    pub(crate) fn update(&mut self, t_ns: u64, input: &LandInputs) {
        let p = &self.params;
        let freefall = input.specific_force_frd.norm() < p.freefall_acc_mps2;
        let (ground_contact, maybe_landed, landed) = if input.armed {
            (
                self.ground_contact_condition(input),
                self.maybe_landed_condition(input),
                self.maybe_landed.state,
            )
        } else {
            (true, true, true)
        };
        self.freefall.update(freefall, t_ns);
        self.ground_contact.update(ground_contact, t_ns);
        self.maybe_landed.update(maybe_landed, t_ns);
        self.landed.update(landed, t_ns);
    }

    fn ground_contact_condition(&self, input: &LandInputs) -> bool {
        let p = &self.params;
        let low_throttle_level = p.thr_min + (p.thr_hover - p.thr_min) * 0.3;
        let mut contact = match input.throttle {
            Some(throttle) => throttle <= low_throttle_level,
            None => input.ground_contact_hint,
        };
        if input.climb_rate_controlled && !self.maybe_landed.state && !self.landed.state {
            contact &= input.in_descend;
        }
        let widen = if self.maybe_landed.state { 2.5 } else { 1.0 };
        let vertical = input.velocity_ned.z.abs() > p.z_vel_max_mps * widen;
        let horizontal = input.velocity_ned.xy().norm() > p.xy_vel_max_mps;
        contact && !vertical && !horizontal
    }

    fn maybe_landed_condition(&self, input: &LandInputs) -> bool {
        let p = &self.params;
        let min_level = if input.climb_rate_controlled {
            p.thr_min + (p.thr_hover - p.thr_min) * 0.1
        } else {
            p.man_thr_min + 0.01
        };
        let minimal_throttle = match input.throttle {
            Some(throttle) => throttle <= min_level,
            None => input.ground_contact_hint,
        };
        if !minimal_throttle || self.freefall.state {
            return false;
        }
        let widen = if self.maybe_landed.state { 2.5 } else { 1.0 };
        let rotating = input.rate_frd.xy().norm() > p.rot_max_deg_s.to_radians() * widen;
        !rotating && self.ground_contact.state
    }

    /// PX4 `vehicle_land_detected.landed`.
    pub fn landed(&self) -> bool {
        self.landed.state
    }

    /// PX4 `vehicle_land_detected.maybe_landed`.
    pub fn maybe_landed(&self) -> bool {
        self.maybe_landed.state
    }

    /// PX4 `vehicle_land_detected.ground_contact`.
    pub fn ground_contact(&self) -> bool {
        self.ground_contact.state
    }

    /// PX4 `vehicle_land_detected.freefall`.
    pub fn freefall(&self) -> bool {
        self.freefall.state
    }
}

#[cfg(test)]
#[path = "land_detector_tests.rs"]
mod tests;
