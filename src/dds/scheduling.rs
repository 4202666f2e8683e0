//! Real-time scheduling for the simulated robot.
//!
//! On the G1 the motor controllers and the policy's computer are different machines: a
//! busy policy cannot delay the robot's 500 Hz loop. On one machine it can, through the
//! kernel's fair scheduler: holosoma's inference package on 2 cores (ONNX Runtime's
//! spinning thread pool, CycloneDDS's threads, Python) with one busy loop beside it made
//! 6.1 % of the physics steps more than a step late at normal priority, 0.09 % under
//! `SCHED_FIFO` (docs/deployment.md, "Your deployment code, unchanged"). So `thorarena dds` asks for
//! `SCHED_FIFO` before its DDS participant starts its threads, which inherit it, as
//! ros2_control's controller manager does for its control loop; refused (no root, no
//! `RLIMIT_RTPRIO`), it runs at normal priority and says so. The bridge's loop sleeps
//! between steps, so the priority costs other processes only the physics' own time.

use serde::{Deserialize, Serialize};

/// The scheduling policy a thread runs under.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "policy")]
pub enum Scheduling {
    /// `SCHED_FIFO` at this priority (1–99): runs before every normal thread.
    Fifo {
        /// Its real-time priority.
        priority: i32,
    },
    /// `SCHED_RR` at this priority.
    RoundRobin {
        /// Its real-time priority.
        priority: i32,
    },
    /// The kernel's fair scheduler (`SCHED_OTHER`, `SCHED_BATCH` or `SCHED_IDLE`).
    Normal,
}

impl Scheduling {
    /// The calling thread's.
    pub fn of_this_thread() -> Self {
        // SAFETY: both calls only read the calling thread's scheduling attributes into a
        // local; pid 0 is the calling thread.
        let policy = unsafe { libc::sched_getscheduler(0) };
        let mut param = libc::sched_param { sched_priority: 0 };
        let priority = match unsafe { libc::sched_getparam(0, &mut param) } {
            0 => param.sched_priority,
            _ => 0,
        };
        match policy {
            libc::SCHED_FIFO => Self::Fifo { priority },
            libc::SCHED_RR => Self::RoundRobin { priority },
            _ => Self::Normal,
        }
    }

    /// Whether it is a real-time policy.
    pub fn is_real_time(&self) -> bool {
        !matches!(self, Self::Normal)
    }
}

impl std::fmt::Display for Scheduling {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Fifo { priority } => write!(f, "SCHED_FIFO {priority}"),
            Self::RoundRobin { priority } => write!(f, "SCHED_RR {priority}"),
            Self::Normal => f.write_str("normal priority"),
        }
    }
}

/// Why the calling thread could not be given a real-time priority.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SchedulingError {
    /// The priority is outside `SCHED_FIFO`'s range.
    #[error("real-time priority {priority} is outside SCHED_FIFO's {min}..={max}")]
    OutOfRange {
        /// What was asked.
        priority: i32,
        /// The lowest the kernel takes.
        min: i32,
        /// The highest the kernel takes.
        max: i32,
    },
    /// The kernel refused it.
    #[error("the kernel refused SCHED_FIFO {priority} ({reason}); a non-root user needs RLIMIT_RTPRIO ≥ {priority} (`ulimit -r`), a container CAP_SYS_NICE")]
    Refused {
        /// What was asked.
        priority: i32,
        /// The kernel's reason.
        reason: String,
    },
}

/// Puts the calling thread under `SCHED_FIFO` at `priority`; threads it starts later
/// inherit it.
pub fn enter_fifo(priority: i32) -> Result<Scheduling, SchedulingError> {
    // SAFETY: plain queries of constants of the kernel.
    let (min, max) = unsafe {
        (
            libc::sched_get_priority_min(libc::SCHED_FIFO),
            libc::sched_get_priority_max(libc::SCHED_FIFO),
        )
    };
    if !(min..=max).contains(&priority) {
        return Err(SchedulingError::OutOfRange { priority, min, max });
    }
    let param = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: `param` is a valid sched_param for the call's duration; pid 0 is the
    // calling thread.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } != 0 {
        return Err(SchedulingError::Refused {
            priority,
            reason: std::io::Error::last_os_error().to_string(),
        });
    }
    Ok(Scheduling::of_this_thread())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_priority_outside_the_range_is_refused_and_nothing_changes() {
        let before = Scheduling::of_this_thread();
        for priority in [0, 100, -3] {
            assert!(matches!(
                enter_fifo(priority),
                Err(SchedulingError::OutOfRange { .. })
            ));
        }
        assert_eq!(Scheduling::of_this_thread(), before);
    }

    #[test]
    fn a_thread_given_fifo_reports_it_or_says_why_not() {
        // On a thread of its own: the test harness's threads keep their scheduling.
        let (result, now) = std::thread::spawn(|| (enter_fifo(1), Scheduling::of_this_thread()))
            .join()
            .unwrap();
        match result {
            Ok(got) => {
                assert_eq!(got, Scheduling::Fifo { priority: 1 });
                assert_eq!(now, got);
                assert!(got.is_real_time());
                assert_eq!(got.to_string(), "SCHED_FIFO 1");
            }
            Err(e) => {
                assert!(matches!(e, SchedulingError::Refused { .. }), "{e}");
                assert_eq!(now, Scheduling::Normal);
            }
        }
    }
}
