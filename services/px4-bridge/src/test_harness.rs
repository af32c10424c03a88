//! [`Harness`]: a scripted PX4 around an [`OffboardLink`] on a simulated clock (10 ms steps).

use crate::*;
use mavlink::dialects::common::{
    MavCmd, MavModeFlag, MavResult, COMMAND_ACK_DATA, COMMAND_LONG_DATA, HEARTBEAT_DATA,
};
use rt_config::{Px4Config, VehicleConfig};
use shared_types::{setpoint_flags, AttitudeSetpoint};

pub(crate) const STEP_NS: u64 = 10_000_000;

pub(crate) struct Harness {
    pub link: OffboardLink,
    pub now: u64,
    /// Everything the link sent, with the time.
    pub sent: Vec<(u64, MavMessage)>,
    pub px4_armed: bool,
    pub px4_mode: u32,
    pending_acks: Vec<COMMAND_ACK_DATA>,
}

pub(crate) fn px4_header() -> MavHeader {
    MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: 0,
    }
}

pub(crate) fn accept_all(_: &COMMAND_LONG_DATA) -> Option<MavResult> {
    Some(MavResult::MAV_RESULT_ACCEPTED)
}

impl Harness {
    pub fn new() -> Self {
        Self::with(Px4Config::default())
    }

    pub fn with(px4: Px4Config) -> Self {
        Self {
            link: OffboardLink::new(&px4, &VehicleConfig::default()).unwrap(),
            now: 1_000_000_000,
            sent: Vec::new(),
            px4_armed: false,
            px4_mode: 3 << 16,
            pending_acks: Vec::new(),
        }
    }

    pub fn px4_sends(&mut self, msg: MavMessage) -> Option<Telemetry> {
        self.link.on_message(self.now, &px4_header(), &msg)
    }

    pub fn heartbeat(&mut self) {
        let base_mode = if self.px4_armed {
            MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED | MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        } else {
            MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        };
        self.px4_sends(MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: self.px4_mode,
            base_mode,
            ..HEARTBEAT_DATA::default()
        }));
    }

    pub fn setpoint(&mut self, arm: bool) -> Option<MavMessage> {
        let sp = AttitudeSetpoint {
            attitude_wxyz: [1.0, 0.0, 0.0, 0.0],
            thrust_n: 20.0,
            flags: if arm { setpoint_flags::ARM_REQUEST } else { 0 },
            ..AttitudeSetpoint::default()
        };
        self.link.on_setpoint(self.now, &sp)
    }

    pub fn poll(&mut self) -> usize {
        let (now, before) = (self.now, self.sent.len());
        let sent = &mut self.sent;
        self.link.poll(now, &mut |m| sent.push((now, m.clone())));
        self.sent.len() - before
    }

    /// `seconds` of 10 ms steps: acks due are delivered, a setpoint (with ARM_REQUEST) if
    /// `stream`, a PX4 HEARTBEAT every 100 ms if `heartbeats`, then a poll whose commands
    /// `respond` answers (acks delivered on the next step; PX4 switches and arms on ACCEPTED).
    pub fn run(
        &mut self,
        seconds: f64,
        stream: bool,
        heartbeats: bool,
        // PX4's answer to a command: Some(result), or None to ignore it.
        respond: &mut impl FnMut(&COMMAND_LONG_DATA) -> Option<MavResult>,
    ) {
        let steps = (seconds * 1e9 / STEP_NS as f64).round() as u64;
        for _ in 0..steps {
            self.now += STEP_NS;
            for a in std::mem::take(&mut self.pending_acks) {
                self.px4_sends(MavMessage::COMMAND_ACK(a));
            }
            if heartbeats && (self.now / STEP_NS).is_multiple_of(10) {
                self.heartbeat();
            }
            if stream {
                self.setpoint(true);
            }
            let first = self.sent.len();
            self.poll();
            for k in first..self.sent.len() {
                let MavMessage::COMMAND_LONG(c) = &self.sent[k].1 else {
                    continue;
                };
                let c = c.clone();
                if let Some(result) = respond(&c) {
                    if result == MavResult::MAV_RESULT_ACCEPTED {
                        match c.command {
                            MavCmd::MAV_CMD_DO_SET_MODE => self.px4_mode = 6 << 16,
                            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => self.px4_armed = true,
                            _ => {}
                        }
                    }
                    self.pending_acks.push(COMMAND_ACK_DATA {
                        command: c.command,
                        result,
                        target_system: 1,
                        target_component: 191,
                        ..COMMAND_ACK_DATA::default()
                    });
                }
            }
        }
    }

    /// The COMMAND_LONGs of `command` sent so far, with their times.
    pub fn commands(&self, command: MavCmd) -> Vec<(u64, COMMAND_LONG_DATA)> {
        self.sent
            .iter()
            .filter_map(|(t, m)| match m {
                MavMessage::COMMAND_LONG(c) if c.command == command => Some((*t, c.clone())),
                _ => None,
            })
            .collect()
    }
}
