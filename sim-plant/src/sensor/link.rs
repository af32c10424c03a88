//! The emulated bus served over a Unix socket, so the real sampler (another process) can talk
//! I2C to it through `embedded_hal::i2c::I2c`.
//!
//! # Transport
//!
//! A Unix `SOCK_SEQPACKET` socket (via libc, as std has none): connection-oriented like a
//! stream, but message boundaries are kept, so one packet is one request and no framing is
//! needed. The server accepts any number of clients, one thread each; the bus sits behind a
//! Mutex and the server reads CLOCK_MONOTONIC when a request arrives and passes that time in.
//!
//! # Protocol (one packet each way)
//!
//! ```text
//! request:  [op, addr, len, payload...]
//!           op 1 = write: payload is the `len` bytes to write (len 0..=255)
//!           op 2 = read:  no payload; read `len` bytes (0..=255)
//! response: [status, data...]
//!           status 0 = ACK      (a read carries exactly `len` data bytes)
//!                  1 = NACK on the address
//!                  2 = NACK on data
//!                  3 = malformed request (bad op, length mismatch, too short or long)
//! ```
//!
//! An empty packet is taken as the client hanging up (SEQPACKET cannot tell them apart).

use std::io;
use std::os::fd::OwnedFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use embedded_hal::i2c::{
    ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation, SevenBitAddress,
};

use super::bus::{Nack, SensorBus};
use super::link_sys as sys;
pub use super::link_sys::monotonic_ns;

pub const OP_WRITE: u8 = 1;
pub const OP_READ: u8 = 2;
pub const STATUS_ACK: u8 = 0;
pub const STATUS_NACK_ADDRESS: u8 = 1;
pub const STATUS_NACK_DATA: u8 = 2;
pub const STATUS_BAD_REQUEST: u8 = 3;
/// Largest read or write per request.
pub const MAX_LEN: usize = 255;
/// Largest valid request packet.
pub const MAX_REQUEST: usize = 3 + MAX_LEN;
/// Largest response packet.
pub const MAX_RESPONSE: usize = 1 + MAX_LEN;

/// How often blocked server threads look at the stop flag.
const POLL_MS: i32 = 50;

fn lock(bus: &Mutex<SensorBus>) -> MutexGuard<'_, SensorBus> {
    // A panic elsewhere while holding the lock leaves the bus usable; keep serving.
    bus.lock().unwrap_or_else(|e| e.into_inner())
}

fn nack_status(n: Nack) -> u8 {
    match n {
        Nack::Address => STATUS_NACK_ADDRESS,
        Nack::Data => STATUS_NACK_DATA,
    }
}

/// Executes one request packet against `bus` at `t_ns`; writes the response into `resp` and
/// returns its length. Accepts any bytes.
pub fn handle_request(
    bus: &mut SensorBus,
    req: &[u8],
    t_ns: u64,
    resp: &mut [u8; MAX_RESPONSE],
) -> usize {
    let [op, addr, len, payload @ ..] = req else {
        resp[0] = STATUS_BAD_REQUEST;
        return 1;
    };
    let len = usize::from(*len);
    match *op {
        OP_WRITE if payload.len() == len => {
            resp[0] = match bus.write(*addr, payload, t_ns) {
                Ok(()) => STATUS_ACK,
                Err(n) => nack_status(n),
            };
            1
        }
        OP_READ if payload.is_empty() => match bus.read(*addr, &mut resp[1..1 + len], t_ns) {
            Ok(()) => {
                resp[0] = STATUS_ACK;
                1 + len
            }
            Err(n) => {
                resp[0] = nack_status(n);
                1
            }
        },
        _ => {
            resp[0] = STATUS_BAD_REQUEST;
            1
        }
    }
}

/// Serves one [`SensorBus`] on a Unix seqpacket socket.
#[derive(Debug)]
pub struct BusServer {
    listener: OwnedFd,
    path: PathBuf,
    bus: Arc<Mutex<SensorBus>>,
}

impl BusServer {
    /// Binds and listens at `path`. A stale socket file there (left by a crashed server) is
    /// removed first; any other kind of file is an error. The file is removed on drop.
    pub fn bind(path: impl AsRef<Path>, bus: SensorBus) -> io::Result<Self> {
        let path = path.as_ref().to_path_buf();
        if let Ok(meta) = std::fs::symlink_metadata(&path) {
            use std::os::unix::fs::FileTypeExt;
            if !meta.file_type().is_socket() {
                return Err(io::Error::new(
                    io::ErrorKind::AlreadyExists,
                    format!("{} exists and is not a socket", path.display()),
                ));
            }
            std::fs::remove_file(&path)?;
        }
        let listener = sys::bind_listen(&path, 16)?;
        Ok(BusServer {
            listener,
            path,
            bus: Arc::new(Mutex::new(bus)),
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The shared bus, to set faults or read counters and ground truth while serving.
    pub fn bus(&self) -> Arc<Mutex<SensorBus>> {
        Arc::clone(&self.bus)
    }

    /// Accepts and serves clients until `stop` is set (checked every 50 ms), then waits for
    /// the connection threads to finish. Errors of one connection only end that connection.
    pub fn serve(&self, stop: &AtomicBool) -> io::Result<()> {
        // Set when the accept loop fails, so the connection threads end too.
        let abort = AtomicBool::new(false);
        let quit = || stop.load(Ordering::Relaxed) || abort.load(Ordering::Relaxed);
        std::thread::scope(|s| {
            let result = self.accept_loop(&quit, |conn| {
                let bus = &*self.bus;
                let quit = &quit;
                s.spawn(move || serve_connection(&conn, bus, quit));
            });
            if result.is_err() {
                abort.store(true, Ordering::Relaxed);
            }
            result
        })
    }

    fn accept_loop(
        &self,
        quit: &dyn Fn() -> bool,
        mut spawn: impl FnMut(OwnedFd),
    ) -> io::Result<()> {
        while !quit() {
            if !sys::poll_in(&self.listener, POLL_MS)? {
                continue;
            }
            match sys::accept(&self.listener) {
                Ok(conn) => spawn(conn),
                Err(e) => match e.raw_os_error() {
                    // The client went away between poll and accept, or a transient limit.
                    Some(
                        libc::EINTR
                        | libc::EAGAIN
                        | libc::ECONNABORTED
                        | libc::EMFILE
                        | libc::ENFILE
                        | libc::ENOBUFS
                        | libc::ENOMEM,
                    ) => std::thread::sleep(Duration::from_millis(1)),
                    _ => return Err(e),
                },
            }
        }
        Ok(())
    }
}

impl Drop for BusServer {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

fn serve_connection(conn: &OwnedFd, bus: &Mutex<SensorBus>, quit: &dyn Fn() -> bool) {
    // One spare byte so an over-long packet shows up as too long, not as a valid one.
    let mut req = [0u8; MAX_REQUEST + 1];
    let mut resp = [0u8; MAX_RESPONSE];
    while !quit() {
        match sys::poll_in(conn, POLL_MS) {
            Ok(true) => {}
            Ok(false) => continue,
            Err(_) => return,
        }
        let n = match sys::recv(conn, &mut req) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(_) => return,
        };
        let t_ns = monotonic_ns();
        let m = handle_request(&mut lock(bus), &req[..n], t_ns, &mut resp);
        if sys::send(conn, &resp[..m]).is_err() {
            return;
        }
    }
}

/// Errors of [`SimI2c`].
#[derive(Debug, thiserror::Error)]
pub enum SimI2cError {
    #[error("I2C NACK: {0}")]
    Nack(NoAcknowledgeSource),
    #[error("emulator socket: {0}")]
    Io(#[from] io::Error),
    #[error("malformed response from the emulator: {0}")]
    Protocol(&'static str),
    #[error("the emulator rejected the request as malformed")]
    BadRequest,
    #[error("an operation of {0} bytes exceeds the {MAX_LEN}-byte limit")]
    TooLong(usize),
}

impl embedded_hal::i2c::Error for SimI2cError {
    fn kind(&self) -> ErrorKind {
        match self {
            SimI2cError::Nack(src) => ErrorKind::NoAcknowledge(*src),
            _ => ErrorKind::Other,
        }
    }
}

/// An I2C master talking to a [`BusServer`]. Each `Operation` of a transaction is one
/// request, in order. After a socket error the connection is dropped and the next request
/// reconnects; a request whose send fails on an old connection is retried once on a new one
/// (it cannot have reached the server). Never panics on a broken socket.
#[derive(Debug)]
pub struct SimI2c {
    path: PathBuf,
    conn: Option<OwnedFd>,
    timeout: Duration,
    reconnects: u64,
}

impl SimI2c {
    /// Connects to the server at `path`, with a 1 s reply timeout.
    pub fn connect(path: impl AsRef<Path>) -> io::Result<Self> {
        let mut c = SimI2c {
            path: path.as_ref().to_path_buf(),
            conn: None,
            timeout: Duration::from_secs(1),
            reconnects: 0,
        };
        c.conn = Some(c.open()?);
        Ok(c)
    }

    /// Sets the send/reply timeout (at least 1 ms) for this and later connections.
    pub fn set_timeout(&mut self, timeout: Duration) -> io::Result<()> {
        self.timeout = timeout.max(Duration::from_millis(1));
        if let Some(c) = &self.conn {
            sys::set_timeouts(c, self.timeout)?;
        }
        Ok(())
    }

    /// Times a new connection was opened after the first.
    pub fn reconnects(&self) -> u64 {
        self.reconnects
    }

    fn open(&self) -> io::Result<OwnedFd> {
        let fd = sys::connect(&self.path)?;
        sys::set_timeouts(&fd, self.timeout)?;
        Ok(fd)
    }

    fn send_request(&mut self, req: &[u8]) -> io::Result<()> {
        let fresh = self.conn.is_none();
        if fresh {
            self.conn = Some(self.open()?);
            self.reconnects += 1;
        }
        let Some(conn) = &self.conn else {
            return Err(io::ErrorKind::NotConnected.into());
        };
        match sys::send(conn, req) {
            Ok(n) if n == req.len() => Ok(()),
            Ok(_) => Err(io::Error::new(io::ErrorKind::WriteZero, "short send")),
            Err(_) if !fresh => {
                self.conn = None;
                self.send_request(req)
            }
            Err(e) => Err(e),
        }
    }

    /// One request/response exchange; returns the response length.
    fn exchange(&mut self, req: &[u8], resp: &mut [u8]) -> Result<usize, SimI2cError> {
        let result = self.send_request(req).and_then(|()| {
            let conn = self.conn.as_ref().ok_or(io::ErrorKind::NotConnected)?;
            match sys::recv(conn, resp)? {
                0 => Err(io::Error::new(
                    io::ErrorKind::UnexpectedEof,
                    "emulator closed the connection",
                )),
                n => Ok(n),
            }
        });
        result.map_err(|e| {
            // A late reply would be taken for the next request's: start over.
            self.conn = None;
            SimI2cError::Io(e)
        })
    }

    fn check_status(&mut self, status: u8) -> Result<(), SimI2cError> {
        match status {
            STATUS_ACK => Ok(()),
            STATUS_NACK_ADDRESS => Err(SimI2cError::Nack(NoAcknowledgeSource::Address)),
            STATUS_NACK_DATA => Err(SimI2cError::Nack(NoAcknowledgeSource::Data)),
            STATUS_BAD_REQUEST => Err(SimI2cError::BadRequest),
            _ => {
                self.conn = None;
                Err(SimI2cError::Protocol("unknown status"))
            }
        }
    }

    fn read_op(&mut self, addr: u8, buf: &mut [u8]) -> Result<(), SimI2cError> {
        let len = u8::try_from(buf.len()).map_err(|_| SimI2cError::TooLong(buf.len()))?;
        let mut resp = [0u8; MAX_RESPONSE + 1];
        let n = self.exchange(&[OP_READ, addr, len], &mut resp)?;
        self.check_status(resp[0])?;
        if n != 1 + buf.len() {
            self.conn = None;
            return Err(SimI2cError::Protocol("read response length"));
        }
        buf.copy_from_slice(&resp[1..n]);
        Ok(())
    }

    fn write_op(&mut self, addr: u8, bytes: &[u8]) -> Result<(), SimI2cError> {
        let len = u8::try_from(bytes.len()).map_err(|_| SimI2cError::TooLong(bytes.len()))?;
        let mut req = [0u8; MAX_REQUEST];
        req[..3].copy_from_slice(&[OP_WRITE, addr, len]);
        req[3..3 + bytes.len()].copy_from_slice(bytes);
        let mut resp = [0u8; MAX_RESPONSE + 1];
        let n = self.exchange(&req[..3 + bytes.len()], &mut resp)?;
        self.check_status(resp[0])?;
        if n != 1 {
            self.conn = None;
            return Err(SimI2cError::Protocol("write response length"));
        }
        Ok(())
    }
}

impl ErrorType for SimI2c {
    type Error = SimI2cError;
}

impl I2c<SevenBitAddress> for SimI2c {
    fn transaction(
        &mut self,
        address: SevenBitAddress,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        for op in operations {
            match op {
                Operation::Read(buf) => self.read_op(address, buf)?,
                Operation::Write(bytes) => self.write_op(address, bytes)?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
#[path = "link_tests.rs"]
mod tests;
