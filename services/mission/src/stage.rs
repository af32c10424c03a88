//! The mission's decentralized state machine (paper V.A), pure: each drone runs one, and the two
//! agree on phase changes only through the ready signals they exchange. A phase ends when this
//! drone is ready (the scenario's rule, [`PhaseTracker`]) and the peer says it is ready in the
//! same phase, or is already past it.

use nalgebra::Vector3;
use shared_types::{
    mission_flags, vehicle_flags, Header, MissionPhase, MissionSetpoint, VehicleState,
};
use sim_plant::scenario::{PathSample, PayloadStart, PhaseKind, PhaseTracker, Scenario};

use crate::signal::{encode_drone_id, signal_flags, PeerSignal};
pub use crate::types::{MissionCounters, MissionError, MissionEvent, MissionOutput, MAX_PHASES};

/// One drone's mission. Allocates only in `new`.
#[derive(Debug, Clone)]
pub struct MissionStage {
    tracker: PhaseTracker,
    drone: usize,
    peer: usize,
    own_id: [u8; 16],
    peer_id: [u8; 16],
    n_phases: usize,
    kinds: [MissionPhase; MAX_PHASES],
    tension: [bool; MAX_PHASES],
    timeout_s: [f64; MAX_PHASES],
    yaw_rad: f64,
    idle_own: Vector3<f64>,
    idle_peer: Vector3<f64>,
    peer_timeout_ns: u64,
    state_timeout_ns: u64,
    arm_timeout_ns: u64,
    // State.
    started: bool,
    arm_request_ns: Option<u64>,
    arm_timed_out: bool,
    timed_out: bool,
    peer_lost: bool,
    peer_holding: bool,
    /// The path clock, ns: advances with the tick time except while frozen.
    path_ns: u64,
    last_now_ns: Option<u64>,
    phase_start_ns: u64,
    sequence: u64,
    last_rejected: Option<(u64, u64)>,
    counters: MissionCounters,
}

fn kind_phase(k: PhaseKind) -> MissionPhase {
    match k {
        PhaseKind::Takeoff => MissionPhase::Takeoff,
        PhaseKind::Move => MissionPhase::Move,
        PhaseKind::Hold => MissionPhase::Hold,
        PhaseKind::Land => MissionPhase::Land,
    }
}

fn secs_to_ns(s: f64) -> u64 {
    (s * 1e9) as u64
}

impl MissionStage {
    /// `drone`: this drone's index in the scenario (0 or 1); the peer is the other.
    pub fn new(
        scenario: &Scenario,
        drone: usize,
        cfg: &rt_config::MissionConfig,
    ) -> Result<Self, MissionError> {
        cfg.validate().map_err(MissionError::Config)?;
        if drone > 1 {
            return Err(MissionError::DroneIndex(drone));
        }
        let peer = 1 - drone;
        let expected = &scenario.drones[peer].id;
        if &cfg.peer != expected {
            return Err(MissionError::PeerMismatch {
                peer: cfg.peer.clone(),
                expected: expected.clone(),
            });
        }
        let n_phases = scenario.phases.len();
        if n_phases > MAX_PHASES {
            return Err(MissionError::TooManyPhases {
                name: scenario.name.clone(),
                n: n_phases,
            });
        }
        let mut kinds = [MissionPhase::Hold; MAX_PHASES];
        let mut tension = [true; MAX_PHASES];
        let mut timeout_s = [f64::INFINITY; MAX_PHASES];
        let resting = scenario.payload.start == PayloadStart::Resting;
        for (i, ph) in scenario.phases.iter().enumerate() {
            kinds[i] = kind_phase(ph.kind);
            // A take-off under a resting payload keeps the cables slack (Test A).
            tension[i] = !(ph.kind == PhaseKind::Takeoff && resting);
            timeout_s[i] = ph.timeout_s;
        }
        Ok(MissionStage {
            tracker: PhaseTracker::new(scenario, 0.0),
            drone,
            peer,
            own_id: encode_drone_id(&scenario.drones[drone].id)?,
            peer_id: encode_drone_id(&cfg.peer)?,
            n_phases,
            kinds,
            tension,
            timeout_s,
            yaw_rad: scenario.yaw_rad(drone),
            idle_own: scenario.takeoff_point(drone),
            idle_peer: scenario.takeoff_point(peer),
            peer_timeout_ns: secs_to_ns(cfg.peer_timeout_s),
            state_timeout_ns: secs_to_ns(cfg.state_timeout_s),
            arm_timeout_ns: secs_to_ns(cfg.arm_timeout_s),
            started: false,
            arm_request_ns: None,
            arm_timed_out: false,
            timed_out: false,
            peer_lost: true,
            peer_holding: false,
            path_ns: 0,
            last_now_ns: None,
            phase_start_ns: 0,
            sequence: 0,
            last_rejected: None,
            counters: MissionCounters::default(),
        })
    }

    pub fn counters(&self) -> MissionCounters {
        self.counters
    }

    /// Index of the running scenario phase (number of phases once done; 0 in Idle).
    pub fn phase_index(&self) -> usize {
        self.tracker.phase()
    }

    pub fn started(&self) -> bool {
        self.started
    }

    pub fn done(&self) -> bool {
        self.started && self.tracker.done()
    }

    /// One tick at `now_ns` with this drone's newest state (None if none yet) and the newest
    /// valid peer signal with the time it was received (None if never).
    pub fn step(
        &mut self,
        now_ns: u64,
        own: Option<&VehicleState>,
        peer: Option<(&PeerSignal, u64)>,
    ) -> MissionOutput {
        self.counters.ticks += 1;
        let dt_ns = self.last_now_ns.map_or(0, |l| now_ns.saturating_sub(l));
        self.last_now_ns = Some(now_ns);

        let peer = peer.filter(|(s, rx)| {
            let expected = s.drone_id == self.peer_id;
            if !expected && self.last_rejected != Some((s.sequence, *rx)) {
                self.last_rejected = Some((s.sequence, *rx));
                self.counters.unexpected_sender += 1;
            }
            expected
        });
        let peer = peer
            .filter(|(_, rx)| now_ns.saturating_sub(*rx) <= self.peer_timeout_ns)
            .map(|(s, _)| *s);
        let own = own.filter(|s| {
            now_ns.saturating_sub(s.header.t_origin_ns) <= self.state_timeout_ns
                && s.flags & vehicle_flags::LINK_LOST == 0
        });

        let mut event = None;
        if peer.is_none() != self.peer_lost {
            self.peer_lost = peer.is_none();
            event = Some(if self.peer_lost {
                MissionEvent::PeerLost
            } else {
                MissionEvent::PeerRegained
            });
        }
        let holding_now =
            peer.is_some_and(|p| p.has(signal_flags::PEER_LOST) || p.has(signal_flags::TIMED_OUT));
        if holding_now != self.peer_holding {
            self.peer_holding = holding_now;
            let e = if holding_now {
                MissionEvent::PeerHolding
            } else {
                MissionEvent::PeerResumed
            };
            event.get_or_insert(e);
        }

        let mut own_ready = false;
        let mut peer_ready = false;
        if !self.started {
            self.step_idle(now_ns, own, peer.as_ref(), &mut event);
        } else if !self.tracker.done() {
            let frozen = self.frozen();
            if !frozen {
                self.path_ns += dt_ns;
            }
            let k = self.tracker.phase();
            if !frozen {
                // A stale state counts as out of tolerance (NaN never compares within).
                let pos = own.map_or(Vector3::repeat(f64::NAN), |s| {
                    Vector3::from(s.position_ned_m)
                });
                let r = self.tracker.readiness(self.drone, self.path_t_s(), &pos);
                own_ready = self.tracker.is_ready(&r);
            }
            peer_ready = peer.is_some_and(|p| {
                let own_progress = k as u64 + 1;
                (p.progress() == own_progress && p.has(signal_flags::READY))
                    || p.progress() > own_progress
            });
            let elapsed_s = self.path_t_s() - self.tracker.phase_starts_s()[k];
            if !frozen && own_ready && peer_ready && event.is_none() {
                self.tracker.advance(self.path_t_s());
                self.phase_start_ns = now_ns;
                let ended = Some(k as u32);
                event = Some(if self.tracker.done() {
                    MissionEvent::Done { last: k as u32 }
                } else {
                    MissionEvent::PhaseStarted {
                        index: k as u32 + 1,
                        phase: self.kinds[k + 1],
                        ended,
                    }
                });
                own_ready = false;
                peer_ready = false;
            } else if !frozen && elapsed_s > self.timeout_s[k] && event.is_none() {
                self.timed_out = true;
                event = Some(MissionEvent::TimedOut { index: k as u32 });
            }
        }
        self.output(now_ns, own, own_ready, peer_ready, event)
    }

    fn path_t_s(&self) -> f64 {
        self.path_ns as f64 * 1e-9
    }

    /// The path is frozen: we lost the peer, the peer holds for its own reason, or we timed out.
    fn frozen(&self) -> bool {
        self.peer_lost || self.peer_holding || self.timed_out
    }

    fn step_idle(
        &mut self,
        now_ns: u64,
        own: Option<&VehicleState>,
        peer: Option<&PeerSignal>,
        event: &mut Option<MissionEvent>,
    ) {
        if self.arm_timed_out {
            return;
        }
        // A peer already flying passed Idle with us idle-ready and its handshake done.
        let peer_idle_ready =
            peer.is_some_and(|p| p.has(signal_flags::IDLE_READY) || p.progress() > 0);
        if self.arm_request_ns.is_none() && own.is_some() && peer_idle_ready {
            self.arm_request_ns = Some(now_ns);
            event.get_or_insert(MissionEvent::ArmRequested);
            return;
        }
        let Some(requested_ns) = self.arm_request_ns else {
            return;
        };
        let own_hs = own.is_some_and(|s| s.flags & vehicle_flags::HANDSHAKE_DONE != 0);
        let peer_hs = peer.is_some_and(|p| p.has(signal_flags::HANDSHAKE_DONE) || p.progress() > 0);
        if own_hs && peer_hs && event.is_none() {
            self.started = true;
            self.path_ns = 0;
            self.phase_start_ns = now_ns;
            *event = Some(MissionEvent::PhaseStarted {
                index: 0,
                phase: self.kinds[0],
                ended: None,
            });
        } else if now_ns.saturating_sub(requested_ns) > self.arm_timeout_ns && event.is_none() {
            self.arm_timed_out = true;
            *event = Some(MissionEvent::ArmTimedOut);
        }
    }

    fn output(
        &mut self,
        now_ns: u64,
        own: Option<&VehicleState>,
        own_ready: bool,
        peer_ready: bool,
        event: Option<MissionEvent>,
    ) -> MissionOutput {
        let k = self.tracker.phase();
        let done = self.started && self.tracker.done();
        let holding = self.started && !done && self.frozen();
        let (phase, sample, peer_pos) = if !self.started {
            let still = PathSample {
                position_ned_m: self.idle_own,
                velocity_ned_m_s: Vector3::zeros(),
                acceleration_ned_m_s2: Vector3::zeros(),
            };
            (MissionPhase::Idle, still, self.idle_peer)
        } else {
            let phase = match (done, holding) {
                (true, _) => MissionPhase::Done,
                (false, true) => MissionPhase::Hold,
                (false, false) => self.kinds[k],
            };
            let peer_pos = self
                .tracker
                .setpoint(self.peer, self.path_t_s())
                .position_ned_m;
            (
                phase,
                self.tracker.setpoint(self.drone, self.path_t_s()),
                peer_pos,
            )
        };
        let mut flags = 0;
        let mut set = |cond: bool, bit: u32| {
            if cond {
                flags |= bit
            }
        };
        set(
            self.arm_request_ns.is_some() && !self.arm_timed_out,
            mission_flags::ARM_REQUEST,
        );
        set(
            self.started && (done || self.tension[k]),
            mission_flags::TENSION_ENABLED,
        );
        set(self.peer_lost, mission_flags::PEER_LOST);
        set(holding, mission_flags::HOLDING);
        set(
            self.timed_out || self.arm_timed_out,
            mission_flags::TIMED_OUT,
        );
        set(own_ready, mission_flags::READY);
        set(peer_ready, mission_flags::PEER_READY);
        let setpoint = MissionSetpoint {
            header: Header {
                sequence: 0,
                t_origin_ns: now_ns,
                t_publish_ns: 0,
            },
            phase,
            phase_index: k as u32,
            phase_start_ns: self.phase_start_ns,
            flags,
            position_ned_m: sample.position_ned_m.into(),
            velocity_ned_m_s: sample.velocity_ned_m_s.into(),
            acceleration_ned_m_s2: sample.acceleration_ned_m_s2.into(),
            yaw_rad: self.yaw_rad,
            peer_position_ned_m: peer_pos.into(),
        };
        let signal = self.signal(now_ns, own, own_ready, done, holding);
        MissionOutput {
            setpoint,
            signal,
            event,
        }
    }

    fn signal(
        &mut self,
        now_ns: u64,
        own: Option<&VehicleState>,
        own_ready: bool,
        done: bool,
        holding: bool,
    ) -> PeerSignal {
        let mut flags = 0;
        let mut set = |cond: bool, bit: u32| {
            if cond {
                flags |= bit
            }
        };
        set(!self.started, signal_flags::IDLE);
        set(!self.started && own.is_some(), signal_flags::IDLE_READY);
        set(
            own.is_some_and(|s| s.flags & vehicle_flags::HANDSHAKE_DONE != 0),
            signal_flags::HANDSHAKE_DONE,
        );
        set(own_ready, signal_flags::READY);
        set(holding, signal_flags::HOLDING);
        // Only our own causes: echoing the peer's hold would keep both holding for ever.
        set(self.started && self.peer_lost, signal_flags::PEER_LOST);
        set(self.timed_out, signal_flags::TIMED_OUT);
        set(done, signal_flags::DONE);
        let s = PeerSignal {
            drone_id: self.own_id,
            sequence: self.sequence,
            phase_index: self.tracker.phase().min(self.n_phases) as u32,
            flags,
            sent_ns: now_ns,
        };
        self.sequence += 1;
        s
    }
}

#[cfg(test)]
#[path = "stage_pair_tests.rs"]
mod pair_tests;
#[cfg(test)]
#[path = "stage_tests.rs"]
mod tests;
