//! taut's mission: the scenario's phases, agreed with the peer drone by exchanging only ready
//! signals over zenoh (paper V.A), turned into the nominal setpoints the controller follows.
//!
//! - [`stage`]: the pure state machine ([`MissionStage`]).
//! - [`signal`]: the fixed-size phase signal ([`PeerSignal`]).
//! - [`peer_link`]: the zenoh link that carries it ([`PeerLink`]).
//! - [`shell`]: the service process (`taut svc mission`).

pub mod peer_link;
pub mod shell;
pub mod signal;
pub mod stage;
pub mod types;

pub use peer_link::{PeerLink, PeerLinkCounters, PeerLinkError};
pub use signal::{signal_flags, PeerSignal, SignalError, PEER_SIGNAL_LEN};
pub use stage::MissionStage;
pub use types::{MissionCounters, MissionError, MissionEvent, MissionOutput};
