//! The recorder service: subscribes to every topic of the listed drones (and the plant's truth
//! in simulation) with deep buffers, drains them into one MCAP file until SIGINT/SIGTERM, then
//! drains what is left and closes the file. Not real-time: it runs at normal priority and never
//! blocks a publisher (iceoryx2 safe overflow): if it falls behind it loses the oldest samples,
//! which it counts from sequence gaps and writes into the file.
//!
//! It polls (every [`POLL_PERIOD`]) instead of waiting on an event: one process listens to ~20
//! topics, a deep buffer makes a few ms of latency harmless, and it is off the real-time path.

use std::path::{Path, PathBuf};
use std::time::Duration;

use rt_config::periodic::now_ns;
use rt_config::Config;
use shared_types::{names, PlantTruth};
use taut_ipc::{stop_requested, Ipc, TopicSubscriber};

use crate::format::{visit_drone_topics, DroneTopicVisitor, Recordable};
use crate::write::{ChannelHandle, ChannelStats, Mode, RecordingInfo, RecordingWriter};

/// How long the loop sleeps when every buffer was empty.
pub const POLL_PERIOD: Duration = Duration::from_millis(5);

/// What to record and where.
#[derive(Debug, Clone)]
pub struct RecordOptions {
    /// iceoryx2 root of the drones' services.
    pub ipc_root: String,
    pub uavs: Vec<String>,
    /// Also record the plant's ground truth (`/plant/truth`).
    pub truth: bool,
    pub out: PathBuf,
    /// (uav, effective config TOML), attached as `config/<uav>.toml`.
    pub configs: Vec<(String, String)>,
    pub chunk_period_ns: u64,
    /// Each subscriber's buffer, samples.
    pub buffer: usize,
    /// Created once every subscriber is connected: a launcher waits for it before starting
    /// the services, so the recording holds every sample from the first.
    pub ready_file: Option<PathBuf>,
    /// Prefix of the iceoryx2 node names.
    pub node_name: String,
}

/// One subscribed topic and its channel (added on the first sample, so a topic nobody
/// publishes leaves no empty channel).
struct Tap<T: Recordable> {
    uav: String,
    topic: &'static str,
    sub: TopicSubscriber<T>,
    channel: Option<ChannelHandle>,
}

/// A tap of any sample type.
trait Drain {
    /// Writes every queued sample; returns how many.
    fn drain(&mut self, w: &mut RecordingWriter) -> Result<usize, String>;
}

impl<T: Recordable> Drain for Tap<T> {
    fn drain(&mut self, w: &mut RecordingWriter) -> Result<usize, String> {
        let mut failure = None;
        let (uav, topic, channel) = (&self.uav, self.topic, &mut self.channel);
        let n = self
            .sub
            .drain(&mut |sample: T| {
                if failure.is_some() {
                    return;
                }
                let ch = match *channel {
                    Some(ch) => Ok(ch),
                    None => w.add_channel::<T>(uav, topic).map(|ch| *channel.insert(ch)),
                };
                if let Err(e) = ch.and_then(|ch| w.write(ch, now_ns(), &sample)) {
                    failure = Some(e.to_string());
                }
            })
            .map_err(|e| e.to_string())?;
        failure.map_or(Ok(n), Err)
    }
}

/// Subscribes to every drone topic of `uav` (see [`visit_drone_topics`]).
struct DroneTaps<'a> {
    ipc: &'a Ipc,
    uav: &'a str,
    buffer: usize,
    taps: Vec<Box<dyn Drain>>,
}

impl DroneTopicVisitor for DroneTaps<'_> {
    type Error = String;
    fn visit<T: Recordable>(&mut self, topic: &'static str) -> Result<(), String> {
        self.taps
            .push(tap::<T>(self.ipc, self.uav, topic, self.buffer)?);
        Ok(())
    }
}

fn tap<T: Recordable>(
    ipc: &Ipc,
    uav: &str,
    topic: &'static str,
    buffer: usize,
) -> Result<Box<dyn Drain>, String> {
    Ok(Box::new(Tap::<T> {
        uav: uav.to_string(),
        topic,
        sub: ipc
            .subscriber_with_buffer(topic, buffer)
            .map_err(|e| e.to_string())?,
        channel: None,
    }))
}

fn open_drone(ipc: &Ipc, uav: &str, buffer: usize) -> Result<Vec<Box<dyn Drain>>, String> {
    let mut v = DroneTaps {
        ipc,
        uav,
        buffer,
        taps: Vec::new(),
    };
    visit_drone_topics(&mut v)?;
    Ok(v.taps)
}

fn drain_all(taps: &mut [Box<dyn Drain>], w: &mut RecordingWriter) -> Result<usize, String> {
    let mut n = 0;
    for t in taps.iter_mut() {
        n += t.drain(w)?;
    }
    Ok(n)
}

/// Records until SIGINT/SIGTERM (or [`taut_ipc::request_stop`]), then drains and closes.
/// Returns what each channel took and lost.
pub fn record(opts: &RecordOptions) -> Result<Vec<ChannelStats>, String> {
    let info = RecordingInfo {
        mode: Mode::Realtime,
        uavs: opts.uavs.clone(),
        chunk_period_ns: opts.chunk_period_ns,
    };
    let mut w = RecordingWriter::create(&opts.out, &info).map_err(|e| e.to_string())?;
    for (uav, toml) in &opts.configs {
        w.attach_config(uav, toml).map_err(|e| e.to_string())?;
    }
    // The nodes must outlive the subscribers.
    let mut ipcs = Vec::new();
    let mut taps: Vec<Box<dyn Drain>> = Vec::new();
    for uav in &opts.uavs {
        let ipc = Ipc::new(&format!("{}-{uav}", opts.node_name), &opts.ipc_root, uav)
            .map_err(|e| e.to_string())?;
        taps.extend(open_drone(&ipc, uav, opts.buffer)?);
        ipcs.push(ipc);
    }
    if opts.truth {
        let plant = names::PLANT;
        let ipc = Ipc::new(
            &format!("{}-{plant}", opts.node_name),
            &opts.ipc_root,
            plant,
        )
        .map_err(|e| e.to_string())?;
        taps.push(tap::<PlantTruth>(&ipc, plant, names::TRUTH, opts.buffer)?);
        ipcs.push(ipc);
    }
    // The first drain connects every subscriber to the publishers already there.
    drain_all(&mut taps, &mut w)?;
    if let Some(ready) = &opts.ready_file {
        std::fs::write(ready, "ready\n").map_err(|e| format!("{}: {e}", ready.display()))?;
    }
    eprintln!(
        "[recorder] recording {} topics of {} to {}",
        taps.len(),
        opts.uavs.join(", ")
            + if opts.truth {
                " and the plant's truth"
            } else {
                ""
            },
        opts.out.display()
    );
    while !stop_requested() {
        let n = drain_all(&mut taps, &mut w)?;
        w.tick(now_ns()).map_err(|e| e.to_string())?;
        if n == 0 {
            std::thread::sleep(POLL_PERIOD);
        }
    }
    // What the publishers sent before they stopped is still queued: take it all.
    while drain_all(&mut taps, &mut w)? > 0 {}
    let stats = w.finish().map_err(|e| e.to_string())?;
    report(&stats, &opts.out);
    Ok(stats)
}

fn report(stats: &[ChannelStats], out: &Path) {
    for s in stats {
        eprintln!(
            "[recorder] {} received={} drops={} missed_before_start={} restarts={}",
            s.topic, s.received, s.drops, s.missed_before_start, s.restarts
        );
    }
    let total: u64 = stats.iter().map(|s| s.received).sum();
    let drops: u64 = stats.iter().map(|s| s.drops).sum();
    eprintln!(
        "[recorder] stopped: {total} samples on {} channels, {drops} dropped, in {}",
        stats.len(),
        out.display()
    );
}

/// `taut svc recorder --config FILE`: one drone's topics into
/// `<recorder.dir>/<uav>-<UTC time>.mcap`, its effective config attached.
pub fn run(cfg: &Config) -> Result<(), String> {
    run_with_ready(cfg, None)
}

/// [`run`], creating `ready` once subscribed to every topic.
pub fn run_with_ready(cfg: &Config, ready: Option<&Path>) -> Result<(), String> {
    let dir = Path::new(&cfg.recorder.dir);
    std::fs::create_dir_all(dir).map_err(|e| format!("recorder.dir = {dir:?}: {e}"))?;
    let opts = RecordOptions {
        ipc_root: cfg.ipc_root.clone(),
        uavs: vec![cfg.uav.clone()],
        truth: false,
        out: dir.join(format!("{}-{}.mcap", cfg.uav, utc_stamp())),
        configs: vec![(cfg.uav.clone(), cfg.to_toml())],
        chunk_period_ns: (cfg.recorder.chunk_period_s * 1e9) as u64,
        buffer: cfg.recorder.buffer,
        ready_file: ready.map(Path::to_path_buf),
        node_name: format!("{}-recorder", cfg.uav),
    };
    record(&opts).map(drop)
}

/// The wall-clock time now as `YYYYMMDDTHHMMSSZ` (UTC).
fn utc_stamp() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let (days, rem) = ((secs / 86_400) as i64, secs % 86_400);
    let (y, m, d) = civil_from_days(days);
    format!(
        "{y:04}{m:02}{d:02}T{:02}{:02}{:02}Z",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

/// Days since 1970-01-01 to (year, month, day), proleptic Gregorian (H. Hinnant's algorithm).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

#[cfg(test)]
mod tests {
    #[test]
    fn civil_dates() {
        assert_eq!(super::civil_from_days(0), (1970, 1, 1));
        assert_eq!(super::civil_from_days(19_782), (2024, 2, 29));
        assert_eq!(super::civil_from_days(20_000), (2024, 10, 4));
        assert_eq!(super::utc_stamp().len(), 16);
    }
}
