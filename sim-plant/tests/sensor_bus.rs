//! End-to-end: the emulated bus served over a Unix socket, driven through `embedded_hal`.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use embedded_hal::i2c::{Error, ErrorKind, I2c, NoAcknowledgeSource};
use sim_plant::sensor::{
    monotonic_ns, BusConfig, BusServer, Faults, LoadProfile, SensorBus, SensorModel, SensorParams,
    SimI2c,
};

const ADDRS: [u8; 4] = [0x68, 0x6A, 0x6C, 0x6E];

fn temp_socket_path() -> PathBuf {
    static N: AtomicU32 = AtomicU32::new(0);
    std::env::temp_dir().join(format!(
        "taut-sensor-{}-{}.sock",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ))
}

struct Running {
    server: Arc<BusServer>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<std::io::Result<()>>>,
}

impl Running {
    fn start(path: &PathBuf, profile: LoadProfile) -> Running {
        let bus = SensorBus::new(
            BusConfig::ideal(),
            SensorModel::ideal(),
            profile,
            monotonic_ns(),
            11,
        )
        .unwrap();
        let server = Arc::new(BusServer::bind(path, bus).unwrap());
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (server, stop) = (Arc::clone(&server), Arc::clone(&stop));
            std::thread::spawn(move || server.serve(&stop))
        };
        Running {
            server,
            stop,
            thread: Some(thread),
        }
    }

    fn shutdown(mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().unwrap().unwrap();
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Reads until RDY = 0 or the deadline; returns (code, config).
fn poll_ready(i2c: &mut SimI2c, addr: u8, timeout: Duration) -> Option<(i16, u8)> {
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        let mut b = [0u8; 3];
        i2c.read(addr, &mut b).unwrap();
        if b[2] & 0x80 == 0 {
            return Some((i16::from_be_bytes([b[0], b[1]]), b[2]));
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    None
}

#[test]
fn round_trip_one_shot_general_call() {
    let path = temp_socket_path();
    let run = Running::start(&path, LoadProfile::Constant([0.0, 0.0, 9.81]));
    let mut chips: Vec<SimI2c> = ADDRS
        .iter()
        .map(|_| SimI2c::connect(&path).unwrap())
        .collect();
    let mut gc = SimI2c::connect(&path).unwrap();
    for (c, &a) in chips.iter_mut().zip(&ADDRS) {
        c.write(a, &[0x00]).unwrap(); // one-shot, 12 bit, x1
    }
    let t_start = monotonic_ns();
    gc.write(0x00, &[0x08]).unwrap();
    let expect = 500 + (160.0 * 1e-3 * 5.0 / 49.033 * 9.81 / 4.0 * 1000.0_f64).round() as i16;
    for (c, &a) in chips.iter_mut().zip(&ADDRS) {
        let (code, cfg) = poll_ready(c, a, Duration::from_secs(2)).expect("conversion");
        assert_eq!((code, cfg), (expect, 0x00));
        // A second read: RDY = 1, same data.
        let mut b = [0u8; 4];
        c.write_read(a, &[], &mut b).unwrap();
        assert_eq!(b, [0x02, 0x1C, 0x80, 0x80]);
    }
    {
        let bus = run.server.bus();
        let bus = bus.lock().unwrap();
        let mids: Vec<u64> = (0..4)
            .map(|i| bus.chip(i).unwrap().result_window().unwrap().mid_ns)
            .collect();
        assert!(mids.iter().all(|&m| m == mids[0]), "{mids:?}");
        assert!(mids[0] > t_start);
        assert_eq!(bus.general_calls(), 1);
        let c = bus.counters();
        assert!(c.iter().all(|c| c.conversions == 1 && c.nacks == 0));
        assert_eq!(bus.true_force_at(mids[0]), [0.0, 0.0, 9.81]);
    }
    run.shutdown();
    assert!(!path.exists(), "socket file left behind");
}

#[test]
fn continuous_mode_rate_over_the_socket() {
    let path = temp_socket_path();
    let run = Running::start(&path, LoadProfile::Constant([0.0, 0.0, 0.0]));
    let mut c = SimI2c::connect(&path).unwrap();
    c.write(0x68, &[0x10]).unwrap();
    let t0 = Instant::now();
    let before = run.server.bus().lock().unwrap().counters()[0].conversions;
    let mut ready = 0u64;
    while t0.elapsed() < Duration::from_millis(250) {
        let mut b = [0u8; 3];
        c.read(0x68, &mut b).unwrap();
        if b[2] & 0x80 == 0 {
            ready += 1;
            assert_eq!(i16::from_be_bytes([b[0], b[1]]), 500);
        }
        std::thread::sleep(Duration::from_micros(300));
    }
    let elapsed = t0.elapsed().as_secs_f64();
    let conversions = run.server.bus().lock().unwrap().counters()[0].conversions - before;
    // The chip converts at 240 SPS of wall-clock time; each poll sees at most one new result,
    // and only a badly loaded machine (polls > 4 ms apart) misses some.
    let expected = elapsed * 240.0;
    assert!(
        (conversions as f64 - expected).abs() <= 3.0,
        "{conversions} conversions in {elapsed} s"
    );
    assert!(
        ready <= conversions && ready as f64 >= 0.5 * expected,
        "{ready}"
    );
    run.shutdown();
}

#[test]
fn nacks_and_faults_over_the_socket() {
    let path = temp_socket_path();
    let run = Running::start(&path, LoadProfile::Constant([0.0, 0.0, 9.81]));
    let mut c = SimI2c::connect(&path).unwrap();
    let e = c.read(0x42, &mut [0u8; 3]).unwrap_err();
    assert_eq!(
        e.kind(),
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)
    );
    let e = c.write(0x00, &[0x99]).unwrap_err();
    assert_eq!(
        e.kind(),
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data)
    );
    let e = c.read(0x68, &mut [0u8; 300]).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Other);

    let bus = run.server.bus();
    let faults = Faults {
        silent: [false, true, false, false],
        ..Faults::default()
    };
    bus.lock().unwrap().set_faults(faults, monotonic_ns());
    let e = c.read(0x6A, &mut [0u8; 3]).unwrap_err();
    assert_eq!(
        e.kind(),
        ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)
    );
    c.read(0x68, &mut [0u8; 3]).unwrap();
    let counters = bus.lock().unwrap().counters();
    assert_eq!((counters[1].transactions, counters[1].nacks), (1, 1));
    // The connection survives NACKs.
    assert_eq!(c.reconnects(), 0);
    run.shutdown();
}

#[test]
fn broken_socket_is_an_error_then_reconnects() {
    let path = temp_socket_path();
    let run = Running::start(&path, LoadProfile::Constant([0.0, 0.0, 9.81]));
    let mut c = SimI2c::connect(&path).unwrap();
    c.set_timeout(Duration::from_millis(500)).unwrap();
    c.read(0x68, &mut [0u8; 3]).unwrap();
    run.shutdown();
    assert!(!path.exists());
    for _ in 0..3 {
        let e = c.read(0x68, &mut [0u8; 3]).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Other);
        let e = c.write(0x68, &[0x10]).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Other);
    }
    // A new server at the same path: the client finds it again.
    let run = Running::start(&path, LoadProfile::Constant([0.0, 0.0, 9.81]));
    c.write(0x68, &[0x10]).unwrap();
    assert!(c.reconnects() >= 1);
    let (code, _) = poll_ready(&mut c, 0x68, Duration::from_secs(2)).unwrap();
    assert_eq!(code, 540);
    run.shutdown();
    assert!(SimI2c::connect(&path).is_err());
}

#[test]
fn default_sensor_is_close_to_ideal() {
    // The realistic defaults stay within a few %FS of the ideal reading.
    let t0 = 0;
    let mut bus = SensorBus::new(
        BusConfig::default(),
        SensorModel::new(SensorParams::default()).unwrap(),
        LoadProfile::Constant([0.0, 0.0, 9.81]),
        t0,
        1,
    )
    .unwrap();
    for (i, &a) in ADDRS.iter().enumerate() {
        let mut b = [0u8; 3];
        bus.read(a, &mut b, t0 + 10_000_000).unwrap();
        let code = i16::from_be_bytes([b[0], b[1]]);
        assert!((code - 540).abs() <= 8, "cell {} code {code}", i + 1);
    }
}
