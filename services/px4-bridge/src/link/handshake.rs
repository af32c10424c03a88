//! The handshake, acks and stream-rate requests: the parts of [`OffboardLink`] driven by
//! PX4's HEARTBEAT and COMMAND_ACK and by the clock.

use super::{OffboardLink, STREAMS};
use crate::command::{AckOutcome, CommandPoll, CommandState};
use crate::status::{HandshakeFailure, HandshakeStage};
use mavlink::dialects::common::{MavCmd, MavMessage, MavResult, COMMAND_ACK_DATA, HEARTBEAT_DATA};
use shared_types::vehicle_flags;

impl OffboardLink {
    pub(super) fn on_heartbeat(&mut self, now_ns: u64, h: &HEARTBEAT_DATA) {
        self.counters.heartbeats_received += 1;
        self.last_heartbeat_ns = Some(now_ns);
        self.base_mode = h.base_mode.bits();
        self.custom_mode = h.custom_mode;
        self.refresh_link(now_ns);
        let armed = self.flags() & vehicle_flags::ARMED != 0;
        match self.stage {
            HandshakeStage::Arming | HandshakeStage::Confirming if self.armed_in_offboard() => {
                self.arm.cancel();
                self.stage = HandshakeStage::Done;
            }
            HandshakeStage::Done if armed && !self.offboard() => {
                self.stage = HandshakeStage::LeftOffboard;
            }
            _ => {}
        }
    }

    pub(super) fn on_ack(&mut self, now_ns: u64, a: &COMMAND_ACK_DATA) {
        let to_us = (a.target_system == 0 || a.target_system == self.own.0)
            && (a.target_component == 0 || a.target_component == self.own.1);
        let pending = match a.command {
            _ if !to_us => None,
            MavCmd::MAV_CMD_DO_SET_MODE => Some(&mut self.set_mode),
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => Some(&mut self.arm),
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => Some(&mut self.interval),
            _ => None,
        };
        let Some(pending) = pending else {
            self.counters.acks_unexpected += 1;
            return;
        };
        let outcome = pending.on_ack(a.result, now_ns, &self.timing);
        let c = &mut self.counters;
        match outcome {
            AckOutcome::Unexpected => c.acks_unexpected += 1,
            AckOutcome::Accepted => c.acks_accepted += 1,
            AckOutcome::InProgress => c.acks_in_progress += 1,
            AckOutcome::Rejected { .. } => {
                c.acks_rejected += 1;
                if a.result == MavResult::MAV_RESULT_TEMPORARILY_REJECTED {
                    c.acks_temporarily_rejected += 1;
                }
            }
        }
        let gave_up = matches!(outcome, AckOutcome::Rejected { gave_up: true });
        match (a.command, self.stage) {
            (MavCmd::MAV_CMD_DO_SET_MODE, HandshakeStage::SettingOffboard) => {
                if outcome == AckOutcome::Accepted {
                    self.stage = HandshakeStage::Arming;
                    self.arm.start([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], now_ns);
                } else if gave_up {
                    self.fail_command(true);
                }
            }
            (MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, HandshakeStage::Arming) => {
                if outcome == AckOutcome::Accepted {
                    self.stage = if self.armed_in_offboard() {
                        HandshakeStage::Done
                    } else {
                        self.confirm_deadline_ns = now_ns + self.link_timeout_ns;
                        HandshakeStage::Confirming
                    };
                } else if gave_up {
                    self.fail_command(false);
                }
            }
            (MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, _) => match outcome {
                AckOutcome::Accepted => self.next_interval(true),
                _ if gave_up => self.next_interval(false),
                _ => {}
            },
            _ => {}
        }
    }

    pub(super) fn stream_stopped(&mut self) {
        self.stream_start_ns = None;
        if matches!(
            self.stage,
            HandshakeStage::Streaming
                | HandshakeStage::SettingOffboard
                | HandshakeStage::Arming
                | HandshakeStage::Confirming
        ) {
            self.counters.handshake_restarts += 1;
            self.reset_handshake();
        }
    }

    pub(super) fn reset_handshake(&mut self) {
        self.stage = HandshakeStage::Idle;
        self.failure = None;
        self.set_mode.cancel();
        self.arm.cancel();
    }

    pub(super) fn fail_command(&mut self, set_mode: bool) {
        let c = if set_mode { &self.set_mode } else { &self.arm };
        let (sends, last_result) = (c.sends, c.last_result);
        self.failure = Some(if set_mode {
            HandshakeFailure::SetModeNotAccepted { sends, last_result }
        } else {
            HandshakeFailure::ArmNotAccepted { sends, last_result }
        });
        self.stage = HandshakeStage::Failed;
    }

    pub(super) fn advance_handshake(&mut self, now_ns: u64, send: &mut impl FnMut(&MavMessage)) {
        match self.stage {
            HandshakeStage::Idle if self.arm_request && self.stream_start_ns.is_some() => {
                self.stage = HandshakeStage::Streaming;
            }
            HandshakeStage::Streaming if self.link_up => {
                // PX4 must have seen the stream: count it from when the link came up.
                let since = self
                    .stream_start_ns
                    .unwrap_or(now_ns)
                    .max(self.link_up_since_ns);
                if now_ns.saturating_sub(since) >= self.stream_before_ns {
                    self.stage = HandshakeStage::SettingOffboard;
                    self.set_mode
                        .start([1.0, 6.0, 0.0, 0.0, 0.0, 0.0, 0.0], now_ns);
                }
            }
            HandshakeStage::Confirming if now_ns >= self.confirm_deadline_ns => {
                self.failure = Some(HandshakeFailure::NotConfirmed);
                self.stage = HandshakeStage::Failed;
            }
            _ => {}
        }
        let set_mode = match self.stage {
            HandshakeStage::SettingOffboard => true,
            HandshakeStage::Arming => false,
            _ => return,
        };
        if !self.link_up {
            return;
        }
        let cmd = if set_mode {
            &mut self.set_mode
        } else {
            &mut self.arm
        };
        let poll = cmd.poll(now_ns, &self.timing);
        if self.handle_poll(poll, send) {
            self.fail_command(set_mode);
        }
    }

    pub(super) fn advance_intervals(&mut self, now_ns: u64, send: &mut impl FnMut(&MavMessage)) {
        if !self.link_up || self.interval_next >= STREAMS.len() {
            return;
        }
        if self.interval.state == CommandState::Idle {
            let k = self.interval_next;
            let mut params = [0.0; 7];
            params[0] = STREAMS[k] as f32;
            params[1] = self.interval_us[k];
            self.interval.start(params, now_ns);
        }
        let poll = self.interval.poll(now_ns, &self.timing);
        if self.handle_poll(poll, send) {
            self.next_interval(false);
        }
    }

    pub(super) fn next_interval(&mut self, accepted: bool) {
        if accepted {
            self.counters.intervals_accepted += 1;
        } else {
            self.counters.intervals_failed += 1;
        }
        self.interval_next += 1;
        self.interval.cancel();
    }

    /// Sends and counts what a command's poll asks for; true if it gave up.
    pub(super) fn handle_poll(
        &mut self,
        poll: CommandPoll,
        send: &mut impl FnMut(&MavMessage),
    ) -> bool {
        let c = &mut self.counters;
        match poll {
            CommandPoll::Nothing => false,
            CommandPoll::Send {
                msg,
                retry,
                after_timeout,
            } => {
                c.ack_timeouts += u64::from(after_timeout);
                c.command_retries += u64::from(retry);
                c.commands_sent += 1;
                send(&msg);
                false
            }
            CommandPoll::GaveUp { after_timeout } => {
                c.ack_timeouts += u64::from(after_timeout);
                true
            }
        }
    }
}
