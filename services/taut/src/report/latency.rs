//! Latency spans from the samples' headers, as HDR histograms (1 ns .. 60 s, 3 significant
//! digits, as `latency-tests`): per drone, the time from a sample's physical origin to each
//! stage's publication, and the recorder's transport.

use hdrhistogram::Histogram;
use recorder::Timed;
use shared_types::{setpoint_flags, Header};

use super::load::DroneData;

/// Largest duration recorded, ns (longer ones saturate).
const MAX_NS: u64 = 60_000_000_000;

/// Name and definition of every span, in report order.
pub const SPANS: [(&str, &str); 7] = [
    ("sampler", "raw_adc publish − origin"),
    ("tension stage", "tension publish − origin"),
    ("estimator", "tension_estimate publish − origin"),
    (
        "controller from tension",
        "attitude_setpoint publish − tension_origin_ns (flight steps that used a tension sample)",
    ),
    (
        "controller from odometry",
        "attitude_setpoint publish − odometry_origin_ns (flight steps)",
    ),
    (
        "bridge",
        "vehicle_state publish − origin (ODOMETRY receipt)",
    ),
    (
        "recorder transport",
        "log_time − publish_time, every channel of the drone",
    ),
];

/// One span of one drone.
#[derive(Debug, Clone)]
pub struct SpanLatency {
    pub drone: String,
    pub span: &'static str,
    pub hist: Histogram<u64>,
    /// Spans that came out negative (clock misuse or reordering): counted, not recorded.
    pub negatives: u64,
}

impl SpanLatency {
    fn new(drone: &str, i: usize) -> Self {
        SpanLatency {
            drone: drone.to_string(),
            span: SPANS[i].0,
            hist: Histogram::new_with_bounds(1, MAX_NS, 3).expect("static bounds are valid"),
            negatives: 0,
        }
    }

    fn record(&mut self, from_ns: u64, to_ns: u64) {
        if to_ns < from_ns {
            self.negatives += 1;
        } else {
            self.hist.saturating_record((to_ns - from_ns).max(1));
        }
    }

    pub fn count(&self) -> u64 {
        self.hist.len()
    }

    /// The latency at quantile `q` (0..=1), ms.
    pub fn quantile_ms(&self, q: f64) -> f64 {
        self.hist.value_at_quantile(q) as f64 * 1e-6
    }

    pub fn max_ms(&self) -> f64 {
        self.hist.max() as f64 * 1e-6
    }

    /// The percentile distribution as HdrHistogram plots it: (1 / (1 − p), latency ms), p < 1,
    /// then the maximum at the last x (or at x = count if that is further).
    pub fn curve(&self) -> Vec<(f64, f64)> {
        if self.hist.is_empty() {
            return Vec::new();
        }
        let mut out: Vec<(f64, f64)> = Vec::new();
        for v in self.hist.iter_quantiles(5) {
            let q = v.quantile_iterated_to();
            if q < 1.0 {
                out.push((1.0 / (1.0 - q), v.value_iterated_to() as f64 * 1e-6));
            }
        }
        let last_x = out.last().map_or(1.0, |p| p.0);
        out.push((last_x.max(self.count() as f64), self.max_ms()));
        out
    }
}

/// Every span of drone `d` (spans without samples included, with a count of 0).
pub fn drone_spans(d: &DroneData) -> Vec<SpanLatency> {
    let mut s: Vec<SpanLatency> = (0..SPANS.len())
        .map(|i| SpanLatency::new(&d.id, i))
        .collect();
    let stage = |span: &mut SpanLatency, h: &Header| span.record(h.t_origin_ns, h.t_publish_ns);
    d.raw_adc
        .iter()
        .for_each(|x| stage(&mut s[0], &x.sample.header));
    d.tension
        .iter()
        .for_each(|x| stage(&mut s[1], &x.sample.header));
    d.tension_estimate
        .iter()
        .for_each(|x| stage(&mut s[2], &x.sample.header));
    // Flight steps only, as the summary's latencies: before arming the controller runs on its
    // fallback deadline and PX4 streams odometry at its default rate.
    for sp in d
        .attitude
        .iter()
        .filter(|x| x.sample.flags & setpoint_flags::IDLE == 0)
    {
        let t = sp.sample.header.t_publish_ns;
        if sp.sample.tension_origin_ns > 0 {
            s[3].record(sp.sample.tension_origin_ns, t);
        }
        if sp.sample.odometry_origin_ns > 0 {
            s[4].record(sp.sample.odometry_origin_ns, t);
        }
    }
    d.vehicle_state
        .iter()
        .for_each(|x| stage(&mut s[5], &x.sample.header));
    let transport = &mut s[6];
    transport_of(transport, &d.raw_adc, |x| x.header);
    transport_of(transport, &d.tension, |x| x.header);
    transport_of(transport, &d.tension_estimate, |x| x.header);
    transport_of(transport, &d.tension_truth, |x| x.header);
    transport_of(transport, &d.vehicle_state, |x| x.header);
    transport_of(transport, &d.imu, |x| x.header);
    transport_of(transport, &d.motor_speeds, |x| x.header);
    transport_of(transport, &d.mission, |x| x.header);
    transport_of(transport, &d.attitude, |x| x.header);
    s
}

fn transport_of<T>(span: &mut SpanLatency, samples: &[Timed<T>], header: impl Fn(&T) -> Header) {
    for x in samples {
        span.record(header(&x.sample).t_publish_ns, x.log_time_ns);
    }
}
