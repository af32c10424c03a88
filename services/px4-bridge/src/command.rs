//! One COMMAND_LONG until PX4 accepts it: sent, resent when no ack came within the ack timeout
//! or after a rejection (after the same delay, so a burst of rejections cannot use up the
//! attempts at once), given up after the configured number of sends.

use mavlink::dialects::common::{MavCmd, MavMessage, MavResult, COMMAND_LONG_DATA};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CommandState {
    Idle,
    /// To be sent at or after this time, ns.
    Due(u64),
    /// Sent; without an ack by this time it is resent, ns.
    Waiting {
        deadline_ns: u64,
    },
    Accepted,
    GaveUp,
}

/// What [`PendingCommand::poll`] asks for (a transient stack value: its size does not matter).
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub(crate) enum CommandPoll {
    Nothing,
    /// Send this; `retry` if it is not the first send, `after_timeout` if the previous send
    /// got no ack in time.
    Send {
        msg: MavMessage,
        retry: bool,
        after_timeout: bool,
    },
    /// No ack (or only rejections) after the last allowed send.
    GaveUp {
        after_timeout: bool,
    },
}

/// How an ack for this command's id was taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum AckOutcome {
    /// No send of ours is waiting for an ack (late or duplicate ack).
    Unexpected,
    Accepted,
    /// Still working on it: the deadline moves.
    InProgress,
    /// Rejected; resent after the ack timeout unless the attempts are used up.
    Rejected {
        gave_up: bool,
    },
}

/// Timing and addressing shared by every command.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CommandTiming {
    pub ack_timeout_ns: u64,
    pub attempts: u32,
    pub target_system: u8,
    pub target_component: u8,
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct PendingCommand {
    pub command: MavCmd,
    pub params: [f32; 7],
    pub sends: u32,
    pub state: CommandState,
    pub last_result: Option<MavResult>,
}

impl PendingCommand {
    pub fn new(command: MavCmd) -> Self {
        Self {
            command,
            params: [0.0; 7],
            sends: 0,
            state: CommandState::Idle,
            last_result: None,
        }
    }

    /// Starts over with `params`, first send due now.
    pub fn start(&mut self, params: [f32; 7], now_ns: u64) {
        self.params = params;
        self.sends = 0;
        self.state = CommandState::Due(now_ns);
        self.last_result = None;
    }

    pub fn cancel(&mut self) {
        self.state = CommandState::Idle;
    }

    pub fn waiting(&self) -> bool {
        matches!(self.state, CommandState::Waiting { .. })
    }

    pub fn poll(&mut self, now_ns: u64, t: &CommandTiming) -> CommandPoll {
        let after_timeout = match self.state {
            CommandState::Due(at) if now_ns >= at => false,
            CommandState::Waiting { deadline_ns } if now_ns >= deadline_ns => true,
            _ => return CommandPoll::Nothing,
        };
        if self.sends >= t.attempts {
            self.state = CommandState::GaveUp;
            return CommandPoll::GaveUp { after_timeout };
        }
        self.sends += 1;
        self.state = CommandState::Waiting {
            deadline_ns: now_ns + t.ack_timeout_ns,
        };
        let p = self.params;
        let msg = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: p[0],
            param2: p[1],
            param3: p[2],
            param4: p[3],
            param5: p[4],
            param6: p[5],
            param7: p[6],
            command: self.command,
            target_system: t.target_system,
            target_component: t.target_component,
            // MAVLink: 0 on the first transmission, +1 on each resend.
            confirmation: (self.sends - 1).min(255) as u8,
        });
        CommandPoll::Send {
            msg,
            retry: self.sends > 1,
            after_timeout,
        }
    }

    pub fn on_ack(&mut self, result: MavResult, now_ns: u64, t: &CommandTiming) -> AckOutcome {
        if !self.waiting() {
            return AckOutcome::Unexpected;
        }
        self.last_result = Some(result);
        match result {
            MavResult::MAV_RESULT_ACCEPTED => {
                self.state = CommandState::Accepted;
                AckOutcome::Accepted
            }
            MavResult::MAV_RESULT_IN_PROGRESS => {
                self.state = CommandState::Waiting {
                    deadline_ns: now_ns + t.ack_timeout_ns,
                };
                AckOutcome::InProgress
            }
            _ => {
                let gave_up = self.sends >= t.attempts;
                self.state = if gave_up {
                    CommandState::GaveUp
                } else {
                    CommandState::Due(now_ns + t.ack_timeout_ns)
                };
                AckOutcome::Rejected { gave_up }
            }
        }
    }
}
