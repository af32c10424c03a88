//! taut's iceoryx2 plumbing. A topic is a publish-subscribe service carrying one fixed-size
//! sample type plus an event service of the same name that wakes subscribers, so no receiver
//! polls or sleeps-and-checks. Publishing never blocks: a subscriber that falls behind loses
//! its oldest samples (safe overflow), which it sees as a gap in `Header::sequence`.

mod stop;
mod topic;

pub use stop::{install_stop_handler, request_stop, stop_requested};
pub use topic::{
    Ipc, IpcError, Stamped, TopicPublisher, TopicSubscriber, SUBSCRIBER_BUFFER,
    SUBSCRIBER_MAX_BUFFER,
};
