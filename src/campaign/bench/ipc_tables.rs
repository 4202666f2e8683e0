//! The tables of `thorarena bench ipc` as text: each table's heading, its Markdown rows and
//! the lines under it. The documentation's tables and the tests that read them parse this
//! text, so the column order lives here once, next to nothing else.

use super::ipc_clients::{AdapterRow, Builder, IpcClients};
use crate::eval::LatencySummary;
use thorarena_ipc::Layout;

/// The echo table's heading: what is timed, then the Markdown header and separator.
pub(super) fn echo_heading(c: &IpcClients) -> [String; 3] {
    [
        format!(
            "round trip, observation published → actions received, {} timed steps after {} warm-up; spin {} µs then block; µs",
            c.steps, c.warmup, c.spin_us
        ),
        "| client | envs | batch KB | p50 | p90 | p99 | p99.9 | max | socket p50 (blocking / spin) | socket p99.9 (blocking / spin) | socket/shm p50 (blocking / spin) |".into(),
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|".into(),
    ]
}

/// Echo client `client`'s round trips over shared memory with `layout` (`shm`), beside
/// the socket moving the same bytes with blocking reads and with the same spin.
pub(super) fn echo_row(
    client: &str,
    layout: Layout,
    shm: &LatencySummary,
    blocking: &LatencySummary,
    spinning: &LatencySummary,
) -> String {
    format!(
        "| {client} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} / {:.1} | {:.1} / {:.1} | {:.1}× / {:.1}× |",
        layout.n_envs,
        (layout.obs_bytes() + layout.action_bytes()) as f64 / 1024.0,
        shm.p50_us,
        shm.p90_us,
        shm.p99_us,
        shm.p999_us,
        shm.max_us,
        blocking.p50_us,
        spinning.p50_us,
        blocking.p999_us,
        spinning.p999_us,
        blocking.p50_us / shm.p50_us,
        spinning.p50_us / shm.p50_us
    )
}

/// Under the echo table: what the figures are held against.
pub(super) const ECHO_GOALS: &str = "goals (2-core machine): Rust p50 ≤ 10 µs and p99.9 ≤ 100 µs at 1 environment; Python p50 ≤ 30 µs; ≥ 5× faster than the socket at 64 environments";

/// The adapter table's heading (after an empty line: it follows the echo table).
pub(super) fn adapter_heading(c: &IpcClients) -> [String; 3] {
    [
        format!(
            "\nPython TWIST2 adapter (ONNX Runtime, 1 thread), standing observations: {} timed steps after {} warm-up; spin {} µs then block; the network call timed inside the adapter over the same steps; µs",
            c.adapter_steps, c.warmup, c.spin_us
        ),
        "| envs | observation built by | round trip p50 | p90 | p99 | simulator's build p50 | prepared while waiting p50 | network p50 | network p90 | overhead p50 | overhead p90 | answers noticed polling % |".into(),
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|".into(),
    ]
}

/// The adapter at `envs` environments with its observation built by `built_by`.
pub(super) fn adapter_row(envs: usize, built_by: Builder, row: &AdapterRow) -> String {
    let (timing, net) = (&row.timing, &row.network);
    let (rt, build) = (&timing.round_trip, &timing.input_build);
    let noticed = timing.noticed;
    let polling = (noticed.spinning + noticed.in_window) as f64;
    format!(
        "| {envs} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
        built_by.label(),
        rt.p50_us,
        rt.p90_us,
        rt.p99_us,
        build.p50_us,
        timing.input_prepare.p50_us,
        net.p50,
        net.p90,
        row.overhead_at(0.5),
        row.overhead_at(0.9),
        100.0 * polling / noticed.total().max(1) as f64
    )
}

/// Under the adapter table: what its two derived columns mean.
pub(super) const ADAPTER_NOTES: [&str; 2] = [
    "overhead: per step, round trip + simulator's build − that step's network call; goal ≤ 50 µs at 1 and at 64 environments (the history part of the input is prepared while the policy computes, inside the round trip)",
    "answers noticed polling: by the simulator's first spin or in the window where the answer was due; the rest cost a kernel wake-up (WaitPolicy::wake_early)",
];
