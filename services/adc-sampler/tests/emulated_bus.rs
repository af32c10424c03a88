//! The real sampler and driver against the emulated sensor (sim-plant), in one process on a
//! simulated clock: deterministic, and every conversion's true timing is known.

use adc_sampler::mcp3423::Mcp3423;
use adc_sampler::{Clock, Sampler, SamplerSettings};
use embedded_hal::i2c::{
    ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation, SevenBitAddress,
};
use shared_types::{ChannelStatus, SamplingMode};
use sim_plant::sensor::{BusConfig, Faults, LoadProfile, Nack, SensorBus, SensorModel};
use std::cell::{Cell, RefCell};
use std::rc::Rc;

/// Simulated time, shared by the clock and the bus.
#[derive(Clone)]
struct SimTime(Rc<Cell<u64>>);

impl Clock for SimTime {
    fn now_ns(&mut self) -> u64 {
        self.0.get()
    }
    fn sleep_until_ns(&mut self, t: u64) {
        self.0.set(self.0.get().max(t));
    }
}

/// An I2C handle on the shared emulated bus; each transfer takes bus time (400 kHz).
struct BusI2c {
    bus: Rc<RefCell<SensorBus>>,
    time: SimTime,
}

#[derive(Debug)]
struct BusError(ErrorKind);
impl embedded_hal::i2c::Error for BusError {
    fn kind(&self) -> ErrorKind {
        self.0
    }
}
impl ErrorType for BusI2c {
    type Error = BusError;
}

impl I2c<SevenBitAddress> for BusI2c {
    fn transaction(&mut self, addr: u8, ops: &mut [Operation<'_>]) -> Result<(), BusError> {
        for op in ops {
            let t = self.time.0.get();
            let (r, bytes) = match op {
                Operation::Write(b) => (self.bus.borrow_mut().write(addr, b, t), b.len()),
                Operation::Read(b) => (self.bus.borrow_mut().read(addr, b, t), b.len()),
            };
            // Address byte + data bytes, 9 clocks each at 400 kHz, plus start/stop.
            self.time.0.set(t + (1 + bytes as u64) * 22_500 + 5_000);
            r.map_err(|n| {
                BusError(ErrorKind::NoAcknowledge(match n {
                    Nack::Address => NoAcknowledgeSource::Address,
                    Nack::Data => NoAcknowledgeSource::Data,
                }))
            })?;
        }
        Ok(())
    }
}

struct Rig {
    bus: Rc<RefCell<SensorBus>>,
    time: SimTime,
    sampler: Sampler<BusI2c>,
}

fn rig(mode: SamplingMode, bus_cfg: BusConfig, load: [f64; 3]) -> Rig {
    let t0 = 1_000_000_000;
    let time = SimTime(Rc::new(Cell::new(t0)));
    let bus = Rc::new(RefCell::new(
        SensorBus::new(
            bus_cfg,
            SensorModel::ideal(),
            LoadProfile::Constant(load),
            t0,
            7,
        )
        .unwrap(),
    ));
    let handle = || BusI2c {
        bus: bus.clone(),
        time: time.clone(),
    };
    let addrs = bus.borrow().addresses();
    let chips = addrs.map(|a| Mcp3423::new(handle(), a).unwrap());
    let sampler = Sampler::new(chips, handle(), SamplerSettings::new(mode, 240.0, 2));
    Rig { bus, time, sampler }
}

/// Runs `frames` frames; returns (rate Hz, per-frame skew ns, worst timestamp error ns).
fn run(rig: &mut Rig, frames: usize) -> (f64, Vec<u64>, u64) {
    let mut clock = rig.time.clone();
    rig.sampler.start(&mut clock);
    let mut skews = Vec::new();
    let mut worst = 0u64;
    let mut first = None;
    let mut last = 0;
    for k in 0..frames {
        let f = rig.sampler.next_frame(&mut clock);
        assert_eq!(f.header.sequence, k as u64);
        if k < 10 {
            continue; // let the sampler learn the chips' periods
        }
        first.get_or_insert(f.header.t_origin_ns);
        last = f.header.t_origin_ns;
        skews.push(f.skew_ns());
        let bus = rig.bus.borrow();
        for c in 0..4 {
            if f.status[c] == ChannelStatus::Fresh {
                // The chip may have finished again since it was read (while other chips were
                // polled): the conversion read is the newest or one a whole period before.
                let chip = bus.chip(c).unwrap();
                let newest = chip.result_window().unwrap().mid_ns;
                let err = (0..3)
                    .map(|k| (newest - k * chip.period_ns() as u64).abs_diff(f.conversion_ns[c]))
                    .min()
                    .unwrap();
                worst = worst.max(err);
            }
        }
    }
    let rate = (frames - 11) as f64 / ((last - first.unwrap()) as f64 * 1e-9);
    (rate, skews, worst)
}

fn percentile(v: &mut [u64], q: f64) -> u64 {
    v.sort_unstable();
    v[((v.len() - 1) as f64 * q) as usize]
}

#[test]
fn continuous_mode_runs_at_the_chips_rate_with_accurate_timestamps() {
    let mut r = rig(
        SamplingMode::Continuous,
        BusConfig::default(),
        [0.0, 0.0, 9.81],
    );
    let (rate, mut skews, worst) = run(&mut r, 2400);
    // The slowest chip (+0.19 %) sets the frame rate.
    assert!((rate - 240.0 / 1.0019).abs() < 0.5, "rate {rate}");
    assert!(worst < 300_000, "timestamp error {worst} ns");
    let p50 = percentile(&mut skews, 0.5);
    let max = percentile(&mut skews, 1.0);
    // Never more than one period of the slowest chip plus the timestamp error.
    assert!(max < 4_175_000 + 300_000, "skew p50 {p50} max {max}");
    assert!(p50 > 1_000_000, "free-running chips drift apart: p50 {p50}");
    eprintln!("continuous: rate {rate:.2} Hz, skew p50 {p50} ns max {max} ns, ts error {worst} ns");
}

#[test]
fn synchronous_mode_has_no_skew_but_a_lower_rate() {
    let mut r = rig(
        SamplingMode::Synchronous,
        BusConfig::default(),
        [0.0, 0.0, 9.81],
    );
    let (rate, mut skews, worst) = run(&mut r, 1200);
    let max = percentile(&mut skews, 1.0);
    assert!(max < 200_000, "skew max {max}");
    assert!(rate < 240.0 && rate > 200.0, "rate {rate}");
    assert!(worst < 300_000, "timestamp error {worst} ns");
    eprintln!("synchronous: rate {rate:.2} Hz, skew max {max} ns, ts error {worst} ns");
}

#[test]
fn codes_match_the_load() {
    // 9.81 N hanging, ideal sensor: 2.4525 N per cell -> 40.0 mV above 500 mV.
    let mut r = rig(
        SamplingMode::Continuous,
        BusConfig::ideal(),
        [0.0, 0.0, 9.81],
    );
    let mut clock = r.time.clone();
    r.sampler.start(&mut clock);
    let f = (0..5)
        .map(|_| r.sampler.next_frame(&mut clock))
        .last()
        .unwrap();
    assert_eq!(f.codes, [540; 4]);
    assert_eq!(f.status, [ChannelStatus::Fresh; 4]);
}

#[test]
fn faults_are_flagged_and_the_loop_keeps_its_rate() {
    let mut r = rig(
        SamplingMode::Continuous,
        BusConfig::ideal(),
        [0.0, 0.0, 9.81],
    );
    let mut clock = r.time.clone();
    r.sampler.start(&mut clock);
    for _ in 0..20 {
        r.sampler.next_frame(&mut clock);
    }
    let t = r.time.0.get();
    r.bus.borrow_mut().set_faults(
        Faults {
            silent: [false, true, false, false],
            stuck: [false, false, true, false],
            nack_probability: [0.05, 0.0, 0.0, 0.0],
            ..Faults::default()
        },
        t,
    );
    let start = r.time.0.get();
    let mut last = None;
    for _ in 0..240 {
        last = Some(r.sampler.next_frame(&mut clock));
    }
    let f = last.unwrap();
    let secs = (r.time.0.get() - start) as f64 * 1e-9;
    assert_eq!(f.status[1], ChannelStatus::BusError, "silent chip");
    assert_eq!(f.status[2], ChannelStatus::Stale, "stuck chip");
    assert_eq!(f.status[3], ChannelStatus::Fresh);
    assert_eq!(f.codes[3], 540);
    assert!(r.sampler.counters().bus_errors > 240);
    // 240 frames still take about one second: a dead chip does not slow the others.
    assert!((0.95..1.3).contains(&secs), "240 frames took {secs} s");
}
