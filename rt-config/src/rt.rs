//! Real-time setup of a service process: lock memory, SCHED_FIFO priority, core pinning.
//!
//! Each setting is tried independently; what the OS refuses is reported and, under
//! [`RtPolicy::Require`], fails the start. In a VM or a container without CAP_SYS_NICE,
//! `warn` lets the same binary run with best effort.

use crate::config::{RtPolicy, ServiceRt};
use thread_priority::{
    set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy, ThreadPriority,
    ThreadPriorityValue, ThreadSchedulePolicy,
};

/// A real-time setting the OS refused.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum RtError {
    #[error("mlockall refused: {0}")]
    LockMemory(String),
    #[error("SCHED_FIFO priority {priority} refused: {reason}")]
    Priority { priority: u8, reason: String },
    #[error("pinning to core {core} refused: {reason}")]
    Pin { core: usize, reason: String },
}

/// What [`apply`] achieved.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct RtReport {
    pub memory_locked: bool,
    pub fifo_priority: Option<u8>,
    pub pinned_core: Option<usize>,
    /// Refusals tolerated under [`RtPolicy::Warn`].
    pub warnings: Vec<RtError>,
}

impl std::fmt::Display for RtReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "mlockall={} fifo={} core={}",
            self.memory_locked,
            self.fifo_priority
                .map_or("off".to_string(), |p| p.to_string()),
            self.pinned_core
                .map_or("any".to_string(), |c| c.to_string())
        )?;
        for w in &self.warnings {
            write!(f, "; warning: {w}")?;
        }
        Ok(())
    }
}

/// Applies `rt` to the calling thread (call it first thing in a service's `main`, before
/// spawning threads, so they inherit the settings).
pub fn apply(rt: &ServiceRt) -> Result<RtReport, RtError> {
    let mut report = RtReport::default();
    let mut outcome = |r: Result<(), RtError>| -> Result<(), RtError> {
        match (r, rt.policy) {
            (Ok(()), _) => Ok(()),
            (Err(e), RtPolicy::Warn) => {
                report.warnings.push(e);
                Ok(())
            }
            (Err(e), RtPolicy::Require) => Err(e),
        }
    };
    if rt.lock_memory {
        let r = lock_memory();
        let ok = r.is_ok();
        outcome(r)?;
        report.memory_locked = ok;
    }
    if let Some(core) = rt.core {
        let r = pin_to_core(core);
        let ok = r.is_ok();
        outcome(r)?;
        report.pinned_core = ok.then_some(core);
    }
    if let Some(priority) = rt.priority {
        let r = set_fifo_priority(priority);
        let ok = r.is_ok();
        outcome(r)?;
        report.fifo_priority = ok.then_some(priority);
    }
    Ok(report)
}

fn lock_memory() -> Result<(), RtError> {
    // SAFETY: mlockall only changes the paging of this process.
    let rc = unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) };
    if rc == 0 {
        Ok(())
    } else {
        Err(RtError::LockMemory(
            std::io::Error::last_os_error().to_string(),
        ))
    }
}

fn pin_to_core(core: usize) -> Result<(), RtError> {
    let ids = core_affinity::get_core_ids().unwrap_or_default();
    let Some(id) = ids.into_iter().find(|c| c.id == core) else {
        return Err(RtError::Pin {
            core,
            reason: "no such core on this machine".into(),
        });
    };
    if core_affinity::set_for_current(id) {
        Ok(())
    } else {
        Err(RtError::Pin {
            core,
            reason: "sched_setaffinity failed".into(),
        })
    }
}

fn set_fifo_priority(priority: u8) -> Result<(), RtError> {
    let value = ThreadPriorityValue::try_from(priority).map_err(|e| RtError::Priority {
        priority,
        reason: e.to_string(),
    })?;
    set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| RtError::Priority {
        priority,
        reason: format!("{e:?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_asked_nothing_done() {
        let r = apply(&ServiceRt::default()).unwrap();
        assert_eq!(r, RtReport::default());
    }

    #[test]
    fn missing_core_warns_or_fails_by_policy() {
        let mut rt = ServiceRt {
            core: Some(1000),
            ..ServiceRt::default()
        };
        let r = apply(&rt).unwrap();
        assert_eq!(r.pinned_core, None);
        assert!(matches!(r.warnings[0], RtError::Pin { core: 1000, .. }));
        rt.policy = RtPolicy::Require;
        assert!(matches!(apply(&rt), Err(RtError::Pin { core: 1000, .. })));
    }

    #[test]
    fn pinning_to_core_zero_works() {
        // Run in a thread so the test harness's thread keeps its affinity.
        std::thread::spawn(|| {
            let r = apply(&ServiceRt {
                core: Some(0),
                policy: RtPolicy::Require,
                ..ServiceRt::default()
            })
            .unwrap();
            assert_eq!(r.pinned_core, Some(0));
        })
        .join()
        .unwrap();
    }
}
