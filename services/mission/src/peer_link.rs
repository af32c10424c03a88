//! The zenoh link between the two mission processes: each publishes its phase signal on
//! `<key_prefix>/<own id>` and listens on `<key_prefix>/*`, keeping the newest valid signal of
//! the configured peer. Peer mode with explicit endpoints only: no multicast scouting, no gossip.
//!
//! Signals are decoded on zenoh's receive thread (stamped with CLOCK_MONOTONIC on arrival) and
//! handed over through a mutex; `try_recv` copies one fixed-size value. A zenoh `put` allocates
//! internally: acceptable here, the mission is not the real-time controller.

use std::sync::{Arc, Mutex, MutexGuard};

use rt_config::periodic::now_ns;
use zenoh::qos::{CongestionControl, Priority};
use zenoh::sample::{Locality, Sample};
use zenoh::Wait;

use crate::signal::{encode_drone_id, PeerSignal, PEER_SIGNAL_LEN};

/// Why the link could not be opened or used; each names the key or the operation.
#[derive(Debug, thiserror::Error)]
pub enum PeerLinkError {
    #[error("{0}")]
    Config(String),
    #[error("zenoh config key {key} = {value}: {message}")]
    ZenohConfig {
        key: &'static str,
        value: String,
        message: String,
    },
    #[error("cannot open the zenoh session (mission.listen / mission.connect): {0}")]
    Open(String),
    #[error("cannot declare the zenoh {what} on {key:?}: {message}")]
    Declare {
        what: &'static str,
        key: String,
        message: String,
    },
    #[error("own id: {0}")]
    Id(#[from] crate::signal::SignalError),
    #[error("cannot send the phase signal: {0}")]
    Send(String),
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PeerLinkCounters {
    pub sent: u64,
    pub send_errors: u64,
    /// Valid signals from the peer.
    pub received: u64,
    /// Samples on the peer's key that are not a phase signal.
    pub malformed: u64,
    /// Samples on another key, or whose embedded id is not the peer's.
    pub unexpected_sender: u64,
}

#[derive(Default)]
struct Inbox {
    newest: Option<(PeerSignal, u64)>,
    counters: PeerLinkCounters,
}

fn lock(inbox: &Mutex<Inbox>) -> MutexGuard<'_, Inbox> {
    // A panic elsewhere while holding the lock leaves plain data behind: keep using it.
    inbox.lock().unwrap_or_else(|e| e.into_inner())
}

/// The zenoh config of the link (peer mode, explicit endpoints, no scouting).
pub fn zenoh_config(cfg: &rt_config::MissionConfig) -> Result<zenoh::Config, PeerLinkError> {
    let list = |v: &[String]| {
        let quoted: Vec<String> = v.iter().map(|e| format!("{e:?}")).collect();
        format!("[{}]", quoted.join(","))
    };
    let mut z = zenoh::Config::default();
    let settings: [(&'static str, String); 6] = [
        ("mode", "\"peer\"".into()),
        ("listen/endpoints", list(&cfg.listen)),
        ("connect/endpoints", list(&cfg.connect)),
        ("scouting/multicast/enabled", "false".into()),
        ("scouting/gossip/enabled", "false".into()),
        // Reach a peer that starts later or restarts within about a second (default 1-4 s).
        (
            "connect/retry",
            "{period_init_ms: 250, period_max_ms: 1000, period_increase_factor: 2}".into(),
        ),
    ];
    for (key, value) in settings {
        z.insert_json5(key, &value)
            .map_err(|e| PeerLinkError::ZenohConfig {
                key,
                value: value.clone(),
                message: e.to_string(),
            })?;
    }
    Ok(z)
}

/// One drone's end of the link.
pub struct PeerLink {
    session: zenoh::Session,
    publisher: zenoh::pubsub::Publisher<'static>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    inbox: Arc<Mutex<Inbox>>,
    buf: [u8; PEER_SIGNAL_LEN],
    sent: u64,
    send_errors: u64,
}

impl PeerLink {
    /// Opens a zenoh peer session with `cfg.listen` / `cfg.connect`, a publisher on
    /// `<key_prefix>/<own_id>` and a subscriber on `<key_prefix>/*`.
    pub fn open(cfg: &rt_config::MissionConfig, own_id: &str) -> Result<Self, PeerLinkError> {
        cfg.validate().map_err(PeerLinkError::Config)?;
        encode_drone_id(own_id)?;
        let peer_id = encode_drone_id(&cfg.peer)?;
        let session = zenoh::open(zenoh_config(cfg)?)
            .wait()
            .map_err(|e| PeerLinkError::Open(e.to_string()))?;
        let own_key = format!("{}/{own_id}", cfg.key_prefix);
        let publisher = session
            .declare_publisher(own_key.clone())
            .congestion_control(CongestionControl::Drop)
            .priority(Priority::RealTime)
            .express(true)
            // Our own subscriber would hear us otherwise.
            .allowed_destination(Locality::Remote)
            .wait()
            .map_err(|e| PeerLinkError::Declare {
                what: "publisher",
                key: own_key,
                message: e.to_string(),
            })?;
        let inbox = Arc::new(Mutex::new(Inbox::default()));
        let peer_key = format!("{}/{}", cfg.key_prefix, cfg.peer);
        let all_key = format!("{}/*", cfg.key_prefix);
        let rx_inbox = inbox.clone();
        let subscriber = session
            .declare_subscriber(all_key.clone())
            .allowed_origin(Locality::Remote)
            .callback(move |sample: Sample| {
                let t_ns = now_ns();
                let payload = sample.payload().to_bytes();
                let mut inbox = lock(&rx_inbox);
                if sample.key_expr().as_str() != peer_key {
                    inbox.counters.unexpected_sender += 1;
                    return;
                }
                match PeerSignal::decode(&payload) {
                    Err(_) => inbox.counters.malformed += 1,
                    Ok(s) if s.drone_id != peer_id => inbox.counters.unexpected_sender += 1,
                    Ok(s) => {
                        inbox.counters.received += 1;
                        inbox.newest = Some((s, t_ns));
                    }
                }
            })
            .wait()
            .map_err(|e| PeerLinkError::Declare {
                what: "subscriber",
                key: all_key,
                message: e.to_string(),
            })?;
        Ok(PeerLink {
            session,
            publisher,
            _subscriber: subscriber,
            inbox,
            buf: [0; PEER_SIGNAL_LEN],
            sent: 0,
            send_errors: 0,
        })
    }

    pub fn send(&mut self, signal: &PeerSignal) -> Result<(), PeerLinkError> {
        signal.encode(&mut self.buf);
        match self.publisher.put(self.buf).wait() {
            Ok(()) => {
                self.sent += 1;
                Ok(())
            }
            Err(e) => {
                self.send_errors += 1;
                Err(PeerLinkError::Send(e.to_string()))
            }
        }
    }

    /// The newest valid signal from the expected peer and when it arrived (CLOCK_MONOTONIC ns),
    /// if any new one arrived since the last call.
    pub fn try_recv(&mut self) -> Option<(PeerSignal, u64)> {
        lock(&self.inbox).newest.take()
    }

    pub fn counters(&self) -> PeerLinkCounters {
        PeerLinkCounters {
            sent: self.sent,
            send_errors: self.send_errors,
            ..lock(&self.inbox).counters
        }
    }

    /// Zenoh ids of the sessions this one has a transport to (for logs and tests).
    pub fn connected_peers(&self) -> usize {
        self.session.info().peers_zid().wait().count()
    }
}

impl Drop for PeerLink {
    fn drop(&mut self) {
        // Close now so the peer sees the link go at once rather than at lease expiry.
        let _ = self.session.close().wait();
    }
}
