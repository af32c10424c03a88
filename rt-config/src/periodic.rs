//! An absolute-deadline periodic loop: `clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)` to the
//! next deadline, so wake-up error never accumulates into drift. A deadline already passed by
//! more than one period is an overrun: it is counted and the schedule skips ahead instead of
//! bursting to catch up.

/// CLOCK_MONOTONIC now, ns.
pub fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime only writes the timespec.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (returns at once if it has passed).
pub fn sleep_until_ns(deadline_ns: u64) {
    let ts = libc::timespec {
        tv_sec: (deadline_ns / 1_000_000_000) as libc::time_t,
        tv_nsec: (deadline_ns % 1_000_000_000) as libc::c_long,
    };
    loop {
        // SAFETY: reads the timespec only; a signal interrupts with EINTR and we sleep again.
        let rc = unsafe {
            libc::clock_nanosleep(
                libc::CLOCK_MONOTONIC,
                libc::TIMER_ABSTIME,
                &ts,
                std::ptr::null_mut(),
            )
        };
        if rc != libc::EINTR {
            return;
        }
    }
}

/// One wake-up of a [`PeriodicLoop`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// Index of this period since start (skipped periods are counted in it).
    pub index: u64,
    /// The deadline this wake-up was scheduled for.
    pub deadline_ns: u64,
    /// How late the wake-up was, ns (`now - deadline`).
    pub lateness_ns: u64,
}

/// The pure schedule of a periodic loop; [`PeriodicLoop`] adds the sleeping.
#[derive(Debug, Clone)]
pub struct PeriodicSchedule {
    start_ns: u64,
    period_ns: u64,
    next_index: u64,
    overruns: u64,
}

impl PeriodicSchedule {
    /// First deadline at `start_ns`.
    pub fn new(start_ns: u64, period_ns: u64) -> Self {
        Self {
            start_ns,
            period_ns: period_ns.max(1),
            next_index: 0,
            overruns: 0,
        }
    }

    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// The deadline the loop will wait for next.
    pub fn next_deadline_ns(&self) -> u64 {
        self.start_ns + self.next_index * self.period_ns
    }

    /// Periods skipped because the loop was later than a whole period.
    pub fn overruns(&self) -> u64 {
        self.overruns
    }

    /// Accounts a wake-up at `now_ns` for the pending deadline and advances the schedule.
    pub fn on_wake(&mut self, now_ns: u64) -> Tick {
        let deadline = self.next_deadline_ns();
        let lateness = now_ns.saturating_sub(deadline);
        let index = self.next_index;
        let missed = lateness / self.period_ns;
        self.overruns += missed;
        self.next_index += 1 + missed;
        Tick {
            index,
            deadline_ns: deadline,
            lateness_ns: lateness,
        }
    }
}

/// A loop that wakes at `start + k * period` on CLOCK_MONOTONIC.
#[derive(Debug, Clone)]
pub struct PeriodicLoop {
    schedule: PeriodicSchedule,
}

impl PeriodicLoop {
    /// Starts one period from now.
    pub fn new(period_ns: u64) -> Self {
        Self::starting_at(now_ns() + period_ns, period_ns)
    }

    pub fn starting_at(start_ns: u64, period_ns: u64) -> Self {
        Self {
            schedule: PeriodicSchedule::new(start_ns, period_ns),
        }
    }

    /// Sleeps to the next deadline and returns the tick.
    pub fn wait(&mut self) -> Tick {
        sleep_until_ns(self.schedule.next_deadline_ns());
        self.schedule.on_wake(now_ns())
    }

    pub fn schedule(&self) -> &PeriodicSchedule {
        &self.schedule
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_time_wakes_advance_one_period() {
        let mut s = PeriodicSchedule::new(1_000, 100);
        let t = s.on_wake(1_010);
        assert_eq!((t.index, t.deadline_ns, t.lateness_ns), (0, 1_000, 10));
        assert_eq!(s.next_deadline_ns(), 1_100);
        assert_eq!(s.overruns(), 0);
    }

    #[test]
    fn a_late_wake_counts_skipped_periods_and_does_not_burst() {
        let mut s = PeriodicSchedule::new(0, 100);
        s.on_wake(0);
        // Woke 250 ns after the deadline at 100: periods at 200 and 300 are gone.
        let t = s.on_wake(350);
        assert_eq!(t.lateness_ns, 250);
        assert_eq!(s.overruns(), 2);
        assert_eq!(s.next_deadline_ns(), 400);
    }

    #[test]
    fn real_loop_keeps_its_schedule() {
        let mut l = PeriodicLoop::new(2_000_000);
        let first = l.wait();
        for _ in 0..4 {
            l.wait();
        }
        // Index counts periods (plus any skipped on a loaded machine): never fewer than 5 wakes.
        assert!(l.schedule().next_deadline_ns() >= first.deadline_ns + 5 * 2_000_000);
    }
}
