/// A triangle wave between `low` and `high` (vectors, N) with the given rise time, as
/// `(t_s, force)` vertices covering `duration_s`: a load the emulator applies and whose value
/// at every instant the analysis knows.
pub fn triangle_wave(
    low: [f64; 3],
    high: [f64; 3],
    rise_s: f64,
    start_s: f64,
    duration_s: f64,
) -> Vec<(f64, [f64; 3])> {
    let mut v = vec![(0.0, low), (start_s, low)];
    let mut t = start_s;
    let mut up = true;
    while t < start_s + duration_s {
        t += rise_s;
        v.push((t, if up { high } else { low }));
        up = !up;
    }
    v
}

/// Lag of a reading `value` (axis `axis` of the force) published at `t_read_s`, against a
/// piecewise-linear truth `vertices` (time in s since the profile's origin): `t_read_s - t*`
/// with t* the latest time at or before `t_read_s` when the truth had `value` on that axis.
///
/// Returns `None` when the answer is ambiguous: t* within `guard_s` of a vertex (the
/// filter mixes two slopes there), a flat segment, or no crossing within `max_lag_s`.
pub fn ramp_lag(
    vertices: &[(f64, [f64; 3])],
    axis: usize,
    value: f64,
    t_read_s: f64,
    max_lag_s: f64,
    guard_s: f64,
) -> Option<f64> {
    for w in vertices.windows(2).rev() {
        let (ta, fa) = (w[0].0, w[0].1[axis]);
        let (tb, fb) = (w[1].0, w[1].1[axis]);
        if ta > t_read_s {
            continue;
        }
        if tb < t_read_s - max_lag_s {
            return None;
        }
        if (fb - fa).abs() < 1e-12 || tb <= ta {
            continue;
        }
        let t_star = ta + (value - fa) / (fb - fa) * (tb - ta);
        if t_star < ta || t_star > tb.min(t_read_s + 0.5 * max_lag_s) {
            continue;
        }
        if t_star - ta < guard_s || tb - t_star < guard_s {
            return None;
        }
        return Some(t_read_s - t_star);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lag_on_a_rising_and_falling_edge() {
        let tri = triangle_wave([0.0; 3], [0.0, 0.0, 50.0], 0.5, 1.0, 2.0);
        // Rising: truth = 100 N/s * (t - 1). Reading 25 N at t = 1.26 s: truth had 25 N at 1.25.
        let lag = ramp_lag(&tri, 2, 25.0, 1.26, 0.1, 0.02).unwrap();
        assert!((lag - 0.01).abs() < 1e-9);
        // Falling from 50 at 1.5 s: 25 N at 1.75 s; read at 1.758 s.
        let lag = ramp_lag(&tri, 2, 25.0, 1.758, 0.1, 0.02).unwrap();
        assert!((lag - 0.008).abs() < 1e-9);
        // Next to the top vertex: ambiguous.
        assert!(ramp_lag(&tri, 2, 49.9, 1.505, 0.1, 0.02).is_none());
        // Before the wave starts (flat): nothing.
        assert!(ramp_lag(&tri, 2, 0.0, 0.5, 0.1, 0.02).is_none());
    }
}
