//! MAVLink framing on datagrams: a scanner that reports every rejected byte run by kind, and a
//! frame writer that serialises into one reused buffer with a per-link sequence number.
//!
//! The crate's `MavlinkReader` resynchronises silently (bad candidates are skipped without a
//! report), so the endpoint frames datagrams itself and uses the crate for the CRC
//! (`calculate_crc` with the dialect's CRC_EXTRA), message parsing (`Message::parse`) and
//! serialisation (`MAVLinkV2MessageRaw`).

use mavlink::dialects::common::{MavCmd, MavMessage, MavResult, COMMAND_ACK_DATA};
use mavlink::{calculate_crc, MAVLinkV2MessageRaw, MavHeader, MavlinkVersion, Message};

const STX_V1: u8 = 0xFE;
const STX_V2: u8 = 0xFD;
const HEADER_V1: usize = 6;
const HEADER_V2: usize = 10;
const CHECKSUM: usize = 2;
const SIGNATURE: usize = 13;
const IFLAG_SIGNED: u8 = 0x01;
/// MAVLink message id of COMMAND_ACK.
const COMMAND_ACK_ID: u32 = 77;
/// A placeholder command whose second byte is non-zero, so the serialised payload always keeps
/// both command bytes (MAVLink 2 trims trailing zeros) and they can be overwritten.
const ACK_PLACEHOLDER: MavCmd = MavCmd::MAV_CMD_REQUEST_MESSAGE;

/// Why a candidate frame was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RejectKind {
    /// Known message id, checksum mismatch.
    BadCrc,
    /// Message id not in the common dialect (its checksum cannot be verified).
    UnknownMessage,
    /// The datagram ends before the frame the header announces.
    Truncated,
    /// MAVLink 2 incompatibility flags other than "signed".
    BadHeader,
}

/// A frame whose checksum is good, borrowed from the datagram.
#[derive(Debug, Clone, Copy)]
pub struct RawFrame<'a> {
    /// MAVLink 1 or 2.
    pub version: MavlinkVersion,
    /// Sender's sequence number.
    pub sequence: u8,
    /// Sender system id.
    pub system_id: u8,
    /// Sender component id.
    pub component_id: u8,
    /// Message id.
    pub message_id: u32,
    /// Payload bytes (possibly trimmed by MAVLink 2 zero truncation).
    pub payload: &'a [u8],
}

/// One item found in a datagram.
#[derive(Debug, Clone, Copy)]
pub enum Scanned<'a> {
    /// A checksum-valid frame.
    Frame(RawFrame<'a>),
    /// A rejected candidate (counted once; candidates inside its span are not counted again).
    Rejected(RejectKind),
    /// This many bytes outside any frame or rejected candidate.
    Garbage(usize),
}

/// Walks a datagram; after a rejected candidate it resumes at the next byte so a valid frame
/// hidden behind a corrupt header is still found.
pub struct FrameScanner<'a> {
    buf: &'a [u8],
    pos: usize,
    /// End of the last counted rejected candidate: nothing before it is counted again.
    shadow_end: usize,
}

impl<'a> FrameScanner<'a> {
    /// Scanner over one datagram.
    pub fn new(buf: &'a [u8]) -> FrameScanner<'a> {
        FrameScanner {
            buf,
            pos: 0,
            shadow_end: 0,
        }
    }

    /// Bytes in `[from, to)` outside the shadow of rejected candidates.
    fn uncovered(&self, from: usize, to: usize) -> usize {
        to.saturating_sub(from.max(self.shadow_end))
    }
}

impl<'a> Iterator for FrameScanner<'a> {
    type Item = Scanned<'a>;

    fn next(&mut self) -> Option<Scanned<'a>> {
        loop {
            if self.pos >= self.buf.len() {
                return None;
            }
            let rest = &self.buf[self.pos..];
            let marker = rest.iter().position(|&b| b == STX_V1 || b == STX_V2);
            let skip = marker.unwrap_or(rest.len());
            if skip > 0 {
                let counted = self.uncovered(self.pos, self.pos + skip);
                self.pos += skip;
                if counted > 0 {
                    return Some(Scanned::Garbage(counted));
                }
                continue;
            }
            match check_candidate(rest) {
                Ok((frame, len)) => {
                    self.pos += len;
                    return Some(Scanned::Frame(frame));
                }
                Err((kind, span)) => {
                    let counted = self.pos >= self.shadow_end;
                    if counted {
                        self.shadow_end = self.pos + span.max(1);
                    }
                    self.pos += 1;
                    if counted {
                        return Some(Scanned::Rejected(kind));
                    }
                }
            }
        }
    }
}

/// Validates the candidate frame at the start of `rest` (which starts with a marker byte).
/// Returns the frame and its length, or the reject kind and the span the candidate claims.
fn check_candidate(rest: &[u8]) -> Result<(RawFrame<'_>, usize), (RejectKind, usize)> {
    let v2 = rest[0] == STX_V2;
    let header = if v2 { HEADER_V2 } else { HEADER_V1 };
    if rest.len() < header {
        return Err((RejectKind::Truncated, rest.len()));
    }
    let payload_len = usize::from(rest[1]);
    let flags = if v2 { rest[2] } else { 0 };
    let signature = if flags & IFLAG_SIGNED != 0 {
        SIGNATURE
    } else {
        0
    };
    let frame_len = header + payload_len + CHECKSUM + signature;
    if flags & !IFLAG_SIGNED != 0 {
        return Err((RejectKind::BadHeader, frame_len.min(rest.len())));
    }
    if rest.len() < frame_len {
        return Err((RejectKind::Truncated, rest.len()));
    }
    let (version, sequence, system_id, component_id, message_id) = if v2 {
        let id = u32::from_le_bytes([rest[7], rest[8], rest[9], 0]);
        (MavlinkVersion::V2, rest[4], rest[5], rest[6], id)
    } else {
        (
            MavlinkVersion::V1,
            rest[2],
            rest[3],
            rest[4],
            u32::from(rest[5]),
        )
    };
    let crc_at = header + payload_len;
    let received = u16::from_le_bytes([rest[crc_at], rest[crc_at + 1]]);
    // The dialect answers CRC_EXTRA 0 for ids it does not know (and a few known ids have 0).
    let extra = MavMessage::extra_crc(message_id);
    let known = || MavMessage::default_message_from_id(message_id).is_some();
    if extra == 0 && !known() {
        return Err((RejectKind::UnknownMessage, frame_len));
    }
    if received != calculate_crc(&rest[1..crc_at], extra) {
        let kind = if known() {
            RejectKind::BadCrc
        } else {
            RejectKind::UnknownMessage
        };
        return Err((kind, frame_len));
    }
    let frame = RawFrame {
        version,
        sequence,
        system_id,
        component_id,
        message_id,
        payload: &rest[header..crc_at],
    };
    Ok((frame, frame_len))
}

/// Serialises MAVLink 2 frames into one reused buffer; the sequence number counts every frame.
pub struct FrameWriter {
    raw: MAVLinkV2MessageRaw,
    sequence: u8,
    system_id: u8,
    component_id: u8,
}

impl FrameWriter {
    /// Writer for frames from `system_id`/`component_id`, first sequence number 0.
    pub fn new(system_id: u8, component_id: u8) -> FrameWriter {
        FrameWriter {
            raw: MAVLinkV2MessageRaw::new(),
            sequence: 0,
            system_id,
            component_id,
        }
    }

    /// Sequence number the next frame will carry.
    pub fn next_sequence(&self) -> u8 {
        self.sequence
    }

    fn header(&mut self) -> MavHeader {
        let header = MavHeader {
            system_id: u32::from(self.system_id),
            component_id: self.component_id,
            sequence: self.sequence,
        };
        self.sequence = self.sequence.wrapping_add(1);
        header
    }

    /// Serialises `msg` and returns the frame bytes.
    pub fn encode(&mut self, msg: &MavMessage) -> &[u8] {
        let header = self.header();
        self.raw.serialize_message(header, msg);
        self.raw.raw_bytes()
    }

    /// Serialises a COMMAND_ACK for any 16-bit command id, including ids the dialect's `MavCmd`
    /// does not know (those are written over a placeholder and the checksum recomputed).
    pub fn encode_command_ack(
        &mut self,
        command: u16,
        known: Option<MavCmd>,
        result: MavResult,
        target: (u8, u8),
    ) -> &[u8] {
        let ack = COMMAND_ACK_DATA {
            command: known.unwrap_or(ACK_PLACEHOLDER),
            result,
            progress: 0,
            result_param2: 0,
            target_system: target.0,
            target_component: target.1,
        };
        let header = self.header();
        self.raw
            .serialize_message(header, &MavMessage::COMMAND_ACK(ack));
        if known.is_none() {
            let payload_len = usize::from(self.raw.payload_length());
            let bytes = self.raw.as_mut_slice();
            bytes[HEADER_V2..HEADER_V2 + 2].copy_from_slice(&command.to_le_bytes());
            let crc_at = HEADER_V2 + payload_len;
            let crc = calculate_crc(&bytes[1..crc_at], MavMessage::extra_crc(COMMAND_ACK_ID));
            bytes[crc_at..crc_at + CHECKSUM].copy_from_slice(&crc.to_le_bytes());
        }
        self.raw.raw_bytes()
    }
}

#[cfg(test)]
#[path = "codec_tests.rs"]
mod tests;
