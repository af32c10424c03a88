use hdrhistogram::Histogram;
use serde::Serialize;
use std::collections::BTreeMap;

/// Percentiles of one span, microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Percentiles {
    pub count: u64,
    pub p50: f64,
    pub p99: f64,
    pub p999: f64,
    pub max: f64,
}

/// Named HDR histograms of nanosecond durations (1 ns .. 60 s, 3 significant digits).
#[derive(Debug, Clone)]
pub struct SpanHistograms {
    names: Vec<&'static str>,
    hists: Vec<Histogram<u64>>,
    /// Negative durations (clock misuse or a reordered sample), per span.
    negative: Vec<u64>,
}

const MAX_NS: u64 = 60_000_000_000;

impl SpanHistograms {
    pub fn new(names: &[&'static str]) -> Self {
        let hists = names
            .iter()
            .map(|_| Histogram::new_with_bounds(1, MAX_NS, 3).expect("static bounds are valid"))
            .collect();
        Self {
            names: names.to_vec(),
            hists,
            negative: vec![0; names.len()],
        }
    }

    fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| *n == name)
    }

    /// Records `to - from` (ns) under `name`; unknown names and negative spans are counted,
    /// never a panic. Allocation-free.
    pub fn record_span(&mut self, name: &str, from_ns: u64, to_ns: u64) {
        let Some(i) = self.index(name) else { return };
        if to_ns < from_ns {
            self.negative[i] += 1;
            return;
        }
        self.hists[i].saturating_record((to_ns - from_ns).max(1));
    }

    /// Records a duration that may be negative (a lag estimate); negatives are counted apart.
    pub fn record_signed(&mut self, name: &str, ns: i64) {
        if ns < 0 {
            if let Some(i) = self.index(name) {
                self.negative[i] += 1;
            }
        } else {
            self.record_span(name, 0, ns as u64);
        }
    }

    pub fn percentiles(&self, name: &str) -> Option<Percentiles> {
        let h = &self.hists[self.index(name)?];
        let us = |v: u64| v as f64 / 1000.0;
        Some(Percentiles {
            count: h.len(),
            p50: us(h.value_at_quantile(0.5)),
            p99: us(h.value_at_quantile(0.99)),
            p999: us(h.value_at_quantile(0.999)),
            max: us(h.max()),
        })
    }

    /// Every span that has data, by name.
    pub fn summary(&self) -> BTreeMap<String, Percentiles> {
        self.names
            .iter()
            .filter_map(|n| {
                let p = self.percentiles(n)?;
                (p.count > 0).then(|| (n.to_string(), p))
            })
            .collect()
    }

    pub fn negatives(&self, name: &str) -> u64 {
        self.index(name).map_or(0, |i| self.negative[i])
    }

    /// A text histogram of one span: `buckets` rows of equal width between p0.1 and p99.9.
    pub fn ascii_histogram(&self, name: &str, buckets: usize) -> String {
        let Some(i) = self.index(name) else {
            return String::new();
        };
        let h = &self.hists[i];
        if h.is_empty() {
            return format!("{name}: no data\n");
        }
        let lo = h.value_at_quantile(0.001);
        let hi = h.value_at_quantile(0.999).max(lo + 1);
        let width = (hi - lo).div_ceil(buckets as u64).max(1);
        let mut counts = vec![0u64; buckets];
        for v in h.iter_recorded() {
            let x = v.value_iterated_to().clamp(lo, hi);
            let b = (((x - lo) / width) as usize).min(buckets - 1);
            counts[b] += v.count_at_value();
        }
        let top = counts.iter().copied().max().unwrap_or(1).max(1);
        let mut out = format!("{name} (us), {} samples\n", h.len());
        for (b, c) in counts.iter().enumerate() {
            let from = (lo + b as u64 * width) as f64 / 1000.0;
            let bar = "#".repeat((c * 50 / top) as usize);
            out.push_str(&format!("{from:>10.1} | {c:>7} {bar}\n"));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_known_values() {
        let mut s = SpanHistograms::new(&["hop"]);
        for k in 1..=1000u64 {
            s.record_span("hop", 0, k * 1000); // 1..1000 us
        }
        let p = s.percentiles("hop").unwrap();
        assert_eq!(p.count, 1000);
        assert!((p.p50 - 500.0).abs() <= 1.0, "{p:?}");
        assert!((p.p99 - 990.0).abs() <= 1.0, "{p:?}");
        assert!((p.max - 1000.0).abs() <= 1.0, "{p:?}");
    }

    #[test]
    fn negative_and_unknown_spans_are_counted_not_fatal() {
        let mut s = SpanHistograms::new(&["a"]);
        s.record_span("a", 10, 5);
        s.record_signed("a", -3);
        s.record_span("nope", 0, 1);
        assert_eq!(s.negatives("a"), 2);
        assert!(s.summary().is_empty());
        assert!(s.ascii_histogram("a", 5).contains("no data"));
    }
}
