//! The phase signal the two mission processes exchange (paper V.A: "the UAVs publish ready
//! signals"): who sends it, where its sender is in the scenario and whether it is ready. Fixed
//! size, little-endian, with a magic and a version so that anything else on the key is rejected.

use rt_config::MAX_DRONE_ID_LEN;

/// Bits of [`PeerSignal::flags`].
pub mod signal_flags {
    /// The sender is still in Idle (`phase_index` is then 0 and means nothing).
    pub const IDLE: u32 = 1 << 0;
    /// In Idle: its vehicle state is fresh and its PX4 link up; it may be armed.
    pub const IDLE_READY: u32 = 1 << 1;
    /// Its bridge reports the offboard handshake done.
    pub const HANDSHAKE_DONE: u32 = 1 << 2;
    /// It is ready in phase `phase_index` (path done, within tolerance for the settle time).
    pub const READY: u32 = 1 << 3;
    /// Its path is frozen (for whatever reason).
    pub const HOLDING: u32 = 1 << 4;
    /// It has not heard its peer within its timeout (a cause of its hold).
    pub const PEER_LOST: u32 = 1 << 5;
    /// Its phase timed out (a cause of its hold).
    pub const TIMED_OUT: u32 = 1 << 6;
    /// Every phase ended (`phase_index` = number of phases).
    pub const DONE: u32 = 1 << 7;
    /// Every bit defined above; others are rejected.
    pub const ALL: u32 = (1 << 8) - 1;
}

/// Encoded size of a [`PeerSignal`], bytes.
pub const PEER_SIGNAL_LEN: usize = 48;
/// "TAMS" little-endian.
pub const PEER_SIGNAL_MAGIC: u32 = u32::from_le_bytes(*b"TAMS");
pub const PEER_SIGNAL_VERSION: u16 = 1;

/// One drone's phase signal. Layout (little-endian): magic u32, version u16, reserved u16 (0),
/// drone_id [u8; 16] (ASCII, zero padded), sequence u64, phase_index u32, flags u32, sent_ns u64.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PeerSignal {
    /// The sender's id, ASCII, zero padded.
    pub drone_id: [u8; MAX_DRONE_ID_LEN],
    /// +1 per signal sent since the sender started.
    pub sequence: u64,
    /// Index of the sender's running scenario phase (number of phases once done).
    pub phase_index: u32,
    /// Bits of [`signal_flags`].
    pub flags: u32,
    /// The sender's CLOCK_MONOTONIC when sent, ns (another computer's clock: for logs only).
    pub sent_ns: u64,
}

/// Why bytes were not a phase signal.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SignalError {
    #[error("phase signal of {0} bytes, expected {PEER_SIGNAL_LEN}")]
    Length(usize),
    #[error("phase signal magic 0x{0:08x}, expected 0x{PEER_SIGNAL_MAGIC:08x}")]
    Magic(u32),
    #[error("phase signal version {0}, expected {PEER_SIGNAL_VERSION}")]
    Version(u16),
    #[error("phase signal drone_id is not 1..=16 ASCII letters, digits, '-', '_' zero padded")]
    DroneId,
    #[error("phase signal flags 0x{0:x} has unknown bits")]
    Flags(u32),
    #[error("drone id {0:?} is not 1..=16 letters, digits, '-', '_'")]
    BadId(String),
}

/// A drone id as the signal carries it.
pub fn encode_drone_id(id: &str) -> Result<[u8; MAX_DRONE_ID_LEN], SignalError> {
    let ok = !id.is_empty()
        && id.len() <= MAX_DRONE_ID_LEN
        && id
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
    if !ok {
        return Err(SignalError::BadId(id.to_string()));
    }
    let mut out = [0u8; MAX_DRONE_ID_LEN];
    out[..id.len()].copy_from_slice(id.as_bytes());
    Ok(out)
}

fn id_len(id: &[u8; MAX_DRONE_ID_LEN]) -> Option<usize> {
    let n = id.iter().position(|&b| b == 0).unwrap_or(MAX_DRONE_ID_LEN);
    let valid = n > 0
        && id[..n]
            .iter()
            .all(|&b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
        && id[n..].iter().all(|&b| b == 0);
    valid.then_some(n)
}

impl PeerSignal {
    /// The sender's id ("" if the bytes are not a valid id; decode rejects those).
    pub fn drone_id_str(&self) -> &str {
        id_len(&self.drone_id)
            .and_then(|n| std::str::from_utf8(&self.drone_id[..n]).ok())
            .unwrap_or("")
    }

    pub fn has(&self, flag: u32) -> bool {
        self.flags & flag != 0
    }

    /// Position in the mission: 0 in Idle, phase i -> i + 1, done -> number of phases + 1.
    pub fn progress(&self) -> u64 {
        if self.has(signal_flags::IDLE) {
            0
        } else {
            u64::from(self.phase_index) + 1
        }
    }

    pub fn encode(&self, buf: &mut [u8; PEER_SIGNAL_LEN]) {
        buf[0..4].copy_from_slice(&PEER_SIGNAL_MAGIC.to_le_bytes());
        buf[4..6].copy_from_slice(&PEER_SIGNAL_VERSION.to_le_bytes());
        buf[6..8].copy_from_slice(&0u16.to_le_bytes());
        buf[8..24].copy_from_slice(&self.drone_id);
        buf[24..32].copy_from_slice(&self.sequence.to_le_bytes());
        buf[32..36].copy_from_slice(&self.phase_index.to_le_bytes());
        buf[36..40].copy_from_slice(&self.flags.to_le_bytes());
        buf[40..48].copy_from_slice(&self.sent_ns.to_le_bytes());
    }

    pub fn decode(bytes: &[u8]) -> Result<PeerSignal, SignalError> {
        let b: &[u8; PEER_SIGNAL_LEN] = bytes
            .try_into()
            .map_err(|_| SignalError::Length(bytes.len()))?;
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap_or([0; 8]));
        let magic = u32_at(0);
        if magic != PEER_SIGNAL_MAGIC {
            return Err(SignalError::Magic(magic));
        }
        let version = u16_at(4);
        if version != PEER_SIGNAL_VERSION {
            return Err(SignalError::Version(version));
        }
        let mut drone_id = [0u8; MAX_DRONE_ID_LEN];
        drone_id.copy_from_slice(&b[8..24]);
        if id_len(&drone_id).is_none() {
            return Err(SignalError::DroneId);
        }
        let flags = u32_at(36);
        if flags & !signal_flags::ALL != 0 {
            return Err(SignalError::Flags(flags));
        }
        Ok(PeerSignal {
            drone_id,
            sequence: u64_at(24),
            phase_index: u32_at(32),
            flags,
            sent_ns: u64_at(40),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PeerSignal {
        PeerSignal {
            drone_id: encode_drone_id("uav2").unwrap(),
            sequence: 0x0102_0304_0506_0708,
            phase_index: 3,
            flags: signal_flags::READY | signal_flags::HANDSHAKE_DONE,
            sent_ns: 123_456_789_012,
        }
    }

    #[test]
    fn round_trip_is_exact_and_little_endian() {
        let mut buf = [0u8; PEER_SIGNAL_LEN];
        sample().encode(&mut buf);
        assert_eq!(&buf[0..4], b"TAMS");
        assert_eq!(&buf[24..32], &[8, 7, 6, 5, 4, 3, 2, 1]);
        let back = PeerSignal::decode(&buf).unwrap();
        assert_eq!(back, sample());
        assert_eq!(back.drone_id_str(), "uav2");
    }

    #[test]
    fn bad_bytes_are_rejected() {
        let mut buf = [0u8; PEER_SIGNAL_LEN];
        sample().encode(&mut buf);
        assert_eq!(PeerSignal::decode(&buf[..47]), Err(SignalError::Length(47)));
        let mut long = buf.to_vec();
        long.push(0);
        assert_eq!(PeerSignal::decode(&long), Err(SignalError::Length(49)));
        let mut b = buf;
        b[0] = b'X';
        assert!(matches!(PeerSignal::decode(&b), Err(SignalError::Magic(_))));
        let mut b = buf;
        b[4] = 2;
        assert_eq!(PeerSignal::decode(&b), Err(SignalError::Version(2)));
        let mut b = buf;
        b[8..24].fill(0);
        assert_eq!(PeerSignal::decode(&b), Err(SignalError::DroneId));
        let mut b = buf;
        b[14] = b'x'; // a byte after the zero padding started
        assert_eq!(PeerSignal::decode(&b), Err(SignalError::DroneId));
        let mut b = buf;
        b[37] = 0x01; // flag bit 8: unknown
        assert_eq!(PeerSignal::decode(&b), Err(SignalError::Flags(0x10c)));
        assert!(encode_drone_id("uav 1").is_err());
        assert!(encode_drone_id(&"u".repeat(17)).is_err());
        assert!(encode_drone_id(&"u".repeat(16)).is_ok());
    }
}
