//! The flight's metrics from a recording: the recorded truth, mission setpoints and attitude
//! setpoints fed into `sim::metrics::MetricsRecorder` in the order the recorder took them, as
//! the live monitor feeds it, so any recording (real time or fast) yields `summary.json`'s
//! metrics.

use crate::sim::metrics::{FlightMetrics, MetricsRecorder};
use rt_config::{Config, VehicleConfig};
use shared_types::MissionPhase;
use sim_plant::scenario::{PhaseKind, Scenario};

use super::load::FlightData;

/// What the recorder is built with, and where that came from.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricsSetup {
    pub ids: [String; 2],
    pub phase_names: Vec<String>,
    pub phase_is_move: Vec<bool>,
    /// Cable anchor in body FRD, m (swing angle).
    pub anchor_frd_m: [f64; 3],
}

/// Phases and anchor from the first drone's recorded config (its scenario), else from the
/// recorded mission setpoints and the default vehicle; notes say which.
pub fn setup(f: &FlightData, notes: &mut Vec<String>) -> MetricsSetup {
    let id = |k: usize| {
        f.drones
            .get(k)
            .map_or(format!("uav{}", k + 1), |d| d.id.clone())
    };
    let ids = [id(0), id(1)];
    let cfg = f.drones.iter().find_map(|d| {
        let text = f.config_text(&d.id)?;
        match Config::from_toml_str(text, &format!("config/{}.toml", d.id)) {
            Ok(c) => Some(c),
            Err(e) => {
                notes.push(format!("recorded config of {} not usable: {e}", d.id));
                None
            }
        }
    });
    let anchor_frd_m = match &cfg {
        Some(c) => c.vehicle.anchor_offset_frd_m,
        None => {
            notes.push("no recorded config: the cable anchor is the default vehicle's".into());
            VehicleConfig::default().anchor_offset_frd_m
        }
    };
    let scenario = cfg
        .as_ref()
        .and_then(|c| match Scenario::load(&c.mission.scenario) {
            Ok(s) => Some(s),
            Err(e) => {
                notes.push(format!("scenario of the recorded config not loadable: {e}"));
                None
            }
        });
    let (phase_names, phase_is_move) = match scenario {
        Some(s) => (
            s.phases.iter().map(|p| p.name.clone()).collect(),
            s.phases.iter().map(|p| p.kind == PhaseKind::Move).collect(),
        ),
        None => {
            notes.push(
                "phase names and kinds taken from the recorded mission setpoints".to_string(),
            );
            recorded_phases(f)
        }
    };
    MetricsSetup {
        ids,
        phase_names,
        phase_is_move,
        anchor_frd_m,
    }
}

/// Phase names (`<index>-<phase>`) and Move flags by phase index, from the mission setpoints.
pub fn recorded_phases(f: &FlightData) -> (Vec<String>, Vec<bool>) {
    let mut by_index: Vec<Option<MissionPhase>> = Vec::new();
    for d in &f.drones {
        for m in &d.mission {
            let s = &m.sample;
            if matches!(s.phase, MissionPhase::Idle | MissionPhase::Done) {
                continue;
            }
            let i = s.phase_index as usize;
            if i >= 64 {
                continue; // a corrupt index; a scenario has a handful of phases
            }
            if by_index.len() <= i {
                by_index.resize(i + 1, None);
            }
            by_index[i].get_or_insert(s.phase);
        }
    }
    by_index
        .iter()
        .enumerate()
        .map(|(i, p)| match p {
            Some(p) => (
                format!("{i}-{p:?}").to_lowercase(),
                *p == MissionPhase::Move,
            ),
            None => (format!("{i}-unknown"), false),
        })
        .unzip()
}

enum Event {
    Truth(usize),
    Mission(usize, usize),
    Setpoint(usize, usize),
}

/// The metrics of the recorded flight. Without `/plant/truth` most are absent (None).
pub fn compute(f: &FlightData, setup: &MetricsSetup) -> FlightMetrics {
    let mut rec = MetricsRecorder::new(
        setup.ids.clone(),
        setup.phase_names.clone(),
        setup.phase_is_move.clone(),
        setup.anchor_frd_m,
    );
    // (log time, rank at equal times: truth first as the live monitor drains it first).
    let mut events: Vec<(u64, u8, Event)> = Vec::new();
    events.extend(
        f.truth
            .iter()
            .enumerate()
            .map(|(i, t)| (t.log_time_ns, 0, Event::Truth(i))),
    );
    for (k, d) in f.drones.iter().enumerate().take(2) {
        events.extend(
            d.mission
                .iter()
                .enumerate()
                .map(|(i, m)| (m.log_time_ns, 1, Event::Mission(k, i))),
        );
        events.extend(
            d.attitude
                .iter()
                .enumerate()
                .map(|(i, s)| (s.log_time_ns, 2, Event::Setpoint(k, i))),
        );
    }
    events.sort_by_key(|(t, rank, _)| (*t, *rank));
    let realtime = f.mode.as_deref() != Some("fast");
    for (_, _, e) in &events {
        match *e {
            Event::Truth(i) => rec.on_truth(&f.truth[i].sample),
            Event::Mission(k, i) => {
                rec.on_mission(k, &f.drones[k].mission[i].sample);
            }
            Event::Setpoint(k, i) => rec.on_setpoint(k, &f.drones[k].attitude[i].sample, realtime),
        }
    }
    rec.finish()
}
