//! Link configuration: addresses, identity and the default stream rates of PX4's onboard mode.

use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4};

/// First local UDP port of PX4 SITL's onboard link (`mavlink start -u 14580+i`).
pub const PX4_SITL_LOCAL_PORT_BASE: u16 = 14580;
/// First companion UDP port of PX4 SITL's onboard link (`-o 14540+i`, where MAVSDK/MAVROS listen).
pub const PX4_SITL_REMOTE_PORT_BASE: u16 = 14540;
/// MAV_COMP_ID_AUTOPILOT1.
pub const MAV_COMP_ID_AUTOPILOT1: u8 = 1;

/// The outbound streams the endpoint knows, in a fixed order used to index per-stream tables.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stream {
    /// HEARTBEAT (#0).
    Heartbeat,
    /// ATTITUDE_QUATERNION (#31).
    AttitudeQuaternion,
    /// HIGHRES_IMU (#105).
    HighresImu,
    /// LOCAL_POSITION_NED (#32).
    LocalPositionNed,
    /// ODOMETRY (#331).
    Odometry,
    /// ESC_STATUS (#291).
    EscStatus,
}

impl Stream {
    /// Number of streams.
    pub const COUNT: usize = 6;
    /// All streams in table order.
    pub const ALL: [Stream; Stream::COUNT] = [
        Stream::Heartbeat,
        Stream::AttitudeQuaternion,
        Stream::HighresImu,
        Stream::LocalPositionNed,
        Stream::Odometry,
        Stream::EscStatus,
    ];

    /// Index into per-stream tables.
    pub fn index(self) -> usize {
        self as usize
    }

    /// MAVLink message id of the stream.
    pub fn message_id(self) -> u32 {
        match self {
            Stream::Heartbeat => 0,
            Stream::AttitudeQuaternion => 31,
            Stream::HighresImu => 105,
            Stream::LocalPositionNed => 32,
            Stream::Odometry => 331,
            Stream::EscStatus => 291,
        }
    }

    /// The stream that sends message `id`, if any.
    pub fn from_message_id(id: u32) -> Option<Stream> {
        Stream::ALL.into_iter().find(|s| s.message_id() == id)
    }
}

/// Stream rates in Hz; 0 disables a stream. Defaults are PX4 v1.16's onboard-mode rates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamRates {
    /// HEARTBEAT rate, Hz (PX4: 1).
    pub heartbeat_hz: f64,
    /// ATTITUDE_QUATERNION rate, Hz (PX4 onboard: 50).
    pub attitude_quaternion_hz: f64,
    /// HIGHRES_IMU rate, Hz (PX4 onboard: 50).
    pub highres_imu_hz: f64,
    /// LOCAL_POSITION_NED rate, Hz (PX4 onboard: 30).
    pub local_position_ned_hz: f64,
    /// ODOMETRY rate, Hz (PX4 onboard: 30).
    pub odometry_hz: f64,
    /// ESC_STATUS rate, Hz (PX4 onboard: 10).
    pub esc_status_hz: f64,
}

impl Default for StreamRates {
    fn default() -> Self {
        StreamRates {
            heartbeat_hz: 1.0,
            attitude_quaternion_hz: 50.0,
            highres_imu_hz: 50.0,
            local_position_ned_hz: 30.0,
            odometry_hz: 30.0,
            esc_status_hz: 10.0,
        }
    }
}

impl StreamRates {
    /// Rate of `stream`, Hz.
    pub fn get(&self, stream: Stream) -> f64 {
        match stream {
            Stream::Heartbeat => self.heartbeat_hz,
            Stream::AttitudeQuaternion => self.attitude_quaternion_hz,
            Stream::HighresImu => self.highres_imu_hz,
            Stream::LocalPositionNed => self.local_position_ned_hz,
            Stream::Odometry => self.odometry_hz,
            Stream::EscStatus => self.esc_status_hz,
        }
    }

    /// Interval of `stream` in ns, `None` when disabled (rate 0).
    pub fn interval_ns(&self, stream: Stream) -> Option<u64> {
        let hz = self.get(stream);
        (hz > 0.0).then(|| (1e9 / hz).round().max(1.0) as u64)
    }
}

/// Everything that defines one drone's MAVLink endpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkConfig {
    /// Local UDP address the endpoint binds (PX4 SITL: 127.0.0.1:14580+i).
    pub bind: SocketAddr,
    /// Where the streams go until a peer is heard (PX4 SITL: 127.0.0.1:14540+i).
    pub remote: SocketAddr,
    /// MAVLink system id of the drone (PX4 SITL: 1+i).
    pub system_id: u8,
    /// MAVLink component id (MAV_COMP_ID_AUTOPILOT1).
    pub component_id: u8,
    /// Default stream rates (what MAV_CMD_SET_MESSAGE_INTERVAL with interval 0 restores).
    pub rates: StreamRates,
    /// Like PX4's UDP link: once the first datagram arrives, stream to its source address
    /// instead of `remote` (only once; later senders do not steal the link).
    pub follow_first_sender: bool,
    /// Upper bound on datagrams drained by one `poll`, so a flood cannot stall the step loop.
    pub max_datagrams_per_poll: usize,
}

impl LinkConfig {
    /// PX4 SITL's onboard link of instance `instance` (0-based): binds 127.0.0.1:(14580+i),
    /// streams to 127.0.0.1:(14540+i), system id 1+i, component 1, PX4's onboard rates.
    pub fn px4_sitl(instance: u8) -> LinkConfig {
        let lo = Ipv4Addr::LOCALHOST;
        let i = u16::from(instance);
        LinkConfig {
            bind: SocketAddr::V4(SocketAddrV4::new(lo, PX4_SITL_LOCAL_PORT_BASE + i)),
            remote: SocketAddr::V4(SocketAddrV4::new(lo, PX4_SITL_REMOTE_PORT_BASE + i)),
            system_id: instance.saturating_add(1),
            component_id: MAV_COMP_ID_AUTOPILOT1,
            rates: StreamRates::default(),
            follow_first_sender: true,
            max_datagrams_per_poll: 1024,
        }
    }

    /// Checks ids, rates (finite, >= 0) and the poll bound.
    pub fn validate(&self) -> Result<(), LinkConfigError> {
        if self.system_id == 0 {
            return Err(LinkConfigError::SystemId(self.system_id));
        }
        if self.component_id == 0 {
            return Err(LinkConfigError::ComponentId(self.component_id));
        }
        for stream in Stream::ALL {
            let hz = self.rates.get(stream);
            if !hz.is_finite() || hz < 0.0 {
                return Err(LinkConfigError::Rate { stream, hz });
            }
        }
        if self.max_datagrams_per_poll == 0 {
            return Err(LinkConfigError::MaxDatagramsPerPoll(0));
        }
        Ok(())
    }
}

/// A [`LinkConfig`] field out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinkConfigError {
    /// System id 0 is the broadcast id.
    #[error("system_id must be 1..=255, got {0}")]
    SystemId(u8),
    /// Component id 0 is the broadcast id.
    #[error("component_id must be 1..=255, got {0}")]
    ComponentId(u8),
    /// A stream rate that is negative or not finite.
    #[error("rate of stream {stream:?} must be finite and >= 0 Hz, got {hz}")]
    Rate {
        /// The stream.
        stream: Stream,
        /// The bad rate, Hz.
        hz: f64,
    },
    /// A poll bound of zero would never read anything.
    #[error("max_datagrams_per_poll must be >= 1, got {0}")]
    MaxDatagramsPerPoll(usize),
}

/// Why the endpoint could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum LinkOpenError {
    /// The configuration is invalid.
    #[error("invalid link config: {0}")]
    Config(#[from] LinkConfigError),
    /// Binding the local UDP socket failed (port in use?).
    #[error("cannot bind UDP {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: SocketAddr,
        /// The OS error.
        source: std::io::Error,
    },
    /// Switching the socket to non-blocking mode failed.
    #[error("cannot make UDP socket {addr} non-blocking: {source}")]
    NonBlocking {
        /// The bound address.
        addr: SocketAddr,
        /// The OS error.
        source: std::io::Error,
    },
}
