//! `summary.json` and its printed form.

use super::metrics::FlightMetrics;
use serde::Serialize;
use std::fmt;
use std::path::Path;

#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub scenario: String,
    pub seed: u64,
    /// Motion-capture position perturbation on.
    pub noise: bool,
    /// `real-time` or `fast`.
    pub mode: &'static str,
    /// Both drones' `controller.law` and `controller.tension_source`.
    pub law: &'static str,
    pub tension_source: &'static str,
    /// Every phase ended, no crash, no failsafe, no service died.
    pub success: bool,
    pub failure: Option<String>,
    /// Simulated time flown, s.
    pub sim_s: f64,
    pub wall_s: f64,
    #[serde(flatten)]
    pub metrics: FlightMetrics,
}

impl Summary {
    pub fn write(&self, out: &Path) -> Result<(), String> {
        let p = out.join("summary.json");
        let text = serde_json::to_string_pretty(self).map_err(|e| e.to_string())?;
        std::fs::write(&p, text + "\n").map_err(|e| format!("{}: {e}", p.display()))
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |x| format!("{x:.digits$}"))
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.metrics;
        writeln!(
            f,
            "{} seed {} ({}, noise {}, {} law, {} tension): {} after {:.1} s simulated in {:.1} s",
            self.scenario,
            self.seed,
            self.mode,
            if self.noise { "on" } else { "off" },
            self.law,
            self.tension_source,
            match &self.failure {
                None => "SUCCESS".to_string(),
                Some(why) => format!("FAILED: {why}"),
            },
            self.sim_s,
            self.wall_s
        )?;
        for d in &m.drones {
            writeln!(
                f,
                "  {}: position RMSE {} m, z steady-state error {} m, tension RMSE {} N, final error {} m, failsafes {}, crash flags {}",
                d.id,
                opt(d.position_rmse_m, 3),
                opt(d.z_steady_state_error_m, 3),
                opt(d.tension_rmse_n, 2),
                opt(d.final_position_error_m, 3),
                d.failsafe_count,
                d.crash_flags
            )?;
        }
        for d in &m.drones {
            let r = &d.force_rmse;
            let show = |a: &Option<super::force_metrics::AxisRmse>| {
                a.map_or("-".into(), |a| {
                    format!("{:.2} ({:.2}, {:.2}, {:.2})", a.norm, a.x, a.y, a.z)
                })
            };
            writeln!(
                f,
                "  {} force RMSE vs truth, N (norm (x, y, z)): sensor {} FRD, estimator {} FRD, used {} NED",
                d.id,
                show(&r.sensor_frd_n),
                show(&r.estimator_frd_n),
                show(&r.used_ned_n)
            )?;
        }
        let p = &m.payload;
        writeln!(
            f,
            "  payload: lifted at {} s, swing RMS {}°, max {}°, settles below 2° after {} s; max cable force {:.2} N",
            opt(p.lifted_at_s, 2),
            opt(p.swing_rms_deg, 2),
            opt(p.swing_max_deg, 2),
            opt(p.settling_time_s, 2),
            m.max_cable_force_n
        )?;
        for (span, pc) in &m.latency_us {
            writeln!(
                f,
                "  latency {span}: p50 {:.0} µs, p99 {:.0} µs, p99.9 {:.0} µs, max {:.0} µs (n = {})",
                pc.p50, pc.p99, pc.p999, pc.max, pc.count
            )?;
        }
        Ok(())
    }
}
