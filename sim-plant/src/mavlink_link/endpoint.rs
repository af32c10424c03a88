//! The UDP endpoint: streams out on schedule, drains and dispatches inbound datagrams.

use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};

use mavlink::dialects::common::{MavMessage, MavResult, TIMESYNC_DATA};
use mavlink::error::ParserError;
use mavlink::Message;

use super::codec::{FrameScanner, FrameWriter, RawFrame, RejectKind, Scanned};
use super::config::{LinkConfig, LinkOpenError, Stream};
use super::inbound::{attitude_target, CommandLong, Inbound};
use super::outbound;
use super::schedule::{IntervalRequest, StreamSchedule};
use super::telemetry::Telemetry;

const MAV_CMD_SET_MESSAGE_INTERVAL: u16 = 511;
const MAV_CMD_REQUEST_MESSAGE: u16 = 512;
const MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES: u16 = 520;
const AUTOPILOT_VERSION_ID: u32 = 148;
const COMMAND_LONG_ID: u32 = 76;
/// Largest UDP payload; the receive buffer is allocated once at this size.
const MAX_DATAGRAM: usize = 65_536;

/// Link statistics; every dropped byte or frame lands in exactly one rx counter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct LinkCounters {
    /// Datagrams received.
    pub rx_datagrams: u64,
    /// Frames with a good checksum that parsed.
    pub rx_frames_ok: u64,
    /// Frames of a known message id with a checksum mismatch.
    pub rx_bad_crc: u64,
    /// Frames whose message id is not in the common dialect.
    pub rx_unknown_message: u64,
    /// Frames cut short by the end of their datagram.
    pub rx_truncated: u64,
    /// MAVLink 2 frames with unsupported incompatibility flags.
    pub rx_bad_header: u64,
    /// Bytes outside any frame candidate.
    pub rx_garbage_bytes: u64,
    /// Frames with a good checksum whose payload the dialect rejects (e.g. an invalid enum).
    pub rx_decode_errors: u64,
    /// Valid commands/setpoints addressed to another system or component.
    pub rx_not_for_us: u64,
    /// Valid messages the endpoint does not act on.
    pub rx_ignored: u64,
    /// Socket receive errors other than "would block".
    pub rx_socket_errors: u64,
    /// Frames handed to the socket.
    pub tx_frames: u64,
    /// Frames the socket refused (buffer full, unreachable, ...).
    pub tx_errors: u64,
    /// Commands the handler did not support (answered MAV_RESULT_UNSUPPORTED).
    pub unknown_commands: u64,
    /// `send_due` snapshots with a non-finite state value (the last good one was sent instead).
    pub telemetry_rejected: u64,
}

impl LinkCounters {
    /// All rejected frame candidates (not counting garbage bytes).
    pub fn rx_bad_frames(&self) -> u64 {
        self.rx_bad_crc
            + self.rx_unknown_message
            + self.rx_truncated
            + self.rx_bad_header
            + self.rx_decode_errors
    }
}

/// MAVLink 2 endpoint of one emulated PX4: an unconnected, non-blocking UDP socket.
///
/// Streams go to `remote` until the first datagram arrives; with `follow_first_sender` they
/// then go to that datagram's source, once, as PX4's UDP link does. Replies (COMMAND_ACK,
/// TIMESYNC) go to the source of the request.
pub struct MavlinkEndpoint {
    config: LinkConfig,
    socket: UdpSocket,
    local_addr: SocketAddr,
    destination: SocketAddr,
    destination_locked: bool,
    schedule: StreamSchedule,
    one_shot: [bool; Stream::COUNT],
    writer: FrameWriter,
    rx_buf: Box<[u8]>,
    last_good: Option<Telemetry>,
    last_peer_heartbeat: Option<(u64, u8, u8)>,
    counters: LinkCounters,
}

impl MavlinkEndpoint {
    /// Validates `config`, binds the socket and makes it non-blocking.
    pub fn open(config: LinkConfig) -> Result<MavlinkEndpoint, LinkOpenError> {
        config.validate()?;
        let bind = config.bind;
        let socket =
            UdpSocket::bind(bind).map_err(|source| LinkOpenError::Bind { addr: bind, source })?;
        socket
            .set_nonblocking(true)
            .map_err(|source| LinkOpenError::NonBlocking { addr: bind, source })?;
        let local_addr = socket
            .local_addr()
            .map_err(|source| LinkOpenError::Bind { addr: bind, source })?;
        Ok(MavlinkEndpoint {
            config,
            socket,
            local_addr,
            destination: config.remote,
            destination_locked: false,
            schedule: StreamSchedule::new(&config.rates),
            one_shot: [false; Stream::COUNT],
            writer: FrameWriter::new(config.system_id, config.component_id),
            rx_buf: vec![0u8; MAX_DATAGRAM].into_boxed_slice(),
            last_good: None,
            last_peer_heartbeat: None,
            counters: LinkCounters::default(),
        })
    }

    /// The bound local address (useful when binding port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Where the streams currently go.
    pub fn destination(&self) -> SocketAddr {
        self.destination
    }

    /// The configuration the endpoint was opened with.
    pub fn config(&self) -> &LinkConfig {
        &self.config
    }

    /// Link statistics so far.
    pub fn counters(&self) -> LinkCounters {
        self.counters
    }

    /// Current interval of `stream` in ns (`None` = disabled).
    pub fn stream_interval_ns(&self, stream: Stream) -> Option<u64> {
        self.schedule.interval_ns(stream)
    }

    /// Last peer HEARTBEAT: (time ns as given to `poll`, system id, component id).
    pub fn last_peer_heartbeat(&self) -> Option<(u64, u8, u8)> {
        self.last_peer_heartbeat
    }

    /// Sends every stream due at `t_ns` (vehicle time since boot, monotonic) built from
    /// `telemetry`, plus one-shot REQUEST_MESSAGE answers. A snapshot with a non-finite state
    /// value is counted and replaced by the last good one (HEARTBEAT still uses its mode
    /// fields). Returns the number of frames sent. Does not allocate.
    pub fn send_due(&mut self, t_ns: u64, telemetry: &Telemetry) -> usize {
        if telemetry.is_finite() {
            self.last_good = Some(*telemetry);
        } else {
            self.counters.telemetry_rejected += 1;
        }
        let mut sent = 0;
        for stream in Stream::ALL {
            let due = self.schedule.take_due(stream, t_ns);
            if !(due || self.one_shot[stream.index()]) {
                continue;
            }
            let msg = match (stream, self.last_good) {
                (Stream::Heartbeat, _) => outbound::heartbeat(telemetry),
                (_, Some(good)) => outbound::stream_message(stream, &good),
                (_, None) => continue,
            };
            self.one_shot[stream.index()] = false;
            if self.send(&msg, self.destination) {
                sent += 1;
            }
        }
        sent
    }

    /// Drains pending datagrams (at most `max_datagrams_per_poll`) without blocking, parses
    /// every frame, answers link-level requests itself and hands the rest to `handler`.
    /// `t_ns` is the vehicle time since boot. Returns the number of frames that parsed.
    pub fn poll<F>(&mut self, t_ns: u64, handler: &mut F) -> usize
    where
        F: FnMut(Inbound) -> Option<MavResult>,
    {
        let mut buf = std::mem::take(&mut self.rx_buf);
        let before = self.counters.rx_frames_ok;
        for _ in 0..self.config.max_datagrams_per_poll {
            match self.socket.recv_from(&mut buf) {
                Ok((n, src)) => {
                    self.counters.rx_datagrams += 1;
                    if self.config.follow_first_sender && !self.destination_locked {
                        self.destination = src;
                        self.destination_locked = true;
                    }
                    self.handle_datagram(&buf[..n], src, t_ns, handler);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(_) => self.counters.rx_socket_errors += 1,
            }
        }
        self.rx_buf = buf;
        (self.counters.rx_frames_ok - before) as usize
    }

    /// Parses one datagram (exposed for tests that feed bytes without a socket round trip).
    pub fn handle_datagram<F>(
        &mut self,
        datagram: &[u8],
        src: SocketAddr,
        t_ns: u64,
        handler: &mut F,
    ) where
        F: FnMut(Inbound) -> Option<MavResult>,
    {
        for item in FrameScanner::new(datagram) {
            match item {
                Scanned::Frame(frame) => self.handle_frame(&frame, src, t_ns, handler),
                Scanned::Garbage(n) => self.counters.rx_garbage_bytes += n as u64,
                Scanned::Rejected(kind) => match kind {
                    RejectKind::BadCrc => self.counters.rx_bad_crc += 1,
                    RejectKind::UnknownMessage => self.counters.rx_unknown_message += 1,
                    RejectKind::Truncated => self.counters.rx_truncated += 1,
                    RejectKind::BadHeader => self.counters.rx_bad_header += 1,
                },
            }
        }
    }

    fn handle_frame<F>(&mut self, frame: &RawFrame<'_>, src: SocketAddr, t_ns: u64, handler: &mut F)
    where
        F: FnMut(Inbound) -> Option<MavResult>,
    {
        let from = (frame.system_id, frame.component_id);
        let msg = match MavMessage::parse(frame.version, frame.message_id, frame.payload) {
            Ok(msg) => msg,
            Err(ParserError::InvalidEnum { .. }) if frame.message_id == COMMAND_LONG_ID => {
                self.counters.rx_frames_ok += 1;
                let cmd = CommandLong::from_payload(frame.payload);
                self.handle_command(&cmd, from, src, t_ns, handler);
                return;
            }
            Err(ParserError::UnknownMessage { .. }) => {
                self.counters.rx_unknown_message += 1;
                return;
            }
            Err(_) => {
                self.counters.rx_decode_errors += 1;
                return;
            }
        };
        self.counters.rx_frames_ok += 1;
        let (sys, comp) = (self.config.system_id, self.config.component_id);
        match &msg {
            MavMessage::HEARTBEAT(_) => {
                self.last_peer_heartbeat = Some((t_ns, from.0, from.1));
                handler(Inbound::Heartbeat {
                    sysid: from.0,
                    compid: from.1,
                });
            }
            MavMessage::SET_ATTITUDE_TARGET(d) => match attitude_target(d, sys, comp) {
                Some(inbound) => {
                    handler(inbound);
                }
                None => self.counters.rx_not_for_us += 1,
            },
            MavMessage::COMMAND_LONG(d) => {
                let cmd = CommandLong::from_parsed(d);
                self.handle_command(&cmd, from, src, t_ns, handler);
            }
            MavMessage::TIMESYNC(d) if d.tc1 == 0 => {
                // PX4 answers a timesync request with its own clock in tc1 and the echo in ts1.
                let reply = MavMessage::TIMESYNC(TIMESYNC_DATA {
                    tc1: i64::try_from(t_ns).unwrap_or(i64::MAX),
                    ts1: d.ts1,
                    target_system: from.0,
                    target_component: from.1,
                });
                self.send(&reply, src);
            }
            _ => self.counters.rx_ignored += 1,
        }
    }

    fn handle_command<F>(
        &mut self,
        cmd: &CommandLong,
        from: (u8, u8),
        src: SocketAddr,
        t_ns: u64,
        handler: &mut F,
    ) where
        F: FnMut(Inbound) -> Option<MavResult>,
    {
        if !cmd.is_for(self.config.system_id, self.config.component_id) {
            self.counters.rx_not_for_us += 1;
            return;
        }
        let result = match cmd.command {
            MAV_CMD_SET_MESSAGE_INTERVAL => self.set_message_interval(cmd.params, t_ns),
            MAV_CMD_REQUEST_MESSAGE => self.request_message(cmd.params[0], src),
            MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES => self.request_message(148.0, src),
            _ => {
                let inbound = Inbound::Command {
                    command: cmd.command,
                    params: cmd.params,
                    from,
                };
                handler(inbound).unwrap_or_else(|| {
                    self.counters.unknown_commands += 1;
                    MavResult::MAV_RESULT_UNSUPPORTED
                })
            }
        };
        let frame = self
            .writer
            .encode_command_ack(cmd.command, cmd.known, result, from);
        Self::transmit(&self.socket, &mut self.counters, frame, src);
    }

    /// MAV_CMD_SET_MESSAGE_INTERVAL: param1 message id, param2 interval us (0 default, -1 off).
    fn set_message_interval(&mut self, params: [f32; 7], t_ns: u64) -> MavResult {
        let stream = message_id_param(params[0]).and_then(Stream::from_message_id);
        match (stream, IntervalRequest::from_param_us(params[1])) {
            (Some(stream), Some(request)) => {
                self.schedule.set(stream, request, t_ns);
                MavResult::MAV_RESULT_ACCEPTED
            }
            _ => MavResult::MAV_RESULT_DENIED,
        }
    }

    /// MAV_CMD_REQUEST_MESSAGE: streamed messages go out with the next `send_due`,
    /// AUTOPILOT_VERSION at once; anything else is denied, as PX4 does for unknown streams.
    fn request_message(&mut self, message_id: f32, src: SocketAddr) -> MavResult {
        let id = message_id_param(message_id);
        if id == Some(AUTOPILOT_VERSION_ID) {
            let msg = outbound::autopilot_version(self.config.system_id);
            self.send(&msg, src);
            return MavResult::MAV_RESULT_ACCEPTED;
        }
        match id.and_then(Stream::from_message_id) {
            Some(stream) => {
                self.one_shot[stream.index()] = true;
                MavResult::MAV_RESULT_ACCEPTED
            }
            None => MavResult::MAV_RESULT_DENIED,
        }
    }

    fn send(&mut self, msg: &MavMessage, to: SocketAddr) -> bool {
        let frame = self.writer.encode(msg);
        Self::transmit(&self.socket, &mut self.counters, frame, to)
    }

    fn transmit(
        socket: &UdpSocket,
        counters: &mut LinkCounters,
        frame: &[u8],
        to: SocketAddr,
    ) -> bool {
        match socket.send_to(frame, to) {
            Ok(_) => {
                counters.tx_frames += 1;
                true
            }
            Err(_) => {
                counters.tx_errors += 1;
                false
            }
        }
    }
}

/// A message id from a float command parameter (PX4 rounds: `(int)(param + 0.5f)`).
fn message_id_param(p: f32) -> Option<u32> {
    (-0.5..16_777_215.5)
        .contains(&p)
        .then_some((p + 0.5) as u32)
}

#[cfg(test)]
#[path = "endpoint_tests.rs"]
mod tests;
