//! Framing: good frames through, every kind of bad input counted, datagrams independent; and
//! the mavlink crate's own reader behaviour that made us frame datagrams ourselves.

use super::*;
use mavlink::dialects::common::HEARTBEAT_DATA;
use std::io::Read;

fn heartbeat_frame(w: &mut FrameWriter) -> Vec<u8> {
    w.encode(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()))
        .to_vec()
}

/// Scans `chunks` as datagrams; returns the sequence numbers of the frames found.
fn scan_datagrams(s: &mut FrameScanner, chunks: &[Vec<u8>]) -> Vec<u8> {
    let mut seqs = Vec::new();
    for c in chunks {
        let used = s.scan(c, true, |h, _| seqs.push(h.sequence));
        assert_eq!(used, c.len());
    }
    seqs
}

#[test]
fn writer_frames_parse_back_with_ids_and_sequence() {
    let mut w = FrameWriter::new(1, 191);
    let frames: Vec<Vec<u8>> = (0..3).map(|_| heartbeat_frame(&mut w)).collect();
    let mut s = FrameScanner::new();
    let mut got = Vec::new();
    for f in &frames {
        s.scan(f, true, |h, m| {
            got.push((h.system_id, h.component_id, h.sequence));
            assert!(matches!(m, MavMessage::HEARTBEAT(_)));
        });
    }
    assert_eq!(got, [(1, 191, 0), (1, 191, 1), (1, 191, 2)]);
    assert_eq!(s.counters().frames_ok, 3);
    assert_eq!(s.counters().dropped(), 0);
}

#[test]
fn every_kind_of_bad_input_is_dropped_and_counted() {
    let mut w = FrameWriter::new(1, 1);
    let good = heartbeat_frame(&mut w); // seq 0
    let mut bad_crc = heartbeat_frame(&mut w); // seq 1
    *bad_crc.last_mut().unwrap() ^= 0xFF;
    let truncated = heartbeat_frame(&mut w)[..15].to_vec(); // seq 2
                                                            // Unknown id 60000 with a checksum computed as if CRC_EXTRA were 0.
    let mut unknown = heartbeat_frame(&mut w); // seq 3
    unknown[7..10].copy_from_slice(&[0x60, 0xEA, 0x00]);
    let crc = calculate_crc(&unknown[1..unknown.len() - 2], 0);
    let n = unknown.len();
    unknown[n - 2..].copy_from_slice(&crc.to_le_bytes());
    let garbage = vec![0x11u8, 0x22, 0x33, 0x44, 0x55];
    let mut prefixed = garbage.clone();
    prefixed.extend(heartbeat_frame(&mut w)); // seq 4
    let mut bad_flags = heartbeat_frame(&mut w); // seq 5
    bad_flags[1 + 1] = 0x80;
    let tail = heartbeat_frame(&mut w); // seq 6
    let mut s = FrameScanner::new();
    let seqs = scan_datagrams(
        &mut s,
        &[
            good, bad_crc, truncated, unknown, garbage, prefixed, bad_flags, tail,
        ],
    );
    assert_eq!(seqs, [0, 4, 6]);
    let c = s.counters();
    assert_eq!(
        (
            c.frames_ok,
            c.bad_crc,
            c.truncated,
            c.unknown_id,
            c.bad_header
        ),
        (3, 1, 1, 1, 1)
    );
    assert_eq!(c.garbage_bytes, 10, "5 alone + 5 in front of a frame");
}

#[test]
fn a_bogus_header_cannot_hold_back_the_next_datagrams() {
    let mut w = FrameWriter::new(1, 1);
    // 0xFD then length 255: a candidate that wants 267 bytes.
    let bogus = vec![0xFD, 0xFF, 0, 0, 0, 1, 1, 0, 0, 0];
    let mut s = FrameScanner::new();
    assert!(scan_datagrams(&mut s, &[bogus]).is_empty());
    let next = heartbeat_frame(&mut w);
    assert_eq!(
        scan_datagrams(&mut s, &[next]),
        [0],
        "the next datagram at once"
    );
    assert_eq!(s.counters().truncated, 1);
}

#[test]
fn a_stream_reassembles_frames_split_across_reads() {
    let mut w = FrameWriter::new(1, 1);
    let mut bytes = vec![0x42u8; 3];
    for _ in 0..3 {
        bytes.extend(heartbeat_frame(&mut w));
    }
    let mut s = FrameScanner::new();
    let mut seqs = Vec::new();
    let mut kept: Vec<u8> = Vec::new();
    for chunk in bytes.chunks(7) {
        kept.extend_from_slice(chunk);
        let used = s.scan(&kept, false, |h, _| seqs.push(h.sequence));
        kept.drain(..used);
    }
    assert_eq!(seqs, [0, 1, 2]);
    assert!(kept.is_empty());
    assert_eq!(s.counters().garbage_bytes, 3);
    assert_eq!(s.counters().dropped(), 0);
}

/// A reader that hands out one chunk per `read`, as a UDP socket does with datagrams.
struct Datagrams {
    chunks: Vec<Vec<u8>>,
    reads: usize,
}

impl Read for Datagrams {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let Some(c) = self.chunks.get(self.reads) else {
            return Ok(0);
        };
        self.reads += 1;
        buf[..c.len()].copy_from_slice(c);
        Ok(c.len())
    }
}

/// What mavlink 0.21's reader does (it is what `mavlink::connect("udpin:…")` reads with): the
/// datagrams form one stream, so after a bogus 10-byte header announcing 255 payload bytes,
/// the first good HEARTBEAT (21-byte frames) comes out only after 13 more datagrams have
/// arrived: at PX4's 1 Hz heartbeat, 13 s of silence and a false link loss. Bad candidates are
/// skipped without any error or count.
#[test]
fn mavlink_crate_reader_holds_frames_behind_a_bogus_header() {
    let mut w = FrameWriter::new(1, 1);
    let mut chunks = vec![vec![0xFD, 0xFF, 0, 0, 0, 1, 1, 0, 0, 0]];
    let mut bad = heartbeat_frame(&mut w); // seq 0, corrupted
    *bad.last_mut().unwrap() ^= 0xFF;
    chunks.push(bad);
    for _ in 0..20 {
        chunks.push(heartbeat_frame(&mut w)); // seq 1..
    }
    let mut r = mavlink::MavlinkReader::new(Datagrams { chunks, reads: 0 });
    let (header, _) = r
        .read_message::<MavMessage>(MavlinkVersion::V2)
        .expect("a heartbeat eventually");
    assert_eq!(
        header.sequence, 1,
        "the corrupted frame is skipped silently"
    );
    assert_eq!(
        r.get_ref().reads,
        14,
        "bogus header + bad frame + 12 good ones read first"
    );
}
