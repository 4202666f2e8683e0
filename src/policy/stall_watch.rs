//! Says so when a policy process keeps the run waiting: in lock-step the simulator waits
//! for an answer as long as the policy's process lives, and a live process that never
//! answers (a deadlocked Python loop, a GPU that hangs) would stall `eval` without a word.
//! A watcher thread reports the wait after [`FIRST_REPORT`], then at doubling intervals.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long an answer may take before the wait is reported.
pub const FIRST_REPORT: Duration = Duration::from_secs(10);

/// How often the watcher looks.
const LOOK_EVERY: Duration = Duration::from_millis(250);

struct Shared {
    /// When the current wait began, in ms since `base` plus one; 0 while not waiting.
    waiting_since_ms: AtomicU64,
    stop: AtomicBool,
    base: Instant,
}

/// The watcher of one remote policy's waits.
pub struct StallWatch {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl StallWatch {
    /// Watches the waits of the policy `name` (logged with `log::warn!`).
    pub fn new(name: String) -> Self {
        let shared = Arc::new(Shared {
            waiting_since_ms: AtomicU64::new(0),
            stop: AtomicBool::new(false),
            base: Instant::now(),
        });
        let watched = shared.clone();
        let thread = std::thread::Builder::new()
            .name("policy-stall-watch".into())
            .spawn(move || watch(&watched, &name))
            .ok();
        Self { shared, thread }
    }

    /// A step's wait for the policy begins.
    pub fn waiting(&self) {
        let ms = self.shared.base.elapsed().as_millis() as u64 + 1;
        self.shared.waiting_since_ms.store(ms, Ordering::Relaxed);
    }

    /// The wait ended (answered, missed, or the policy gone).
    pub fn answered(&self) {
        self.shared.waiting_since_ms.store(0, Ordering::Relaxed);
    }
}

fn watch(shared: &Shared, name: &str) {
    let mut reported_for: Option<(u64, Duration)> = None;
    while !shared.stop.load(Ordering::Relaxed) {
        std::thread::park_timeout(LOOK_EVERY);
        let since = shared.waiting_since_ms.load(Ordering::Relaxed);
        if since == 0 {
            reported_for = None;
            continue;
        }
        let waited = shared
            .base
            .elapsed()
            .saturating_sub(Duration::from_millis(since - 1));
        let next = match reported_for {
            Some((wait, last)) if wait == since => last * 2,
            _ => FIRST_REPORT,
        };
        if waited >= next {
            log::warn!(
                "policy `{name}` has not answered for {:.0} s; its process is alive, and lock-step waits as long as it lives (a latency budget bounds each step; stop the policy or this run to end it)",
                waited.as_secs_f64()
            );
            reported_for = Some((since, next));
        }
    }
}

impl Drop for StallWatch {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            thread.thread().unpark();
            let _ = thread.join();
        }
    }
}
