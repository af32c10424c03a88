//! Fast mode: the plant and its pilot in one thread, in simulated time, as fast as the CPU
//! allows. The same `Plant` as the real-time process; only the clock differs.

use std::fmt;
use std::time::Instant;

use serde::Serialize;

use crate::inner_loops::PositionControlParams;
use crate::pilot::ScenarioPilot;
use crate::plant::{Plant, PlantConfig, PlantError};
use crate::scenario::Scenario;

/// When a phase started, s of simulated time.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseStart {
    pub name: String,
    pub start_s: f64,
}

/// What a fast run did and how fast.
#[derive(Debug, Clone, Serialize)]
pub struct FastReport {
    pub scenario: String,
    pub seed: u64,
    pub noise: bool,
    /// Simulated time, s.
    pub sim_s: f64,
    /// Wall-clock time, s.
    pub wall_s: f64,
    /// sim_s / wall_s.
    pub speedup: f64,
    pub phases: Vec<PhaseStart>,
    pub completed: bool,
    pub timed_out: bool,
    pub failsafe_count: [u32; 2],
    pub crash_flags: [u32; 2],
    /// Largest cable tension seen, N.
    pub max_cable_tension_n: f64,
    /// When the payload first left its contact, s (None if it never rested or never left).
    pub payload_lifted_at_s: Option<f64>,
}

impl fmt::Display for FastReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{} (seed {}, noise {}): {:.1} s simulated in {:.3} s wall = {:.0}x real time",
            self.scenario,
            self.seed,
            if self.noise { "on" } else { "off" },
            self.sim_s,
            self.wall_s,
            self.speedup
        )?;
        for p in &self.phases {
            writeln!(f, "  phase {:<8} at {:6.2} s", p.name, p.start_s)?;
        }
        write!(
            f,
            "  completed {}, timed out {}, failsafes {:?}, crash flags {:?}, max cable force {:.2} N",
            self.completed, self.timed_out, self.failsafe_count, self.crash_flags,
            self.max_cable_tension_n
        )
    }
}

/// Flies `scenario` with the plant's pilot until it completes (then `linger_s` more), a phase
/// times out, or `max_s` of simulated time pass (default: the sum of the phase timeouts).
pub fn run(
    scenario: &Scenario,
    cfg: &PlantConfig,
    max_s: Option<f64>,
) -> Result<FastReport, PlantError> {
    let mut plant = Plant::new(scenario, cfg)?;
    let pos = PositionControlParams {
        hover_throttle: cfg.inner_loops.motor_map.hover_throttle,
        ..cfg.inner_loops.position.clone()
    };
    let mut pilot =
        ScenarioPilot::new(scenario, &pos).map_err(|e| PlantError::Params(e.to_string()))?;
    let limit_s =
        max_s.unwrap_or_else(|| scenario.phases.iter().map(|p| p.timeout_s).sum::<f64>() + 5.0);
    let limit_ns = (limit_s * 1e9) as u64;
    let mut max_tension: f64 = 0.0;
    let mut lifted_at = None;
    let mut was_in_contact = false;
    let mut done_at_ns: Option<u64> = None;
    let linger_ns = (scenario.linger_s.max(0.0) * 1e9) as u64;
    let wall = Instant::now();
    while plant.time_ns() < limit_ns {
        plant.step();
        pilot.on_step(&mut plant);
        let w = plant.world();
        max_tension = max_tension
            .max(w.cable(0).tension_n)
            .max(w.cable(1).tension_n);
        if w.payload_contact().in_contact {
            was_in_contact = true;
        } else if was_in_contact && lifted_at.is_none() {
            lifted_at = Some(plant.time_ns() as f64 * 1e-9);
        }
        if pilot.finished() && done_at_ns.is_none() {
            done_at_ns = Some(plant.time_ns());
        }
        if done_at_ns.is_some_and(|d| plant.time_ns() >= d + linger_ns) {
            break;
        }
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let sim_s = plant.time_ns() as f64 * 1e-9;
    let starts = pilot.tracker().phase_starts_s();
    Ok(FastReport {
        scenario: scenario.name.clone(),
        seed: cfg.seed,
        noise: cfg.perturbation_enabled,
        sim_s,
        wall_s,
        speedup: sim_s / wall_s.max(1e-9),
        phases: scenario
            .phases
            .iter()
            .zip(starts)
            .filter(|(_, s)| s.is_finite())
            .map(|(p, s)| PhaseStart {
                name: p.name.clone(),
                start_s: *s,
            })
            .collect(),
        completed: pilot.completed(),
        timed_out: pilot.finished() && !pilot.completed(),
        failsafe_count: plant.failsafe_count(),
        crash_flags: plant.crash_flags(),
        max_cable_tension_n: max_tension,
        payload_lifted_at_s: lifted_at,
    })
}
