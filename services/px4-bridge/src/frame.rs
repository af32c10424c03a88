//! MAVLink framing with every rejected byte counted, and a frame writer with one reused buffer.
//!
//! Why not the crate's reader: `mavlink::MavlinkReader` (0.21) turns a UDP socket into one byte
//! stream, so a datagram that ends inside a candidate frame (a truncated frame, or garbage
//! holding 0xFD followed by a large length byte) keeps the following datagrams' good frames
//! waiting until the announced length has arrived (up to 280 bytes); and it skips bad
//! candidates (bad CRC, unknown id) silently, so nothing can be counted. Here a datagram is
//! scanned on its own (`final_chunk = true`), while a serial byte stream keeps an incomplete
//! candidate for the next read. The crate still does the CRC (`calculate_crc` with the
//! dialect's CRC_EXTRA), the parsing (`Message::parse`) and the serialisation.

use mavlink::dialects::common::MavMessage;
use mavlink::{calculate_crc, MAVLinkV2MessageRaw, MavHeader, MavlinkVersion, Message};

const STX_V1: u8 = 0xFE;
const STX_V2: u8 = 0xFD;
const HEADER_V1: usize = 6;
const HEADER_V2: usize = 10;
const CHECKSUM: usize = 2;
const SIGNATURE: usize = 13;
const IFLAG_SIGNED: u8 = 0x01;
/// Longest MAVLink 2 frame (signed, 255-byte payload).
pub const MAX_FRAME: usize = HEADER_V2 + 255 + CHECKSUM + SIGNATURE;

/// What the scanner dropped and kept, by kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameCounters {
    /// Frames with a good checksum that parsed.
    pub frames_ok: u64,
    /// Known message id, checksum mismatch.
    pub bad_crc: u64,
    /// Message id not in the common dialect.
    pub unknown_id: u64,
    /// The datagram ended before the frame its header announces.
    pub truncated: u64,
    /// MAVLink 2 incompatibility flags other than "signed".
    pub bad_header: u64,
    /// Good checksum, but the payload does not parse (e.g. an enum value out of range).
    pub decode_errors: u64,
    /// Bytes outside any frame or rejected candidate.
    pub garbage_bytes: u64,
}

impl FrameCounters {
    /// Everything dropped (candidates and garbage runs are counted once each).
    pub fn dropped(&self) -> u64 {
        self.bad_crc + self.unknown_id + self.truncated + self.bad_header + self.decode_errors
    }
}

// The parsed message is large; it lives on the stack for one frame (no allocation).
#[allow(clippy::large_enum_variant)]
enum Candidate {
    /// A good frame of this length, parsed.
    Frame(usize, MavHeader, MavMessage),
    /// Checksum good but the payload did not parse; skip the frame's length.
    Undecodable(usize),
    /// The frame runs past the end of the bytes at hand.
    Incomplete,
    /// Rejected: count it, shadow `span` bytes, resume at the next byte.
    Rejected(Reject, usize),
}

#[derive(Clone, Copy)]
enum Reject {
    BadCrc,
    UnknownId,
    BadHeader,
}

/// Scans MAVLink bytes: one datagram at a time, or a byte stream across reads.
#[derive(Debug, Default)]
pub struct FrameScanner {
    counters: FrameCounters,
    /// Bytes at the start of the next scan still inside a counted rejected candidate: not
    /// counted again as garbage or as further candidates.
    shadow: usize,
}

impl FrameScanner {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn counters(&self) -> FrameCounters {
        self.counters
    }

    /// Scans `bytes`, handing each good frame to `on_frame`. With `final_chunk` (a whole
    /// datagram) everything is consumed and an incomplete frame counts as truncated; without
    /// it (a stream) scanning stops at an incomplete frame. Returns the bytes consumed; the
    /// caller keeps the rest and prepends it to the next read.
    pub fn scan(
        &mut self,
        bytes: &[u8],
        final_chunk: bool,
        mut on_frame: impl FnMut(&MavHeader, &MavMessage),
    ) -> usize {
        let mut pos = 0;
        let mut shadow_end = self.shadow;
        while pos < bytes.len() {
            let rest = &bytes[pos..];
            let skip = rest
                .iter()
                .position(|&b| b == STX_V1 || b == STX_V2)
                .unwrap_or(rest.len());
            if skip > 0 {
                let uncovered = (pos + skip).saturating_sub(pos.max(shadow_end));
                self.counters.garbage_bytes += uncovered as u64;
                pos += skip;
                continue;
            }
            match check_candidate(rest) {
                Candidate::Frame(len, header, msg) => {
                    self.counters.frames_ok += 1;
                    on_frame(&header, &msg);
                    pos += len;
                }
                Candidate::Undecodable(len) => {
                    self.counters.decode_errors += 1;
                    pos += len;
                }
                Candidate::Incomplete if !final_chunk => break,
                Candidate::Incomplete => {
                    if pos >= shadow_end {
                        self.counters.truncated += 1;
                        shadow_end = bytes.len();
                    }
                    pos += 1;
                }
                Candidate::Rejected(kind, span) => {
                    if pos >= shadow_end {
                        match kind {
                            Reject::BadCrc => self.counters.bad_crc += 1,
                            Reject::UnknownId => self.counters.unknown_id += 1,
                            Reject::BadHeader => self.counters.bad_header += 1,
                        }
                        shadow_end = pos + span.max(1);
                    }
                    pos += 1;
                }
            }
        }
        self.shadow = if final_chunk {
            0
        } else {
            shadow_end.saturating_sub(pos)
        };
        pos
    }
}

/// Validates the candidate at the start of `rest` (which starts with a marker byte).
fn check_candidate(rest: &[u8]) -> Candidate {
    let v2 = rest[0] == STX_V2;
    let header_len = if v2 { HEADER_V2 } else { HEADER_V1 };
    if rest.len() < 3 {
        return Candidate::Incomplete;
    }
    let payload_len = usize::from(rest[1]);
    let flags = if v2 { rest[2] } else { 0 };
    let signature = if flags & IFLAG_SIGNED != 0 {
        SIGNATURE
    } else {
        0
    };
    let frame_len = header_len + payload_len + CHECKSUM + signature;
    if flags & !IFLAG_SIGNED != 0 {
        return Candidate::Rejected(Reject::BadHeader, frame_len.min(rest.len()));
    }
    if rest.len() < frame_len {
        return Candidate::Incomplete;
    }
    let (version, header, id) = if v2 {
        let header = MavHeader {
            sequence: rest[4],
            system_id: u32::from(rest[5]),
            component_id: rest[6],
        };
        let id = u32::from_le_bytes([rest[7], rest[8], rest[9], 0]);
        (MavlinkVersion::V2, header, id)
    } else {
        let header = MavHeader {
            sequence: rest[2],
            system_id: u32::from(rest[3]),
            component_id: rest[4],
        };
        (MavlinkVersion::V1, header, u32::from(rest[5]))
    };
    let crc_at = header_len + payload_len;
    let received = u16::from_le_bytes([rest[crc_at], rest[crc_at + 1]]);
    // The dialect answers CRC_EXTRA 0 for ids it does not know (a few known ids have 0 too).
    let extra = MavMessage::extra_crc(id);
    if extra == 0 && MavMessage::default_message_from_id(id).is_none() {
        return Candidate::Rejected(Reject::UnknownId, frame_len);
    }
    if received != calculate_crc(&rest[1..crc_at], extra) {
        return Candidate::Rejected(Reject::BadCrc, frame_len);
    }
    match MavMessage::parse(version, id, &rest[header_len..crc_at]) {
        Ok(msg) => Candidate::Frame(frame_len, header, msg),
        Err(_) => Candidate::Undecodable(frame_len),
    }
}

/// Serialises MAVLink 2 frames from our ids into one reused buffer, numbering them.
pub struct FrameWriter {
    raw: MAVLinkV2MessageRaw,
    header: MavHeader,
}

impl FrameWriter {
    pub fn new(system_id: u8, component_id: u8) -> Self {
        Self {
            raw: MAVLinkV2MessageRaw::new(),
            header: MavHeader {
                system_id: u32::from(system_id),
                component_id,
                sequence: 0,
            },
        }
    }

    /// The frame of `msg`, with the next sequence number.
    pub fn encode(&mut self, msg: &MavMessage) -> &[u8] {
        self.raw.serialize_message(self.header, msg);
        self.header.sequence = self.header.sequence.wrapping_add(1);
        self.raw.raw_bytes()
    }
}

#[cfg(test)]
#[path = "frame_tests.rs"]
mod tests;
