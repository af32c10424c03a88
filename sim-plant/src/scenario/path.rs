//! Setpoint paths: a drone's position setpoint over a phase, as a chain of segments.
//!
//! Segments move with a minimum-jerk time law (s = 10τ³ - 15τ⁴ + 6τ⁵), so velocity and
//! acceleration are zero at both ends of each segment and a controller fed the feed-forward
//! velocity never sees a jump; a `step` segment jumps, as a setpoint change in the paper does.

use nalgebra::Vector3;
use serde::Deserialize;

/// One piece of a path. Positions NED, m.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Segment {
    /// Jump to `to_ned_m` at the segment start (a setpoint change).
    Step { to_ned_m: [f64; 3] },
    /// Straight line to `to_ned_m` in `duration_s`.
    Line { to_ned_m: [f64; 3], duration_s: f64 },
    /// Circular arc about the vertical axis through `center_ned_m`, turning by `sweep_deg`
    /// (positive = clockwise seen from above, i.e. about +z down, north towards east), at constant
    /// altitude, in `duration_s`.
    Arc {
        center_ned_m: [f64; 2],
        sweep_deg: f64,
        duration_s: f64,
    },
    /// Stay where the previous segment ended for `duration_s`.
    Hold { duration_s: f64 },
}

impl Segment {
    pub fn duration_s(&self) -> f64 {
        match self {
            Segment::Step { .. } => 0.0,
            Segment::Line { duration_s, .. }
            | Segment::Arc { duration_s, .. }
            | Segment::Hold { duration_s } => *duration_s,
        }
    }

    /// Where the segment ends when it starts at `from`.
    fn end(&self, from: Vector3<f64>) -> Vector3<f64> {
        match self {
            Segment::Step { to_ned_m } | Segment::Line { to_ned_m, .. } => v3(*to_ned_m),
            Segment::Arc {
                center_ned_m,
                sweep_deg,
                ..
            } => arc_point(from, *center_ned_m, sweep_deg.to_radians()),
            Segment::Hold { .. } => from,
        }
    }
}

/// A position setpoint with its feed-forward derivatives, NED.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSample {
    pub position_ned_m: Vector3<f64>,
    pub velocity_ned_m_s: Vector3<f64>,
    pub acceleration_ned_m_s2: Vector3<f64>,
}

/// A chain of segments starting at a known point. Sampling allocates nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    start: Vector3<f64>,
    segments: Vec<Segment>,
    /// Start point of each segment (same index as `segments`).
    starts: Vec<Vector3<f64>>,
    /// Start time of each segment, s since the path started.
    times: Vec<f64>,
    duration_s: f64,
}

impl Path {
    pub fn new(start: Vector3<f64>, segments: Vec<Segment>) -> Self {
        let mut starts = Vec::with_capacity(segments.len());
        let mut times = Vec::with_capacity(segments.len());
        let (mut p, mut t) = (start, 0.0);
        for s in &segments {
            starts.push(p);
            times.push(t);
            p = s.end(p);
            t += s.duration_s();
        }
        Path {
            start,
            segments,
            starts,
            times,
            duration_s: t,
        }
    }

    /// Total duration, s.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// Where the path ends (and stays).
    pub fn end(&self) -> Vector3<f64> {
        match (self.segments.last(), self.starts.last()) {
            (Some(s), Some(p)) => s.end(*p),
            _ => self.start,
        }
    }

    /// The setpoint `t_s` after the path started; before 0 the start, after the end the end.
    pub fn sample(&self, t_s: f64) -> PathSample {
        let still = |p| PathSample {
            position_ned_m: p,
            velocity_ned_m_s: Vector3::zeros(),
            acceleration_ned_m_s2: Vector3::zeros(),
        };
        if t_s.is_nan() || t_s < 0.0 {
            return still(self.start);
        }
        // The last segment that has started (a step at time t counts as started).
        let Some(i) = self.times.iter().rposition(|&t0| t0 <= t_s) else {
            return still(self.start);
        };
        let (seg, from, t0) = (&self.segments[i], self.starts[i], self.times[i]);
        let d = seg.duration_s();
        if t_s >= t0 + d {
            return still(seg.end(from));
        }
        let tau = (t_s - t0) / d;
        let (s, ds, dds) = min_jerk(tau);
        let (ds, dds) = (ds / d, dds / (d * d));
        match seg {
            Segment::Line { to_ned_m, .. } => {
                let delta = v3(*to_ned_m) - from;
                PathSample {
                    position_ned_m: from + delta * s,
                    velocity_ned_m_s: delta * ds,
                    acceleration_ned_m_s2: delta * dds,
                }
            }
            Segment::Arc {
                center_ned_m,
                sweep_deg,
                ..
            } => {
                let sweep = sweep_deg.to_radians();
                let c = Vector3::new(center_ned_m[0], center_ned_m[1], from.z);
                let r = from - c;
                let (radius, phi0) = (r.x.hypot(r.y), r.y.atan2(r.x));
                let phi = phi0 + sweep * s;
                let (w, dw) = (sweep * ds, sweep * dds);
                let (sin, cos) = phi.sin_cos();
                let radial = Vector3::new(cos, sin, 0.0);
                let tangent = Vector3::new(-sin, cos, 0.0);
                PathSample {
                    position_ned_m: c + radial * radius,
                    velocity_ned_m_s: tangent * (radius * w),
                    acceleration_ned_m_s2: tangent * (radius * dw) - radial * (radius * w * w),
                }
            }
            Segment::Step { .. } | Segment::Hold { .. } => still(seg.end(from)),
        }
    }
}

/// Minimum-jerk time law and its first two derivatives with respect to τ in [0, 1].
fn min_jerk(tau: f64) -> (f64, f64, f64) {
    let t = tau.clamp(0.0, 1.0);
    let (t2, t3) = (t * t, t * t * t);
    (
        10.0 * t3 - 15.0 * t3 * t + 6.0 * t3 * t2,
        30.0 * t2 - 60.0 * t3 + 30.0 * t3 * t,
        60.0 * t - 180.0 * t2 + 120.0 * t3,
    )
}

fn arc_point(from: Vector3<f64>, center: [f64; 2], sweep: f64) -> Vector3<f64> {
    let (dx, dy) = (from.x - center[0], from.y - center[1]);
    let (sin, cos) = sweep.sin_cos();
    Vector3::new(
        center[0] + dx * cos - dy * sin,
        center[1] + dx * sin + dy * cos,
        from.z,
    )
}

pub(crate) fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}
