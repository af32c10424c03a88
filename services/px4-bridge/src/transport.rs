//! The link's two halves, each used by one thread: a receiver of byte chunks (one datagram, or
//! what one serial read returned) and a sender of frames. Reads time out so the receive loop
//! sees a stop request; a udpin link answers the address PX4's frames come from.

use rt_config::Px4Link;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, UdpSocket};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How long a read waits before the loop looks at its stop flag and timers.
const READ_TIMEOUT: Duration = Duration::from_millis(20);

type Peer = Arc<Mutex<Option<SocketAddr>>>;

pub(crate) enum Receiver {
    Udp {
        socket: UdpSocket,
        peer: Peer,
        /// udpin: the peer is whoever PX4's frames come from.
        learn_peer: bool,
    },
    Serial(serialport::TTYPort),
}

pub(crate) enum Sender {
    Udp { socket: UdpSocket, peer: Peer },
    Serial(serialport::TTYPort),
}

pub(crate) fn open(link: &Px4Link) -> io::Result<(Receiver, Sender)> {
    match link {
        Px4Link::UdpIn(addr) | Px4Link::UdpOut(addr) => {
            let udpin = matches!(link, Px4Link::UdpIn(_));
            let socket = if udpin {
                UdpSocket::bind(addr)?
            } else {
                let any: SocketAddr = if addr.is_ipv4() {
                    "0.0.0.0:0".parse().expect("literal address")
                } else {
                    "[::]:0".parse().expect("literal address")
                };
                UdpSocket::bind(any)?
            };
            socket.set_read_timeout(Some(READ_TIMEOUT))?;
            let peer = Arc::new(Mutex::new((!udpin).then_some(*addr)));
            let rx = Receiver::Udp {
                socket: socket.try_clone()?,
                peer: peer.clone(),
                learn_peer: udpin,
            };
            Ok((rx, Sender::Udp { socket, peer }))
        }
        Px4Link::Serial { device, baud } => {
            let port = serialport::new(device, *baud)
                .data_bits(serialport::DataBits::Eight)
                .parity(serialport::Parity::None)
                .stop_bits(serialport::StopBits::One)
                .flow_control(serialport::FlowControl::None)
                .timeout(READ_TIMEOUT)
                .open_native()
                .map_err(io::Error::from)?;
            let writer = port.try_clone_native().map_err(io::Error::from)?;
            Ok((Receiver::Serial(port), Sender::Serial(writer)))
        }
    }
}

fn timed_out(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
    )
}

impl Receiver {
    /// True when each chunk is a whole datagram (scanned on its own).
    pub fn datagrams(&self) -> bool {
        matches!(self, Receiver::Udp { .. })
    }

    /// Waits up to [`READ_TIMEOUT`] for bytes: Ok(None) on timeout, else the byte count and
    /// (UDP) the sender.
    pub fn recv(&mut self, buf: &mut [u8]) -> io::Result<Option<(usize, Option<SocketAddr>)>> {
        let r = match self {
            Receiver::Udp { socket, .. } => socket.recv_from(buf).map(|(n, a)| (n, Some(a))),
            Receiver::Serial(port) => port.read(buf).map(|n| (n, None)),
        };
        match r {
            Ok(got) => Ok(Some(got)),
            Err(e) if timed_out(&e) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// A datagram from `from` held a frame from PX4: answer there (udpin only).
    pub fn heard_px4(&self, from: SocketAddr) {
        if let Receiver::Udp {
            peer,
            learn_peer: true,
            ..
        } = self
        {
            let mut p = peer.lock().unwrap_or_else(|e| e.into_inner());
            if *p != Some(from) {
                *p = Some(from);
            }
        }
    }
}

impl Sender {
    /// Sends one frame; Ok(false) when there is nobody to send to yet (udpin before PX4 spoke).
    pub fn send(&mut self, frame: &[u8]) -> io::Result<bool> {
        match self {
            Sender::Udp { socket, peer } => {
                let to = *peer.lock().unwrap_or_else(|e| e.into_inner());
                match to {
                    Some(addr) => socket.send_to(frame, addr).map(|_| true),
                    None => Ok(false),
                }
            }
            Sender::Serial(port) => port.write_all(frame).map(|_| true),
        }
    }
}
