//! Per-channel sequence accounting: what a recorder took, and what it must have lost.
//!
//! Every publisher numbers its samples 0, 1, 2, ... (`Header::sequence`). A gap between two
//! consecutive samples taken is a drop (the subscriber's buffer overflowed and iceoryx2 threw
//! the oldest away). A first sample numbered N > 0 means N samples went out before the
//! recorder subscribed: "missed before start", not a drop. A sequence that goes backwards means
//! the publisher restarted (a supervisor restart): its new samples 0..s-1 not taken are drops.

use std::collections::BTreeMap;

/// What one channel saw.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ChannelStats {
    /// The channel topic, `/<uav>/<topic>`.
    pub topic: String,
    /// Samples taken (and written).
    pub received: u64,
    /// Samples lost to sequence gaps after the first one taken.
    pub drops: u64,
    /// The first sample's sequence: samples published before the recorder subscribed.
    pub missed_before_start: u64,
    /// Times the sequence went backwards (the publisher restarted).
    pub restarts: u64,
    pub first_sequence: Option<u64>,
    pub last_sequence: Option<u64>,
}

impl ChannelStats {
    pub fn new(topic: String) -> Self {
        Self {
            topic,
            ..Default::default()
        }
    }

    /// Accounts for one sample taken with `sequence`.
    pub fn observe(&mut self, sequence: u64) {
        self.received += 1;
        match self.last_sequence {
            None => {
                self.first_sequence = Some(sequence);
                self.missed_before_start = sequence;
            }
            Some(last) if sequence > last => self.drops += sequence - last - 1,
            Some(_) => {
                self.restarts += 1;
                self.drops += sequence;
            }
        }
        self.last_sequence = Some(sequence);
    }
}

/// The metadata records written at a clean close, by name: record -> (channel topic -> value).
pub fn close_metadata(stats: &[ChannelStats]) -> BTreeMap<&'static str, BTreeMap<String, String>> {
    let mut out: BTreeMap<&'static str, BTreeMap<String, String>> = BTreeMap::new();
    let opt = |v: Option<u64>| v.map(|v| v.to_string()).unwrap_or_default();
    for s in stats {
        let mut put = |record: &'static str, value: String| {
            out.entry(record)
                .or_default()
                .insert(s.topic.clone(), value);
        };
        put(crate::format::META_DROPS, s.drops.to_string());
        put(crate::format::META_RECEIVED, s.received.to_string());
        put(
            crate::format::META_MISSED_BEFORE_START,
            s.missed_before_start.to_string(),
        );
        put(crate::format::META_RESTARTS, s.restarts.to_string());
        put(crate::format::META_FIRST_SEQUENCE, opt(s.first_sequence));
        put(crate::format::META_LAST_SEQUENCE, opt(s.last_sequence));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(seqs: &[u64]) -> ChannelStats {
        let mut s = ChannelStats::new("/u/t".into());
        for &q in seqs {
            s.observe(q);
        }
        s
    }

    #[test]
    fn gaps_are_drops_and_a_late_start_is_not() {
        let s = run(&[5, 6, 9, 10, 14]);
        assert_eq!(s.received, 5);
        assert_eq!(s.missed_before_start, 5);
        assert_eq!(s.drops, 2 + 3);
        assert_eq!((s.first_sequence, s.last_sequence), (Some(5), Some(14)));
    }

    #[test]
    fn a_restarted_publisher_counts_its_missed_first_samples() {
        let s = run(&[0, 1, 2, 3, 2, 3]);
        assert_eq!(s.restarts, 1);
        assert_eq!(s.drops, 2, "the new publisher's 0 and 1 were not taken");
        let s = run(&[0, 1, 0, 1]);
        assert_eq!((s.restarts, s.drops), (1, 0));
    }

    #[test]
    fn close_metadata_has_every_record() {
        let m = close_metadata(&[run(&[1, 3])]);
        assert_eq!(m[crate::format::META_DROPS]["/u/t"], "1");
        assert_eq!(m[crate::format::META_RECEIVED]["/u/t"], "2");
        assert_eq!(m[crate::format::META_MISSED_BEFORE_START]["/u/t"], "1");
        assert_eq!(m[crate::format::META_LAST_SEQUENCE]["/u/t"], "3");
    }
}
