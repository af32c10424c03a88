use super::*;
use crate::mavlink_link::outbound;
use crate::mavlink_link::telemetry::{px4_custom_mode, Telemetry};
use mavlink::dialects::common::{COMMAND_LONG_DATA, HEARTBEAT_DATA};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};

fn hex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// Frames produced by pymavlink 2.4.50 (`MAVLink(srcSystem=1, srcComponent=1)`, `msg.pack`),
/// ESC_STATUS packed by hand with pymavlink's x25crc (its bundled common.xml lacks #291).
const PY_HEARTBEAT_SEQ0: &str = "fd09000000010100000000000600020c810403d291";
const PY_ATTITUDE_QUATERNION_SEQ1: &str =
    "fd2000000101011f000040e201000000003f0000003f000000bf0000003f0000003e000080be0000003f4a02";
const PY_ACK_60000_UNSUPPORTED_SEQ2: &str = "fd0a00000201014d000060ea0300000000002abfb084";
const PY_ACK_511_ACCEPTED_SEQ3: &str = "fd0a00000301014d0000ff010000000000002abfd2ff";
const PY_ODOMETRY_SEQ4: &str = concat!(
    "fde800000401014b0100a0252600000000000000c03f000000c00000a0bf0000003f0000003f000000bf",
    "0000003f0000403f000000bf0000803e0000003e000080be0000003f0000803e0000c07f0000c07f0000c07f",
    "0000c07f0000c07f0000803e0000c07f0000c07f0000c07f0000c07f0000003f0000c07f0000c07f0000c07f",
    "0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f",
    "0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f0000c07f",
    "0000c07f0000c07f0000c07f0000c07f0000c07f010103085fd9"
);
const PY_ESC_STATUS_SEQ255: &str =
    "fd160000ff0101230100a025260000000000b91c0000c31c0000cc1c0000d61ce279";

/// The snapshot the pymavlink frames above were built from.
fn reference_telemetry() -> Telemetry {
    Telemetry {
        time_boot_ns: 2_500_000_000,
        base_mode: 129,
        custom_mode: px4_custom_mode(6, 0),
        system_status: 4,
        position_ned_m: Vector3::new(1.5, -2.0, -1.25),
        velocity_ned_m_s: Vector3::new(0.75, -0.5, 0.25),
        attitude_body_to_ned: UnitQuaternion::from_quaternion(Quaternion::new(0.5, 0.5, -0.5, 0.5)),
        body_rates_frd_rad_s: Vector3::new(0.125, -0.25, 0.5),
        rotor_speeds_rad_s: [770.0, 771.0, 772.0, 773.0],
        position_variance_ned_m2: [0.25, 0.25, 0.5],
        reset_counter: 3,
        ..Telemetry::default()
    }
}

#[test]
fn frames_are_byte_exact_against_pymavlink() {
    let t = reference_telemetry();
    let mut w = FrameWriter::new(1, 1);
    assert_eq!(w.encode(&outbound::heartbeat(&t)), hex(PY_HEARTBEAT_SEQ0));
    let att = Telemetry {
        time_boot_ns: 123_456_000_000,
        ..t
    };
    assert_eq!(
        w.encode(&outbound::attitude_quaternion(&att)),
        hex(PY_ATTITUDE_QUATERNION_SEQ1)
    );
    assert_eq!(
        w.encode_command_ack(60000, None, MavResult::MAV_RESULT_UNSUPPORTED, (42, 191)),
        hex(PY_ACK_60000_UNSUPPORTED_SEQ2)
    );
    let known = Some(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL);
    assert_eq!(
        w.encode_command_ack(511, known, MavResult::MAV_RESULT_ACCEPTED, (42, 191)),
        hex(PY_ACK_511_ACCEPTED_SEQ3)
    );
    assert_eq!(w.encode(&outbound::odometry(&t)), hex(PY_ODOMETRY_SEQ4));
    while w.next_sequence() != 255 {
        w.encode(&outbound::heartbeat(&t));
    }
    assert_eq!(
        w.encode(&outbound::esc_status(&t)),
        hex(PY_ESC_STATUS_SEQ255)
    );
    assert_eq!(w.next_sequence(), 0, "sequence wraps after 255");
}

#[test]
fn crc_of_known_frame_matches_the_crate() {
    // HEARTBEAT CRC_EXTRA is 50; checksum over bytes 1.. of the frame up to the CRC.
    let frame = hex(PY_HEARTBEAT_SEQ0);
    let n = frame.len();
    let crc = calculate_crc(&frame[1..n - 2], 50);
    assert_eq!(crc.to_le_bytes(), [frame[n - 2], frame[n - 1]]);
    assert_eq!(crc, 0x91d2);
}

fn scan(buf: &[u8]) -> Vec<String> {
    FrameScanner::new(buf)
        .map(|s| match s {
            Scanned::Frame(f) => format!("frame {} v{:?}", f.message_id, f.version),
            Scanned::Rejected(k) => format!("{k:?}"),
            Scanned::Garbage(n) => format!("garbage {n}"),
        })
        .collect()
}

fn command_long_frame(seq: u8) -> Vec<u8> {
    let mut w = FrameWriter::new(42, 191);
    while w.next_sequence() != seq {
        w.encode(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()));
    }
    let cmd = COMMAND_LONG_DATA {
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        param1: 1.0,
        target_system: 1,
        target_component: 1,
        ..COMMAND_LONG_DATA::default()
    };
    w.encode(&MavMessage::COMMAND_LONG(cmd)).to_vec()
}

#[test]
fn several_frames_in_one_datagram_are_all_found() {
    let mut d = command_long_frame(0);
    d.extend(hex(PY_HEARTBEAT_SEQ0));
    d.extend(hex(PY_ODOMETRY_SEQ4));
    assert_eq!(scan(&d), ["frame 76 vV2", "frame 0 vV2", "frame 331 vV2"]);
}

#[test]
fn garbage_bad_crc_and_truncation_are_reported_once_and_valid_frames_survive() {
    let good = command_long_frame(3);
    assert_eq!(scan(&[0x11, 0x22, 0x33]), ["garbage 3"]);

    let mut bad = good.clone();
    let n = bad.len();
    bad[n - 1] ^= 0xFF;
    let mut d = vec![1, 2, 3, 4];
    d.extend(&bad);
    d.extend(&good);
    assert_eq!(scan(&d), ["garbage 4", "BadCrc", "frame 76 vV2"]);

    // A corrupt byte inside the payload: same verdict.
    let mut bad_payload = good.clone();
    bad_payload[12] ^= 0x01;
    assert_eq!(scan(&bad_payload), ["BadCrc"]);

    // A frame cut short: truncated; the good one after a stray marker claiming 255 bytes is
    // still found.
    assert_eq!(scan(&good[..good.len() - 3]), ["Truncated"]);
    let mut d = vec![0xFD, 0xFF, 0x00];
    d.extend(&good);
    assert_eq!(scan(&d), ["Truncated", "frame 76 vV2"]);
}

#[test]
fn unknown_ids_bad_flags_v1_and_signed_frames() {
    // Message id 0x0ABCDE with a checksum made with CRC_EXTRA 0: unknown to the dialect.
    let mut unknown = vec![0xFD, 3, 0, 0, 7, 9, 1, 0xDE, 0xBC, 0x0A, 1, 2, 3];
    let crc = calculate_crc(&unknown[1..], 0);
    unknown.extend(crc.to_le_bytes());
    assert_eq!(scan(&unknown), ["UnknownMessage"]);

    let mut flagged = hex(PY_HEARTBEAT_SEQ0);
    flagged[2] = 0x04;
    assert_eq!(scan(&flagged), ["BadHeader"]);

    // MAVLink 1 HEARTBEAT built by hand: STX FE, len 9, seq, sys, comp, id 0.
    let mut v1 = vec![0xFE, 9, 5, 255, 190, 0, 0, 0, 0, 0, 6, 8, 0, 0, 3];
    let crc = calculate_crc(&v1[1..], 50);
    v1.extend(crc.to_le_bytes());
    assert_eq!(scan(&v1), ["frame 0 vV1"]);

    // Signed MAVLink 2 frame: flag 0x01 and a 13-byte signature the endpoint does not check.
    let mut signed = hex(PY_HEARTBEAT_SEQ0);
    signed[2] = 0x01;
    let n = signed.len();
    let crc = calculate_crc(&signed[1..n - 2], 50);
    signed[n - 2..].copy_from_slice(&crc.to_le_bytes());
    signed.extend([0u8; 13]);
    assert_eq!(scan(&signed), ["frame 0 vV2"]);
}

#[test]
fn sequence_numbers_increment_per_frame() {
    let t = Telemetry::default();
    let mut w = FrameWriter::new(3, 1);
    for k in 0..600u32 {
        let bytes = w.encode(&outbound::stream_message(
            crate::mavlink_link::Stream::ALL[(k % 6) as usize],
            &t,
        ));
        assert_eq!(bytes[4], (k % 256) as u8, "sequence of frame {k}");
        assert_eq!((bytes[5], bytes[6]), (3, 1), "sender ids");
    }
}
