//! The study's table: per configuration (law × tension source), the mean and spread over seeds
//! of each flight metric, as markdown and CSV.

use std::fmt::Write as _;

/// What one fast Test A flight gave, reduced to the study's columns (per-drone metrics are the
/// mean of the two drones).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunMetrics {
    pub law: String,
    pub source: String,
    pub seed: u64,
    /// RMS of the payload swing from the drop to the end, deg.
    pub swing_rms_deg: Option<f64>,
    /// From the drop until the swing stays below 2°, s (None: never settled).
    pub settling_s: Option<f64>,
    /// Mean over the drones of |z steady-state error| in the Move phase, m.
    pub z_steady_state_m: Option<f64>,
    /// Mean over the drones of the position RMSE against the nominal setpoint, m.
    pub position_rmse_m: Option<f64>,
    /// Mean over the drones of the RMSE (norm) of the tension source's raw force against the
    /// true anchor force, N (sensor or estimator, body FRD; 0 for the truth source).
    pub force_rmse_n: Option<f64>,
    /// The same for the low-pass filtered force the controller acted on (NED), N: includes
    /// the filter's lag, so not 0 for the truth source.
    pub used_force_rmse_n: Option<f64>,
    /// Largest cable force, N.
    pub max_cable_force_n: Option<f64>,
    pub crashed: bool,
    /// The scenario completed (every phase ended, no failsafe or crash).
    pub completed: bool,
}

/// Mean, sample standard deviation and count of the values present.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stat {
    pub mean: f64,
    pub sd: f64,
    pub n: usize,
}

impl Stat {
    pub fn of(values: impl IntoIterator<Item = Option<f64>>) -> Option<Stat> {
        let v: Vec<f64> = values
            .into_iter()
            .flatten()
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            return None;
        }
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Some(Stat { mean, sd, n })
    }
}

/// One column of the table.
struct Column {
    title: &'static str,
    csv: &'static str,
    decimals: usize,
    get: fn(&RunMetrics) -> Option<f64>,
}

const COLUMNS: [Column; 7] = [
    Column {
        title: "swing RMS after drop (deg)",
        csv: "swing_rms_deg",
        decimals: 2,
        get: |r| r.swing_rms_deg,
    },
    Column {
        title: "settling (s)",
        csv: "settling_s",
        decimals: 1,
        get: |r| r.settling_s,
    },
    Column {
        title: "z steady-state (m)",
        csv: "z_steady_state_m",
        decimals: 3,
        get: |r| r.z_steady_state_m,
    },
    Column {
        title: "position RMSE (m)",
        csv: "position_rmse_m",
        decimals: 3,
        get: |r| r.position_rmse_m,
    },
    Column {
        title: "source force RMSE vs truth (N)",
        csv: "force_rmse_n",
        decimals: 2,
        get: |r| r.force_rmse_n,
    },
    Column {
        title: "filtered force used vs truth (N)",
        csv: "used_force_rmse_n",
        decimals: 2,
        get: |r| r.used_force_rmse_n,
    },
    Column {
        title: "max cable force (N)",
        csv: "max_cable_force_n",
        decimals: 1,
        get: |r| r.max_cable_force_n,
    },
];

/// The configurations in first-seen order.
fn configs(runs: &[RunMetrics]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for r in runs {
        let key = (r.law.clone(), r.source.clone());
        if !out.contains(&key) {
            out.push(key);
        }
    }
    out
}

fn runs_of<'a>(runs: &'a [RunMetrics], law: &str, source: &str) -> Vec<&'a RunMetrics> {
    runs.iter()
        .filter(|r| r.law == law && r.source == source)
        .collect()
}

/// The markdown table: `mean ± sd` per cell, with `(k/N)` when only k of N runs had a value
/// (e.g. settled), and the crashed and completed counts.
pub fn markdown(runs: &[RunMetrics]) -> String {
    let mut s = String::from("| controller | tension source | seeds |");
    for c in &COLUMNS {
        let _ = write!(s, " {} |", c.title);
    }
    s.push_str(" crashed | completed |\n|---|---|---|");
    for _ in &COLUMNS {
        s.push_str("---|");
    }
    s.push_str("---|---|\n");
    for (law, source) in configs(runs) {
        let rs = runs_of(runs, &law, &source);
        let _ = write!(s, "| {law} | {source} | {} |", rs.len());
        for c in &COLUMNS {
            let cell = match Stat::of(rs.iter().map(|r| (c.get)(r))) {
                None => "—".to_string(),
                Some(st) => {
                    let mut t = format!("{:.*} ± {:.*}", c.decimals, st.mean, c.decimals, st.sd);
                    if st.n < rs.len() {
                        let _ = write!(t, " ({}/{})", st.n, rs.len());
                    }
                    t
                }
            };
            let _ = write!(s, " {cell} |");
        }
        let crashed = rs.iter().filter(|r| r.crashed).count();
        let completed = rs.iter().filter(|r| r.completed).count();
        let _ = writeln!(s, " {crashed}/{} | {completed}/{} |", rs.len(), rs.len());
    }
    s
}

/// The CSV: one row per configuration, `<metric>_mean,<metric>_sd,<metric>_n` per metric.
pub fn csv(runs: &[RunMetrics]) -> String {
    let mut s = String::from("controller,tension_source,seeds");
    for c in &COLUMNS {
        let _ = write!(s, ",{0}_mean,{0}_sd,{0}_n", c.csv);
    }
    s.push_str(",crashed,completed\n");
    for (law, source) in configs(runs) {
        let rs = runs_of(runs, &law, &source);
        let _ = write!(s, "{law},{source},{}", rs.len());
        for c in &COLUMNS {
            match Stat::of(rs.iter().map(|r| (c.get)(r))) {
                Some(st) => {
                    let _ = write!(s, ",{},{},{}", st.mean, st.sd, st.n);
                }
                None => s.push_str(",,,0"),
            }
        }
        let crashed = rs.iter().filter(|r| r.crashed).count();
        let completed = rs.iter().filter(|r| r.completed).count();
        let _ = writeln!(s, ",{crashed},{completed}");
    }
    s
}

/// Every run, one CSV row each (for anyone who wants the raw numbers).
pub fn runs_csv(runs: &[RunMetrics]) -> String {
    let mut s = String::from("controller,tension_source,seed");
    for c in &COLUMNS {
        let _ = write!(s, ",{}", c.csv);
    }
    s.push_str(",crashed,completed\n");
    let opt = |x: Option<f64>| x.map(|v| v.to_string()).unwrap_or_default();
    for r in runs {
        let _ = write!(s, "{},{},{}", r.law, r.source, r.seed);
        for c in &COLUMNS {
            let _ = write!(s, ",{}", opt((c.get)(r)));
        }
        let _ = writeln!(s, ",{},{}", r.crashed, r.completed);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(law: &str, source: &str, seed: u64, swing: f64, settled: Option<f64>) -> RunMetrics {
        RunMetrics {
            law: law.into(),
            source: source.into(),
            seed,
            swing_rms_deg: Some(swing),
            settling_s: settled,
            crashed: seed == 3,
            completed: seed != 3,
            ..Default::default()
        }
    }

    #[test]
    fn mean_and_sample_sd() {
        let st = Stat::of([Some(1.0), Some(2.0), None, Some(3.0), Some(f64::NAN)]).expect("stat");
        assert_eq!((st.mean, st.n), (2.0, 3));
        assert!((st.sd - 1.0).abs() < 1e-12);
        assert_eq!(Stat::of([None]), None);
    }

    #[test]
    fn table_rows_cells_and_counts() {
        let runs = vec![
            run("proposed", "sensor", 1, 6.0, Some(9.0)),
            run("proposed", "sensor", 2, 8.0, None),
            run("proposed", "sensor", 3, 7.0, Some(11.0)),
            run("geometric", "truth", 1, 20.0, None),
        ];
        let md = markdown(&runs);
        let rows: Vec<&str> = md.lines().collect();
        assert_eq!(rows.len(), 4, "{md}");
        assert!(
            rows[2].starts_with("| proposed | sensor | 3 | 7.00 ± 1.00 | 10.0 ± 1.4 (2/3) |"),
            "{}",
            rows[2]
        );
        assert!(rows[2].ends_with("| 1/3 | 2/3 |"), "{}", rows[2]);
        assert!(rows[3].contains("| 20.00 ± 0.00 | — |"), "{}", rows[3]);
        let c = csv(&runs);
        assert!(
            c.lines()
                .nth(1)
                .expect("row")
                .starts_with("proposed,sensor,3,7,1,3,10,1.4142135623730951,2"),
            "{c}"
        );
        assert_eq!(runs_csv(&runs).lines().count(), 5);
    }
}
