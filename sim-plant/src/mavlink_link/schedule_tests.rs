use super::*;

const MS: u64 = 1_000_000;
const S: u64 = 1_000_000_000;

/// Steps `schedule` from `t0` (inclusive) to `t1` (exclusive) every `step` ns; frames per stream.
fn run(schedule: &mut StreamSchedule, t0: u64, t1: u64, step: u64) -> [u32; Stream::COUNT] {
    let mut counts = [0u32; Stream::COUNT];
    let mut t = t0;
    while t < t1 {
        for s in Stream::ALL {
            if schedule.take_due(s, t) {
                counts[s.index()] += 1;
            }
        }
        t += step;
    }
    counts
}

fn assert_within_one(got: u32, expected: f64, what: &str) {
    assert!(
        (f64::from(got) - expected).abs() <= 1.0,
        "{what}: {got} frames, expected {expected} +- 1"
    );
}

#[test]
fn default_rates_over_ten_seconds_at_1khz_are_px4_onboard_rates() {
    let rates = StreamRates::default();
    let mut schedule = StreamSchedule::new(&rates);
    let counts = run(&mut schedule, 0, 10 * S, MS);
    for s in Stream::ALL {
        assert_within_one(counts[s.index()], rates.get(s) * 10.0, &format!("{s:?}"));
    }
    assert_eq!(counts[Stream::AttitudeQuaternion.index()], 500);
    assert_eq!(counts[Stream::EscStatus.index()], 100);
}

#[test]
fn jittery_caller_keeps_the_mean_rate() {
    // Steps alternate 0.3 ms and 1.7 ms (mean 1 ms): phase-keeping gives the exact count.
    let mut schedule = StreamSchedule::new(&StreamRates::default());
    let mut counts = [0u32; Stream::COUNT];
    let mut t = 0u64;
    let mut k = 0u64;
    while t < 10 * S {
        for s in Stream::ALL {
            if schedule.take_due(s, t) {
                counts[s.index()] += 1;
            }
        }
        t += if k.is_multiple_of(2) {
            300_000
        } else {
            1_700_000
        };
        k += 1;
    }
    assert_within_one(counts[Stream::Odometry.index()], 300.0, "odometry");
    assert_within_one(counts[Stream::HighresImu.index()], 500.0, "highres_imu");
}

#[test]
fn a_stall_gives_one_frame_not_a_burst() {
    let mut schedule = StreamSchedule::new(&StreamRates::default());
    run(&mut schedule, 0, S, MS);
    // The caller stalls for 2 s: at its return the 50 Hz stream sends once, then waits 20 ms.
    assert!(schedule.take_due(Stream::AttitudeQuaternion, 3 * S));
    assert!(!schedule.take_due(Stream::AttitudeQuaternion, 3 * S + MS));
    assert!(!schedule.take_due(Stream::AttitudeQuaternion, 3 * S + 19 * MS));
    assert!(schedule.take_due(Stream::AttitudeQuaternion, 3 * S + 20 * MS));
    let counts = run(&mut schedule, 3 * S + 21 * MS, 4 * S + 21 * MS, MS);
    assert_within_one(
        counts[Stream::AttitudeQuaternion.index()],
        50.0,
        "after stall",
    );
}

#[test]
fn interval_change_disable_and_restore() {
    let mut schedule = StreamSchedule::new(&StreamRates::default());
    let odom = Stream::Odometry;
    run(&mut schedule, 0, S, MS);

    schedule.set(odom, IntervalRequest::IntervalNs(10 * MS), S);
    let c = run(&mut schedule, S, 3 * S, MS);
    assert_within_one(c[odom.index()], 200.0, "odometry at 100 Hz");
    assert_eq!(schedule.interval_ns(odom), Some(10 * MS));

    schedule.set(odom, IntervalRequest::Disable, 3 * S);
    let c = run(&mut schedule, 3 * S, 5 * S, MS);
    assert_eq!(c[odom.index()], 0, "disabled odometry sent frames");
    assert_within_one(
        c[Stream::LocalPositionNed.index()],
        60.0,
        "others unaffected",
    );

    schedule.set(odom, IntervalRequest::Default, 5 * S);
    let c = run(&mut schedule, 5 * S, 7 * S, MS);
    assert_within_one(c[odom.index()], 60.0, "odometry restored to 30 Hz");
}

#[test]
fn zero_rate_stream_is_off_until_enabled() {
    let rates = StreamRates {
        esc_status_hz: 0.0,
        ..StreamRates::default()
    };
    let mut schedule = StreamSchedule::new(&rates);
    let c = run(&mut schedule, 0, S, MS);
    assert_eq!(c[Stream::EscStatus.index()], 0);
    schedule.set(Stream::EscStatus, IntervalRequest::IntervalNs(200 * MS), S);
    let c = run(&mut schedule, S, 3 * S, MS);
    assert_within_one(c[Stream::EscStatus.index()], 10.0, "esc at 5 Hz");
}

#[test]
fn interval_request_reads_param2_like_px4() {
    assert_eq!(
        IntervalRequest::from_param_us(0.0),
        Some(IntervalRequest::Default)
    );
    assert_eq!(
        IntervalRequest::from_param_us(-1.0),
        Some(IntervalRequest::Disable)
    );
    assert_eq!(
        IntervalRequest::from_param_us(10_000.0),
        Some(IntervalRequest::IntervalNs(10 * MS))
    );
    assert_eq!(IntervalRequest::from_param_us(f32::NAN), None);
    assert_eq!(IntervalRequest::from_param_us(f32::INFINITY), None);
}
