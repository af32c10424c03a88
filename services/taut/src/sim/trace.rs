//! `taut sim --fast --trace FILE`: every controller step of both drones as CSV, for plots.

use shared_types::{AttitudeSetpoint, PlantTruth, VehicleState};

/// A CSV of every controller step, for looking at a flight.
pub struct Trace {
    out: std::io::BufWriter<std::fs::File>,
}

impl Trace {
    pub fn create(path: &std::path::Path) -> Result<Self, String> {
        use std::io::Write;
        let f = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut out = std::io::BufWriter::new(f);
        writeln!(
            out,
            "t_s,drone,phase,flags,x,y,z,true_x,true_y,true_z,nom_x,nom_y,nom_z,sh_x,sh_y,sh_z,\
             td_x,td_y,td_z,tf_x,tf_y,tf_z,ad_x,ad_y,ad_z,thrust_n,payload_x,payload_y,payload_z,\
             cable_n"
        )
        .map_err(|e| e.to_string())?;
        Ok(Trace { out })
    }

    pub fn row(
        &mut self,
        t: u64,
        k: usize,
        s: &VehicleState,
        sp: &AttitudeSetpoint,
        truth: &PlantTruth,
    ) {
        use std::io::Write;
        let v = |a: &[f64]| {
            a.iter()
                .map(|x| format!("{x:.4}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        let _ = writeln!(
            self.out,
            "{:.3},{},{},{},{},{},{},{},{},{},{},{:.3},{},{:.3}",
            t as f64 * 1e-9,
            k,
            sp.phase as u32,
            sp.flags,
            v(&s.position_ned_m),
            v(&truth.drones[k].body.position_ned_m),
            v(&sp.nominal_position_ned_m),
            v(&sp.shifted_position_ned_m),
            v(&sp.tension_desired_ned_n),
            v(&sp.tension_filtered_ned_n),
            v(&sp.acceleration_desired_ned_m_s2),
            sp.thrust_n,
            v(&truth.payload.position_ned_m),
            truth.cable_tension_n[k],
        );
    }
}
