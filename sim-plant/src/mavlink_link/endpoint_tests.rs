//! The endpoint over real loopback sockets against a peer built from the crate.

use std::net::UdpSocket;
use std::time::Duration;

use super::*;
use crate::mavlink_link::config::LinkConfig;
use mavlink::dialects::common::{
    AttitudeTargetTypemask, MavCmd, COMMAND_LONG_DATA, HEARTBEAT_DATA, SET_ATTITUDE_TARGET_DATA,
};
use mavlink::{MavHeader, MavlinkReader, MavlinkVersion};

const MS: u64 = 1_000_000;

struct Peer {
    socket: UdpSocket,
    writer: FrameWriter,
}

impl Peer {
    fn new() -> Peer {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        socket
            .set_read_timeout(Some(Duration::from_millis(500)))
            .unwrap();
        Peer {
            socket,
            writer: FrameWriter::new(42, 191),
        }
    }

    fn send(&mut self, to: SocketAddr, msg: &MavMessage) {
        let bytes = self.writer.encode(msg).to_vec();
        self.send_raw(to, &bytes);
    }

    fn send_raw(&self, to: SocketAddr, bytes: &[u8]) {
        self.socket.send_to(bytes, to).unwrap();
    }

    fn recv(&self) -> Option<(MavHeader, MavMessage)> {
        let mut buf = [0u8; 2048];
        let (n, _) = self.socket.recv_from(&mut buf).ok()?;
        MavlinkReader::new(&buf[..n])
            .read_message::<MavMessage>(MavlinkVersion::V2)
            .ok()
    }

    /// Receives until a COMMAND_ACK arrives (streams may be interleaved).
    fn recv_ack(&self) -> mavlink::dialects::common::COMMAND_ACK_DATA {
        for _ in 0..50 {
            match self.recv() {
                Some((_, MavMessage::COMMAND_ACK(ack))) => return ack,
                Some(_) => continue,
                None => break,
            }
        }
        panic!("no COMMAND_ACK received");
    }
}

fn open(peer: &Peer) -> MavlinkEndpoint {
    let config = LinkConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        remote: peer.socket.local_addr().unwrap(),
        ..LinkConfig::px4_sitl(0)
    };
    MavlinkEndpoint::open(config).unwrap()
}

fn command(cmd: MavCmd, params: [f32; 7], target: (u8, u8)) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: params[0],
        param2: params[1],
        param3: params[2],
        param4: params[3],
        param5: params[4],
        param6: params[5],
        param7: params[6],
        command: cmd,
        target_system: target.0,
        target_component: target.1,
        confirmation: 0,
    })
}

/// Polls until at least one frame was handled, collecting what reaches the vehicle.
fn poll_until_frame(ep: &mut MavlinkEndpoint, t: u64, out: &mut Vec<Inbound>) {
    for _ in 0..200 {
        let mut handler = |i: Inbound| {
            out.push(i);
            match i {
                Inbound::Command { command: 400, .. } => Some(MavResult::MAV_RESULT_ACCEPTED),
                _ => None,
            }
        };
        if ep.poll(t, &mut handler) > 0 {
            return;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    panic!("nothing arrived at the endpoint");
}

#[test]
fn first_send_due_emits_all_six_streams_to_the_remote() {
    let peer = Peer::new();
    let mut ep = open(&peer);
    assert_eq!(ep.send_due(0, &Telemetry::default()), 6);
    let mut ids: Vec<u32> = (0..6)
        .map(|_| peer.recv().unwrap().1.message_id())
        .collect();
    ids.sort_unstable();
    assert_eq!(ids, [0, 31, 32, 105, 291, 331]);
    // Nothing more due 1 ms later.
    assert_eq!(ep.send_due(MS, &Telemetry::default()), 0);
    assert_eq!(ep.counters().tx_frames, 6);
}

#[test]
fn set_message_interval_is_acked_and_applied() {
    let mut peer = Peer::new();
    let mut ep = open(&peer);
    let to = ep.local_addr();
    let mut seen = Vec::new();
    let p = [331.0, 10_000.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, p, (1, 1)),
    );
    poll_until_frame(&mut ep, MS, &mut seen);
    let ack = peer.recv_ack();
    assert_eq!(ack.command, MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL);
    assert_eq!(ack.result, MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!((ack.target_system, ack.target_component), (42, 191));
    assert_eq!(ep.stream_interval_ns(Stream::Odometry), Some(10 * MS));
    assert!(
        seen.is_empty(),
        "SET_MESSAGE_INTERVAL must not reach the vehicle"
    );

    // Disable, restore, and a message id that is not streamed.
    let p = [331.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, p, (1, 1)),
    );
    poll_until_frame(&mut ep, 2 * MS, &mut seen);
    assert_eq!(peer.recv_ack().result, MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!(ep.stream_interval_ns(Stream::Odometry), None);
    let p = [331.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, p, (1, 1)),
    );
    poll_until_frame(&mut ep, 3 * MS, &mut seen);
    assert_eq!(peer.recv_ack().result, MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!(ep.stream_interval_ns(Stream::Odometry), Some(33_333_333));
    let p = [33.0, 10_000.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, p, (1, 1)),
    );
    poll_until_frame(&mut ep, 4 * MS, &mut seen);
    assert_eq!(peer.recv_ack().result, MavResult::MAV_RESULT_DENIED);
}

#[test]
fn commands_go_to_the_handler_and_unknown_ids_are_unsupported() {
    let mut peer = Peer::new();
    let mut ep = open(&peer);
    let to = ep.local_addr();
    let mut seen = Vec::new();
    let arm = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm, (1, 1)),
    );
    poll_until_frame(&mut ep, MS, &mut seen);
    assert_eq!(
        seen,
        [Inbound::Command {
            command: 400,
            params: arm,
            from: (42, 191)
        }]
    );
    assert_eq!(peer.recv_ack().result, MavResult::MAV_RESULT_ACCEPTED);

    // Handler returns None: UNSUPPORTED, counted.
    peer.send(to, &command(MavCmd::MAV_CMD_DO_SET_MODE, arm, (1, 0)));
    poll_until_frame(&mut ep, 2 * MS, &mut seen);
    let ack = peer.recv_ack();
    assert_eq!(ack.command, MavCmd::MAV_CMD_DO_SET_MODE);
    assert_eq!(ack.result, MavResult::MAV_RESULT_UNSUPPORTED);

    // A command id the dialect does not know: raw 60000 in the payload.
    let mut frame = peer
        .writer
        .encode(&command(MavCmd::MAV_CMD_DO_SET_MODE, arm, (1, 1)))
        .to_vec();
    let len = usize::from(frame[1]);
    frame[10 + 28..10 + 30].copy_from_slice(&60000u16.to_le_bytes());
    let crc = mavlink::calculate_crc(&frame[1..10 + len], 152);
    frame[10 + len..10 + len + 2].copy_from_slice(&crc.to_le_bytes());
    peer.send_raw(to, &frame);
    poll_until_frame(&mut ep, 3 * MS, &mut seen);
    assert!(matches!(
        seen.last(),
        Some(Inbound::Command { command: 60000, .. })
    ));
    // The ack carries 60000, which the crate cannot parse into MavCmd: check raw bytes.
    let mut buf = [0u8; 512];
    let (n, _) = peer.socket.recv_from(&mut buf).unwrap();
    assert_eq!(u32::from_le_bytes([buf[7], buf[8], buf[9], 0]), 77);
    assert_eq!(u16::from_le_bytes([buf[10], buf[11]]), 60000);
    assert_eq!(buf[12], MavResult::MAV_RESULT_UNSUPPORTED as u8);
    let crc = mavlink::calculate_crc(&buf[1..n - 2], 143);
    assert_eq!(crc.to_le_bytes(), [buf[n - 2], buf[n - 1]]);
    assert_eq!(ep.counters().unknown_commands, 2);

    // Not for us (PX4's rule: exact system id): no ack, counted, handler not called.
    let before = seen.len();
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm, (0, 0)),
    );
    peer.send(
        to,
        &command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm, (1, 77)),
    );
    poll_until_frame(&mut ep, 4 * MS, &mut seen);
    std::thread::sleep(Duration::from_millis(5));
    ep.poll(4 * MS, &mut |_| None);
    assert_eq!(seen.len(), before);
    assert_eq!(ep.counters().rx_not_for_us, 2);
}

#[test]
fn attitude_target_arrives_intact_and_is_filtered_by_target() {
    let mut peer = Peer::new();
    let mut ep = open(&peer);
    let to = ep.local_addr();
    let target = |sys: u8, time_boot_ms: u32| {
        MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            time_boot_ms,
            q: [0.5, 0.5, -0.5, 0.5],
            body_roll_rate: 0.125,
            body_pitch_rate: -0.25,
            body_yaw_rate: 0.5,
            thrust: 0.625,
            target_system: sys,
            target_component: 1,
            type_mask: AttitudeTargetTypemask::from_bits_retain(7),
            thrust_body: [0.0625, 0.125, -0.75],
        })
    };
    let mut seen = Vec::new();
    peer.send(to, &target(9, 1));
    peer.send(to, &target(1, 2));
    peer.send(to, &target(0, 3));
    std::thread::sleep(Duration::from_millis(5));
    poll_until_frame(&mut ep, MS, &mut seen);
    let expected = |time_boot_ms| Inbound::AttitudeTarget {
        time_boot_ms,
        q: [0.5, 0.5, -0.5, 0.5],
        body_rates: [0.125, -0.25, 0.5],
        thrust: 0.625,
        type_mask: 7,
        thrust_body: [0.0625, 0.125, -0.75],
    };
    assert_eq!(seen, [expected(2), expected(3)]);
    assert_eq!(ep.counters().rx_not_for_us, 1);
}

#[test]
fn bad_datagrams_are_counted_and_the_link_keeps_going() {
    let mut peer = Peer::new();
    let mut ep = open(&peer);
    let to = ep.local_addr();
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
    let mut bad = peer.writer.encode(&hb).to_vec();
    let n = bad.len();
    bad[n - 2] ^= 0x5A;
    peer.send_raw(to, &[0x00, 0x13, 0x37, 0x42, 0x99, 0xAB, 0xCD]);
    peer.send_raw(to, &bad);
    peer.send_raw(to, &bad[..n - 4]);
    peer.send(to, &hb);
    std::thread::sleep(Duration::from_millis(5));
    let mut seen = Vec::new();
    poll_until_frame(&mut ep, 5 * MS, &mut seen);
    assert_eq!(
        seen,
        [Inbound::Heartbeat {
            sysid: 42,
            compid: 191
        }]
    );
    let c = ep.counters();
    assert_eq!(c.rx_datagrams, 4);
    assert_eq!(c.rx_garbage_bytes, 7);
    assert_eq!((c.rx_bad_crc, c.rx_truncated), (1, 1));
    assert_eq!(c.rx_frames_ok, 1);
    assert_eq!(ep.last_peer_heartbeat(), Some((5 * MS, 42, 191)));
}

#[test]
fn streams_follow_the_first_sender_and_sending_to_nobody_is_not_an_error() {
    let nobody = Peer::new();
    let nobody_addr = nobody.socket.local_addr().unwrap();
    drop(nobody);
    let mut peer = Peer::new();
    let config = LinkConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        remote: nobody_addr,
        ..LinkConfig::px4_sitl(0)
    };
    let mut ep = MavlinkEndpoint::open(config).unwrap();
    for k in 0..100 {
        ep.send_due(k * 10 * MS, &Telemetry::default());
    }
    assert_eq!(
        ep.counters().tx_errors,
        0,
        "no ICMP errors on unconnected UDP"
    );
    peer.send(
        ep.local_addr(),
        &MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()),
    );
    poll_until_frame(&mut ep, S_1, &mut Vec::new());
    assert_eq!(ep.destination(), peer.socket.local_addr().unwrap());
    assert!(ep.send_due(S_1 + 100 * MS, &Telemetry::default()) > 0);
    assert!(peer.recv().is_some());
}

const S_1: u64 = 1_000_000_000;

#[test]
fn non_finite_telemetry_is_counted_and_the_last_good_snapshot_sent() {
    let peer = Peer::new();
    let mut ep = open(&peer);
    let good = Telemetry {
        position_ned_m: nalgebra::Vector3::new(1.0, 2.0, -3.0),
        ..Telemetry::default()
    };
    ep.send_due(0, &good);
    while peer.recv().is_some() {}
    let bad = Telemetry {
        position_ned_m: nalgebra::Vector3::new(f64::NAN, 0.0, 0.0),
        ..good
    };
    ep.send_due(40 * MS, &bad);
    assert_eq!(ep.counters().telemetry_rejected, 1);
    let mut got_position = false;
    while let Some((_, msg)) = peer.recv() {
        if let MavMessage::LOCAL_POSITION_NED(p) = msg {
            assert_eq!((p.x, p.y, p.z), (1.0, 2.0, -3.0));
            got_position = true;
        }
    }
    assert!(got_position);
}

#[test]
fn request_message_sends_one_shot_and_timesync_is_answered() {
    let mut peer = Peer::new();
    let mut ep = open(&peer);
    let to = ep.local_addr();
    ep.send_due(0, &Telemetry::default());
    while peer.recv().is_some() {}
    let p = [291.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    peer.send(to, &command(MavCmd::MAV_CMD_REQUEST_MESSAGE, p, (1, 1)));
    poll_until_frame(&mut ep, MS, &mut Vec::new());
    assert_eq!(peer.recv_ack().result, MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!(ep.send_due(2 * MS, &Telemetry::default()), 1);
    assert_eq!(peer.recv().unwrap().1.message_id(), 291);

    let sync = mavlink::dialects::common::TIMESYNC_DATA {
        tc1: 0,
        ts1: 123_456,
        target_system: 1,
        target_component: 1,
    };
    peer.send(to, &MavMessage::TIMESYNC(sync));
    poll_until_frame(&mut ep, 7 * MS, &mut Vec::new());
    let Some((_, MavMessage::TIMESYNC(reply))) = peer.recv() else {
        panic!("no TIMESYNC reply")
    };
    assert_eq!((reply.tc1, reply.ts1), (7 * MS as i64, 123_456));
    assert_eq!((reply.target_system, reply.target_component), (42, 191));
}

#[test]
fn bad_config_is_rejected() {
    let mut config = LinkConfig::px4_sitl(1);
    config.rates.odometry_hz = f64::NAN;
    assert!(matches!(
        MavlinkEndpoint::open(config),
        Err(LinkOpenError::Config(_))
    ));
    let zero_id = LinkConfig {
        system_id: 0,
        ..LinkConfig::px4_sitl(1)
    };
    assert!(zero_id.validate().is_err());
    let sitl = LinkConfig::px4_sitl(1);
    assert_eq!(sitl.bind.port(), 14581);
    assert_eq!(sitl.remote.port(), 14541);
    assert_eq!((sitl.system_id, sitl.component_id), (2, 1));
}
