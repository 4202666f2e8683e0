//! A whole evaluation on every worker, against its physics floor: the time its slowest
//! worker spent inside the physics steps of its own episodes, measured in the run — the
//! least the run could take with nothing else (no policy, replay, metrics or
//! coordination). The ratio of the two is what everything but the physics costs a run
//! (1.0: nothing). Beside it, the same number of steps of a robot standing still
//! ([`physics_floor`]): what a step costs without the episodes' motion and contacts.

use crate::eval::runner::{run_eval, EvalPlan};
use crate::eval::{schedule, EvalSpec};
use crate::policy::Policy;
use crate::sim::physics::{make_physics, standing_default_pose, EngineError, PhysicsSettings};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What one evaluation cost.
#[derive(Debug, Clone, PartialEq)]
pub struct RunTiming {
    /// Episodes run.
    pub episodes: usize,
    /// Control steps over all episodes.
    pub control_steps: usize,
    /// Physics steps over all episodes (control steps × substeps).
    pub physics_steps: usize,
    /// Simulated time over all episodes, s.
    pub simulated_s: f64,
    /// Wall time of the run.
    pub wall: Duration,
    /// CPU time of this process over the run (user + system, every thread).
    pub cpu: Duration,
    /// The policy's per-step latency, p50, µs (in process: the slowest worker's `act`).
    pub act_p50_us: f64,
    /// The slowest worker's wall time inside the physics steps of its episodes: the run's
    /// floor, measured in the run on its own steps.
    pub physics_wall_slowest_worker: Duration,
    /// A hash of the records (JSON, in job order): equal between runs whose every episode
    /// is the same.
    pub records_fingerprint: u64,
}

impl RunTiming {
    /// Simulated seconds per wall second.
    pub fn real_time_factor(&self) -> f64 {
        self.simulated_s / self.wall.as_secs_f64().max(f64::MIN_POSITIVE)
    }

    /// Share of `cores` busy over the run, 0–1.
    pub fn cores_busy(&self, cores: usize) -> f64 {
        self.cpu.as_secs_f64()
            / (self.wall.as_secs_f64() * cores.max(1) as f64).max(f64::MIN_POSITIVE)
    }
}

/// CPU time of this process so far (user + system, all threads).
pub fn process_cpu_time() -> Duration {
    // SAFETY: getrusage writes the struct it is given and nothing else.
    let usage = unsafe {
        let mut u = std::mem::zeroed::<libc::rusage>();
        libc::getrusage(libc::RUSAGE_SELF, &mut u);
        u
    };
    let tv = |t: libc::timeval| Duration::new(t.tv_sec as u64, (t.tv_usec as u32) * 1000);
    tv(usage.ru_utime) + tv(usage.ru_stime)
}

/// Runs every (sequence, setting) of `spec` with `policy`, recording nothing, and times it.
pub fn time_run(spec: &EvalSpec, policy: &mut dyn Policy) -> RunTiming {
    let plan = EvalPlan::of(spec, None);
    let jobs = schedule(spec.sequences.len(), plan.spec.settings.len(), None);
    let substeps = (spec.profile.control_dt_s / spec.profile.physics_dt_s).round() as usize;
    let cpu0 = process_cpu_time();
    let t0 = Instant::now();
    let outcome = run_eval(&plan, &spec.sequences, &jobs, policy, &mut |_, _| {});
    let wall = t0.elapsed();
    let cpu = process_cpu_time().saturating_sub(cpu0);
    let control_steps: usize = outcome
        .records
        .iter()
        .map(|r| r.series.kp_err_m.len())
        .sum();
    RunTiming {
        episodes: outcome.records.len(),
        control_steps,
        physics_steps: control_steps * substeps,
        simulated_s: control_steps as f64 * spec.profile.control_dt_s,
        wall,
        cpu,
        act_p50_us: outcome.latency.p50_us,
        physics_wall_slowest_worker: outcome
            .physics_wall_by_worker
            .iter()
            .copied()
            .max()
            .unwrap_or_default(),
        records_fingerprint: fingerprint(&outcome.records),
    }
}

/// A hash of `records` as JSON, in their order.
fn fingerprint(records: &[crate::eval::EpisodeRecord]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for r in records {
        serde_json::to_string(r).unwrap_or_default().hash(&mut h);
    }
    h.finish()
}

/// CPU time (user + system) of the live processes of process group `pgid` (Linux
/// `/proc`; zero elsewhere): what a policy process started in its own group costs.
pub fn process_group_cpu_time(pgid: u32) -> Duration {
    // SAFETY: sysconf reads a constant of the system.
    let ticks_per_s = unsafe { libc::sysconf(libc::_SC_CLK_TCK) }.max(1) as f64;
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return Duration::ZERO;
    };
    let mut ticks = 0u64;
    for entry in dir.flatten() {
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        // Fields after the command name (which may hold spaces, inside parentheses):
        // state ppid pgrp … utime (14th field overall) stime (15th).
        let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
            continue;
        };
        let fields: Vec<&str> = rest.split_whitespace().collect();
        if fields.len() > 12 && fields[2].parse::<u32>() == Ok(pgid) {
            ticks +=
                fields[11].parse::<u64>().unwrap_or(0) + fields[12].parse::<u64>().unwrap_or(0);
        }
    }
    Duration::from_secs_f64(ticks as f64 / ticks_per_s)
}

/// Wall time of `physics_steps` steps of `spec`'s engine, robot and gains spread evenly
/// over `spec.workers` threads, each a robot holding its standing pose (a robot whose
/// feet touch the ground, as in the episodes).
pub fn physics_floor(spec: &EvalSpec, physics_steps: usize) -> Result<Duration, EngineError> {
    let workers = spec.workers.max(1);
    let robot = Arc::new(spec.robot.clone());
    let settings = PhysicsSettings {
        dt_s: spec.profile.physics_dt_s,
        ..Default::default()
    };
    let per_worker = physics_steps.div_ceil(workers);
    // Made before the clock starts: building a world is not a step.
    let mut worlds = (0..workers)
        .map(|_| {
            make_physics(
                &spec.engine,
                robot.clone(),
                settings.clone(),
                spec.profile.gains.clone(),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let start = standing_default_pose(&robot);
    for w in &mut worlds {
        w.reset(&start);
        w.set_targets(&start.q);
    }
    let t0 = Instant::now();
    std::thread::scope(|scope| {
        for w in &mut worlds {
            scope.spawn(move || {
                for _ in 0..per_worker {
                    w.step();
                }
            });
        }
    });
    Ok(t0.elapsed())
}
