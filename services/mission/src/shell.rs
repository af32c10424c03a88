//! The mission service: reads this drone's VehicleState, hears the peer over zenoh, steps the
//! [`MissionStage`] at `mission.rate_hz` and publishes MissionSetpoint and its own phase signal,
//! until SIGINT/SIGTERM.

use std::io::Write;

use rt_config::periodic::{now_ns, PeriodicLoop};
use shared_types::{names, MissionSetpoint, VehicleState};
use sim_plant::scenario::Scenario;
use taut_ipc::{install_stop_handler, stop_requested, Ipc};

use crate::{MissionEvent, MissionStage, PeerLink, PeerSignal};

fn describe(event: MissionEvent, scenario: &Scenario) -> String {
    let name = |i: u32| {
        scenario
            .phases
            .get(i as usize)
            .map_or("?", |p| p.name.as_str())
    };
    match event {
        MissionEvent::ArmRequested => "both idle-ready: arm requested".into(),
        MissionEvent::ArmTimedOut => {
            "arm timed out: the handshake did not finish on both drones, staying idle".into()
        }
        MissionEvent::PhaseStarted { index, ended, .. } => match ended {
            Some(e) => format!(
                "phase {e} {} ended; phase {index} {} started",
                name(e),
                name(index)
            ),
            None => format!("phase {index} {} started", name(index)),
        },
        MissionEvent::Done { last } => format!("phase {last} {} ended; done", name(last)),
        MissionEvent::PeerLost => "peer lost".into(),
        MissionEvent::PeerRegained => "peer heard".into(),
        MissionEvent::PeerHolding => "peer holds: holding".into(),
        MissionEvent::PeerResumed => "peer resumed".into(),
        MissionEvent::TimedOut { index } => {
            format!("phase {index} {} timed out: holding", name(index))
        }
    }
}

pub fn run(cfg: &rt_config::Config) -> Result<(), String> {
    install_stop_handler();
    let report =
        rt_config::rt::apply(&cfg.services.mission).map_err(|e| format!("mission: {e}"))?;
    eprintln!("[mission] real-time: {report}");
    let m = &cfg.mission;
    m.validate()?;
    let scenario =
        Scenario::load(&m.scenario).map_err(|e| format!("key `mission.scenario`: {e}"))?;
    let own_id = if m.drone.is_empty() {
        cfg.uav.as_str()
    } else {
        m.drone.as_str()
    };
    let drone = scenario.drone_index(own_id).ok_or_else(|| {
        format!(
            "key `mission.drone` (or `uav`) = {own_id:?}: scenario {} has drones {:?} and {:?}",
            scenario.name, scenario.drones[0].id, scenario.drones[1].id
        )
    })?;
    let mut stage = MissionStage::new(&scenario, drone, m).map_err(|e| e.to_string())?;

    let ipc = Ipc::new(&format!("{}-mission", cfg.uav), &cfg.ipc_root, &cfg.uav)
        .map_err(|e| e.to_string())?;
    let states = ipc
        .subscriber::<VehicleState>(names::VEHICLE_STATE)
        .map_err(|e| e.to_string())?;
    let mut setpoints = ipc
        .publisher::<MissionSetpoint>(names::MISSION_SETPOINT)
        .map_err(|e| e.to_string())?;
    let mut link = PeerLink::open(m, own_id).map_err(|e| e.to_string())?;

    let tag = format!("[mission {own_id}]");
    let mut stdout = std::io::stdout();
    let _ = writeln!(
        stdout,
        "{tag} scenario {} as drone {drone}, peer {}",
        scenario.name, m.peer
    );
    let _ = stdout.flush();

    let t0_ns = now_ns();
    let mut periodic = PeriodicLoop::new((1e9 / m.rate_hz) as u64);
    let mut own: Option<VehicleState> = None;
    let mut peer: Option<(PeerSignal, u64)> = None;
    let (mut ipc_errors, mut send_errors) = (0u64, 0u64);
    while !stop_requested() {
        periodic.wait();
        let now = now_ns();
        if states.drain(&mut |s| own = Some(s)).is_err() {
            ipc_errors += 1;
        }
        if let Some(p) = link.try_recv() {
            peer = Some(p);
        }
        let out = stage.step(now, own.as_ref(), peer.as_ref().map(|(s, t)| (s, *t)));
        if setpoints.publish(out.setpoint).is_err() {
            ipc_errors += 1;
        }
        if link.send(&out.signal).is_err() {
            send_errors += 1;
        }
        if let Some(e) = out.event {
            let t = now.saturating_sub(t0_ns) as f64 * 1e-9;
            let _ = writeln!(stdout, "{tag} t={t:.2} s {}", describe(e, &scenario));
            let _ = stdout.flush();
        }
    }
    let (c, l) = (stage.counters(), link.counters());
    let _ = writeln!(
        stdout,
        "{tag} stopped: ticks={} overruns={} phase={} ipc_errors={ipc_errors} signals_sent={} send_errors={send_errors} received={} malformed={} unexpected_sender={}",
        c.ticks,
        periodic.schedule().overruns(),
        stage.phase_index(),
        l.sent,
        l.received,
        l.malformed,
        l.unexpected_sender + c.unexpected_sender,
    );
    let _ = stdout.flush();
    Ok(())
}
