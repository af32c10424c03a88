use super::*;
use recorder::read::ChannelData;
use shared_types::{mission_flags, vehicle_flags, Header, MissionPhase};
use std::collections::BTreeMap;

const DT_NS: u64 = 10_000_000;
const STEPS: u64 = 300;

/// A drone's inputs over 3 s: armed, swaying a little around its setpoint, with a pull that
/// grows, so the integrators, filters and the tension shift all move.
struct Flight {
    cfg_text: String,
    states: Vec<VehicleState>,
    tensions: Vec<TensionSample>,
    missions: Vec<MissionSetpoint>,
    setpoints: Vec<AttitudeSetpoint>,
}

fn fly() -> Flight {
    let cfg_text = Config::embedded_sim().to_toml();
    let cfg = Config::from_toml_str(&cfg_text, "test").expect("config");
    let mut stage = ControllerStage::new(&cfg.vehicle, &cfg.controller).expect("stage");
    let mut f = Flight {
        cfg_text,
        states: Vec::new(),
        tensions: Vec::new(),
        missions: Vec::new(),
        setpoints: Vec::new(),
    };
    for k in 0..STEPS {
        let t = 1_000_000_000 + k * DT_NS;
        let s = (k as f64 * 0.05).sin();
        let header = |seq: u64| Header {
            sequence: seq,
            t_origin_ns: t - 2_000_000,
            t_publish_ns: t - 1_000_000,
        };
        f.states.push(VehicleState {
            header: header(k),
            position_ned_m: [0.1 * s, -0.05 * s, -1.0 + 0.02 * s],
            velocity_ned_m_s: [0.05 * s, 0.01, -0.02 * s],
            attitude_wxyz: [1.0, 0.01 * s, 0.0, 0.0],
            flags: vehicle_flags::ARMED | vehicle_flags::OFFBOARD,
            ..Default::default()
        });
        // Tension at half the rate after the first 0.5 s (seq k/2): some steps get none.
        if k >= 50 && k % 2 == 0 {
            let seq = f.tensions.len() as u64;
            f.tensions.push(TensionSample {
                header: header(seq),
                force_body_n: [0.3 * s, 0.1, 3.0 + 0.01 * k as f64],
                ..Default::default()
            });
        }
        f.missions.push(MissionSetpoint {
            header: header(k),
            phase: MissionPhase::Move,
            flags: mission_flags::TENSION_ENABLED,
            position_ned_m: [0.0, 0.0, -1.0],
            peer_position_ned_m: [0.0, 1.5, -1.0],
            ..Default::default()
        });
        let mut sp = stage.step(
            t,
            f.states.last().expect("state"),
            f.tensions.last(),
            f.missions.last(),
        );
        sp.header.sequence = k;
        sp.header.t_publish_ns = t + 100_000;
        f.setpoints.push(sp);
    }
    f
}

fn channel<T: Recordable>(topic: &str, samples: &[T]) -> ChannelData {
    ChannelData {
        topic: recorder::channel_topic("uav1", topic),
        schema_name: recorder::format::schema_name::<T>(),
        metadata: BTreeMap::from([
            ("uav".to_string(), "uav1".to_string()),
            ("topic".to_string(), topic.to_string()),
        ]),
        messages: samples
            .iter()
            .map(|s| {
                (
                    s.header().t_publish_ns,
                    serde_json::to_vec(s).expect("encode"),
                )
            })
            .collect(),
    }
}

fn recording(f: &Flight) -> Recording {
    Recording {
        channels: vec![
            channel(names::VEHICLE_STATE, &f.states),
            channel(names::TENSION, &f.tensions),
            channel(names::MISSION_SETPOINT, &f.missions),
            channel(names::ATTITUDE_SETPOINT, &f.setpoints),
        ],
        attachments: BTreeMap::from([(
            recorder::format::config_attachment("uav1"),
            f.cfg_text.clone().into_bytes(),
        )]),
        ..Default::default()
    }
}

#[test]
fn a_recorded_flight_replays_bit_for_bit() {
    let f = fly();
    // The flight must exercise the law, or replaying it proves little.
    let active = f
        .setpoints
        .iter()
        .filter(|s| s.given_inputs & given_inputs::TENSION != 0)
        .count();
    assert!(active > 200, "steps with tension: {active}");
    let o = replay_drone(&recording(&f), "uav1").expect("replay");
    assert_eq!(o.first_mismatch, None);
    assert_eq!(o.steps, STEPS as usize);
}

#[test]
fn one_bit_of_thrust_is_reported_at_its_step() {
    let mut f = fly();
    let sp = &mut f.setpoints[137];
    sp.thrust_n = f64::from_bits(sp.thrust_n.to_bits() + 1);
    let o = replay_drone(&recording(&f), "uav1").expect("replay");
    let m = o.first_mismatch.expect("a mismatch");
    assert_eq!(m.sequence, 137);
    assert!(m.what.starts_with("thrust_n: recorded"), "{}", m.what);
    assert_eq!(o.steps, 138);
}

#[test]
fn a_changed_input_changes_the_output() {
    // The replay really recomputes: a recorded input nudged by 1 mm shows up as a mismatch.
    let mut f = fly();
    f.states[200].position_ned_m[2] += 1e-3;
    let o = replay_drone(&recording(&f), "uav1").expect("replay");
    assert_eq!(o.first_mismatch.expect("a mismatch").sequence, 200);
}

#[test]
fn a_missing_input_or_a_late_start_is_named() {
    let mut f = fly();
    f.tensions.remove(40);
    let o = replay_drone(&recording(&f), "uav1").expect("replay");
    let m = o.first_mismatch.expect("a mismatch");
    assert!(
        m.what.contains("tension sample 40 is not in the recording"),
        "{}",
        m.what
    );

    let mut f = fly();
    f.setpoints.drain(..5);
    match replay_drone(&recording(&f), "uav1") {
        Err(ReplayError::LateStart { sequence: 5, .. }) => {}
        other => panic!("expected a late start, got {other:?}"),
    }

    let mut f = fly();
    f.setpoints.remove(77);
    let m = replay_drone(&recording(&f), "uav1")
        .expect("replay")
        .first_mismatch
        .expect("a mismatch");
    assert_eq!(m.sequence, 78);
    assert!(m.what.contains("77..78"), "{}", m.what);
}
