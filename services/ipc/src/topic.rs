use core::time::Duration;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::{event, publish_subscribe};
use shared_types::{
    names, AttitudeSetpoint, Header, ImuSample, MissionSetpoint, MotorSpeeds, PlantTruth,
    RawAdcFrame, TensionSample, VehicleState,
};
use std::fmt::Debug;

/// Samples whose header the publisher stamps.
pub trait Stamped: Copy + Debug + ZeroCopySend + 'static {
    fn header(&self) -> &Header;
    fn header_mut(&mut self) -> &mut Header;
}

/// Every sample type starts with a `header: Header` field.
macro_rules! impl_stamped {
    ($($t:ty),* $(,)?) => {$(
        impl Stamped for $t {
            fn header(&self) -> &Header {
                &self.header
            }
            fn header_mut(&mut self) -> &mut Header {
                &mut self.header
            }
        }
    )*};
}

impl_stamped!(
    RawAdcFrame,
    TensionSample,
    PlantTruth,
    VehicleState,
    ImuSample,
    MotorSpeeds,
    MissionSetpoint,
    AttitudeSetpoint,
);

/// One error enum for the plumbing; each variant names the service it failed on.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    #[error("cannot create iceoryx2 node {name:?}: {message}")]
    Node { name: String, message: String },
    #[error("invalid service name {name:?}: {message}")]
    Name { name: String, message: String },
    #[error("cannot open service {name:?}: {message}")]
    Open { name: String, message: String },
    #[error("cannot create a port on {name:?}: {message}")]
    Port { name: String, message: String },
    #[error("cannot send on {name:?}: {message}")]
    Send { name: String, message: String },
    #[error("cannot receive on {name:?}: {message}")]
    Receive { name: String, message: String },
}

/// Sizing of every topic: enough subscribers for the consumer, a monitor, the recorder and a
/// benchmark; buffers of a few samples (consumers are faster than producers).
const MAX_SUBSCRIBERS: usize = 8;
const MAX_PUBLISHERS: usize = 2;
const MAX_NODES: usize = 16;
/// A consumer's buffer, samples.
pub const SUBSCRIBER_BUFFER: usize = 16;
/// The deepest buffer a subscriber may ask for (the recorder's: ~0.3 s of a 900 Hz IMU, so a
/// recorder that is descheduled on a loaded machine still loses nothing).
pub const SUBSCRIBER_MAX_BUFFER: usize = 256;

/// A topic's name, its publish-subscribe service and its event service.
type TopicServices<T> = (
    String,
    publish_subscribe::PortFactory<ipc::Service, T, ()>,
    event::PortFactory<ipc::Service>,
);

/// A process's iceoryx2 node and the naming of its drone's topics.
pub struct Ipc {
    node: Node<ipc::Service>,
    root: String,
    uav: String,
}

impl Ipc {
    /// Creates the node `node_name` and removes what dead nodes (crashed processes) left behind,
    /// so a restart after a crash starts clean.
    pub fn new(node_name: &str, root: &str, uav: &str) -> Result<Self, IpcError> {
        let err = |message: String| IpcError::Node {
            name: node_name.to_string(),
            message,
        };
        // iceoryx2 warns on every start that it runs on its built-in defaults, which we intend.
        set_log_level(LogLevel::Error);
        let name: NodeName = node_name.try_into().map_err(|e| err(format!("{e:?}")))?;
        let node = NodeBuilder::new()
            .name(&name)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| err(format!("{e:?}")))?;
        node.try_cleanup_dead_nodes();
        Ok(Self {
            node,
            root: root.to_string(),
            uav: uav.to_string(),
        })
    }

    /// Removes what crashed processes left in shared memory, from a short-lived node of its
    /// own (a supervisor calls this after stopping its children).
    pub fn cleanup_dead_nodes(node_name: &str) -> Result<(), IpcError> {
        Self::new(node_name, "", "cleanup").map(drop)
    }

    pub fn service_name(&self, topic: &str) -> String {
        names::service_name(&self.root, &self.uav, topic)
    }

    fn open<T: Stamped>(&self, topic: &str) -> Result<TopicServices<T>, IpcError> {
        let name = self.service_name(topic);
        let sn: ServiceName = name.as_str().try_into().map_err(|e| IpcError::Name {
            name: name.clone(),
            message: format!("{e:?}"),
        })?;
        let open_err = |message: String| IpcError::Open {
            name: name.clone(),
            message,
        };
        let ps = self
            .node
            .service_builder(&sn)
            .publish_subscribe::<T>()
            .max_publishers(MAX_PUBLISHERS)
            .max_subscribers(MAX_SUBSCRIBERS)
            .max_nodes(MAX_NODES)
            .subscriber_max_buffer_size(SUBSCRIBER_MAX_BUFFER)
            .history_size(0)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| open_err(format!("publish-subscribe: {e:?}")))?;
        let ev = self
            .node
            .service_builder(&sn)
            .event()
            .max_notifiers(MAX_PUBLISHERS)
            .max_listeners(MAX_SUBSCRIBERS)
            .max_nodes(MAX_NODES)
            .open_or_create()
            .map_err(|e| open_err(format!("event: {e:?}")))?;
        Ok((name, ps, ev))
    }

    /// A publisher of `T` on this drone's `topic`.
    pub fn publisher<T: Stamped>(&self, topic: &str) -> Result<TopicPublisher<T>, IpcError> {
        let (name, ps, ev) = self.open::<T>(topic)?;
        let port_err = |e: String| IpcError::Port {
            name: name.clone(),
            message: e,
        };
        let publisher = ps
            .publisher_builder()
            .create()
            .map_err(|e| port_err(format!("{e:?}")))?;
        let notifier = ev
            .notifier_builder()
            .create()
            .map_err(|e| port_err(format!("{e:?}")))?;
        Ok(TopicPublisher {
            name,
            publisher,
            notifier,
            sequence: 0,
            send_failures: 0,
        })
    }

    /// A subscriber of `T` on this drone's `topic` with a buffer of [`SUBSCRIBER_BUFFER`].
    pub fn subscriber<T: Stamped>(&self, topic: &str) -> Result<TopicSubscriber<T>, IpcError> {
        self.subscriber_with_buffer(topic, SUBSCRIBER_BUFFER)
    }

    /// A subscriber of `T` on this drone's `topic` holding up to `buffer` samples (at most
    /// [`SUBSCRIBER_MAX_BUFFER`]) before the oldest are overwritten.
    pub fn subscriber_with_buffer<T: Stamped>(
        &self,
        topic: &str,
        buffer: usize,
    ) -> Result<TopicSubscriber<T>, IpcError> {
        let (name, ps, ev) = self.open::<T>(topic)?;
        if buffer == 0 || buffer > SUBSCRIBER_MAX_BUFFER {
            return Err(IpcError::Port {
                name,
                message: format!("buffer {buffer}: must be 1..={SUBSCRIBER_MAX_BUFFER}"),
            });
        }
        let port_err = |e: String| IpcError::Port {
            name: name.clone(),
            message: e,
        };
        let subscriber = ps
            .subscriber_builder()
            .buffer_size(buffer)
            .create()
            .map_err(|e| port_err(format!("{e:?}")))?;
        let listener = ev
            .listener_builder()
            .create()
            .map_err(|e| port_err(format!("{e:?}")))?;
        Ok(TopicSubscriber {
            name,
            subscriber,
            listener,
        })
    }
}

/// Publishes samples of one topic and wakes its subscribers. When dropped it logs
/// `[ipc] published N on <service name>` (N = sequence numbers given out, sent or not) so a
/// test can compare a recording against what went out.
pub struct TopicPublisher<T: Stamped> {
    name: String,
    publisher: iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>,
    notifier: iceoryx2::port::notifier::Notifier<ipc::Service>,
    sequence: u64,
    send_failures: u64,
}

impl<T: Stamped> Drop for TopicPublisher<T> {
    fn drop(&mut self) {
        eprintln!("{}", self.published_line());
    }
}

impl<T: Stamped> TopicPublisher<T> {
    /// Stamps `sample` (sequence, `t_publish_ns` = now; `t_origin_ns` is the caller's) and sends
    /// it. Returns the stamped header.
    pub fn publish(&mut self, mut sample: T) -> Result<Header, IpcError> {
        let h = sample.header_mut();
        h.sequence = self.sequence;
        h.t_publish_ns = rt_config::periodic::now_ns();
        let header = *h;
        self.sequence += 1;
        let sent = self
            .publisher
            .loan_uninit()
            .map_err(|e| format!("{e:?}"))
            .and_then(|l| l.write_payload(sample).send().map_err(|e| format!("{e:?}")));
        if let Err(message) = sent {
            self.send_failures += 1;
            return Err(IpcError::Send {
                name: self.name.clone(),
                message,
            });
        }
        self.notifier.notify().map_err(|e| IpcError::Send {
            name: self.name.clone(),
            message: format!("notify: {e:?}"),
        })?;
        Ok(header)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Samples given a sequence number so far (the next sample's sequence).
    pub fn published(&self) -> u64 {
        self.sequence
    }

    /// Samples that could not be sent (they still used a sequence number: a subscriber sees a
    /// gap).
    pub fn send_failures(&self) -> u64 {
        self.send_failures
    }

    /// `[ipc] published N on NAME` (and the send failures, if any), as logged on drop.
    pub fn published_line(&self) -> String {
        let failed = match self.send_failures {
            0 => String::new(),
            n => format!(" ({n} not sent)"),
        };
        format!("[ipc] published {} on {}{failed}", self.sequence, self.name)
    }
}

/// Receives samples of one topic, sleeping on its event until one arrives.
pub struct TopicSubscriber<T: Stamped> {
    name: String,
    subscriber: iceoryx2::port::subscriber::Subscriber<ipc::Service, T, ()>,
    listener: iceoryx2::port::listener::Listener<ipc::Service>,
}

impl<T: Stamped> TopicSubscriber<T> {
    /// Waits up to `timeout` for a wake-up, then hands every queued sample to `f`, oldest
    /// first. Returns how many samples were handed over (0 on timeout).
    pub fn wait_and_drain(
        &self,
        timeout: Duration,
        mut f: impl FnMut(T),
    ) -> Result<usize, IpcError> {
        self.wait(timeout)?;
        self.drain(&mut f)
    }

    /// Waits up to `timeout` for a wake-up without taking samples (returns at once if some
    /// are queued).
    pub fn wait(&self, timeout: Duration) -> Result<(), IpcError> {
        let queued = self.subscriber.has_samples().unwrap_or(false);
        if !queued {
            self.listener
                .timed_wait(|_| {}, timeout)
                .map_err(|e| IpcError::Receive {
                    name: self.name.clone(),
                    message: format!("event wait: {e:?}"),
                })?;
        }
        Ok(())
    }

    /// Hands every queued sample to `f` without waiting.
    pub fn drain(&self, f: &mut impl FnMut(T)) -> Result<usize, IpcError> {
        let mut n = 0;
        loop {
            match self.subscriber.receive() {
                Ok(Some(sample)) => {
                    f(*sample);
                    n += 1;
                }
                Ok(None) => return Ok(n),
                Err(e) => {
                    return Err(IpcError::Receive {
                        name: self.name.clone(),
                        message: format!("{e:?}"),
                    })
                }
            }
        }
    }

    pub fn name(&self) -> &str {
        &self.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn publish_wakes_subscriber_with_stamped_samples() {
        let root = format!("unit-{}", std::process::id());
        let ipc = Ipc::new("ipc-test", &root, "uavT").unwrap();
        let sub = ipc.subscriber::<TensionSample>("tension").unwrap();
        let mut publ = ipc.publisher::<TensionSample>("tension").unwrap();
        for k in 0..3 {
            let mut s = TensionSample::default();
            s.header.t_origin_ns = 100 + k;
            publ.publish(s).unwrap();
        }
        let mut got = Vec::new();
        let n = sub
            .wait_and_drain(Duration::from_millis(500), |s| got.push(s.header))
            .unwrap();
        assert_eq!(n, 3);
        assert_eq!(
            got.iter().map(|h| h.sequence).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        assert_eq!(got[2].t_origin_ns, 102);
        assert!(got[0].t_publish_ns > 0 && got[0].t_publish_ns <= got[2].t_publish_ns);
        // Nothing more: a timed wait returns empty.
        assert_eq!(
            sub.wait_and_drain(Duration::from_millis(10), |_| {})
                .unwrap(),
            0
        );
    }

    #[test]
    fn a_deep_buffer_keeps_what_a_shallow_one_loses_even_after_the_publisher_left() {
        let root = format!("unit-deep-{}", std::process::id());
        let ipc = Ipc::new("ipc-test-deep", &root, "uavT").unwrap();
        let deep = ipc
            .subscriber_with_buffer::<TensionSample>("tension", SUBSCRIBER_MAX_BUFFER)
            .unwrap();
        let shallow = ipc.subscriber::<TensionSample>("tension").unwrap();
        assert!(ipc
            .subscriber_with_buffer::<TensionSample>("tension", SUBSCRIBER_MAX_BUFFER + 1)
            .is_err());
        let mut publ = ipc.publisher::<TensionSample>("tension").unwrap();
        // Both subscribers connect to the new publisher (the recorder's loop does this on
        // every poll; here once, before the burst).
        assert_eq!(deep.drain(&mut |_| {}).unwrap(), 0);
        assert_eq!(shallow.drain(&mut |_| {}).unwrap(), 0);
        for _ in 0..200 {
            publ.publish(TensionSample::default()).unwrap();
        }
        assert_eq!(publ.published(), 200);
        assert_eq!(
            publ.published_line(),
            format!("[ipc] published 200 on {}", publ.name())
        );
        // iceoryx2 keeps a departed publisher's undelivered samples for its subscribers.
        drop(publ);
        let mut seqs = Vec::new();
        deep.drain(&mut |s| seqs.push(s.header.sequence)).unwrap();
        assert_eq!(seqs, (0..200).collect::<Vec<_>>());
        let mut newest = Vec::new();
        shallow
            .drain(&mut |s| newest.push(s.header.sequence))
            .unwrap();
        assert_eq!(
            newest,
            (200 - SUBSCRIBER_BUFFER as u64..200).collect::<Vec<_>>()
        );
    }
}
