//! The library names what a user set by its field in backticks — a field of the
//! evaluation's request as `request.envs`, `request.io.budget_s`, another option of a
//! command as `option.out` — which a request file or a library caller reads as it is; on
//! the terminal those names become the flags that set them. This table is the one place
//! the two meet, and the prefixes keep it from touching anything else in backticks (a
//! sweep spec's keys, a user's values).

/// A field as the library's messages name it, and the flag that sets it.
const FIELD_FLAGS: [(&str, &str); 44] = [
    ("request.profile", "--profile"),
    ("request.profile_mismatch_ok", "--profile-mismatch-ok"),
    ("request.unchecked", "--unchecked"),
    ("request.settings", "--settings"),
    (
        "request.replay_without_force_logs",
        "--replay-without-force-logs",
    ),
    ("request.workers", "--workers"),
    ("request.envs", "--envs"),
    ("request.pipeline_depth", "--pipeline-depth"),
    ("request.trace", "--trace"),
    ("request.engine", "--engine"),
    ("request.mjcf", "--mjcf"),
    ("request.physics_dt_s", "--physics-dt"),
    ("request.io.budget_s", "--budget"),
    ("request.io.latency_mode", "--latency-mode"),
    ("request.io.max_abs_action", "--max-abs-action"),
    (
        "request.termination.max_torso_height_error_m",
        "--max-torso-height-error",
    ),
    (
        "request.termination.max_torso_tilt_error_rad",
        "--max-torso-tilt-error",
    ),
    ("option.out", "--out"),
    ("option.overwrite", "--overwrite"),
    ("option.resume", "--resume"),
    ("option.unchecked", "--unchecked"),
    ("option.forces", "--forces"),
    ("option.task", "--task"),
    ("option.trim_glitches", "--trim-glitches"),
    (
        "option.renormalize_quaternions",
        "--renormalize-quaternions",
    ),
    ("option.force_offset", "--force-offset"),
    ("option.address", "--address"),
    ("option.interface", "--interface"),
    ("option.domain", "--domain"),
    ("option.engines", "--engines"),
    ("option.per_task", "--per-task"),
    ("option.pair_seconds", "--pair-seconds"),
    ("option.thorarena", "--thorarena"),
    ("option.array", "--array"),
    ("option.partition", "--partition"),
    ("option.time", "--time"),
    ("option.cpus_per_task", "--cpus-per-task"),
    ("option.max_parallel", "--max-parallel"),
    ("option.parallelism", "--parallelism"),
    ("option.jobs", "--jobs"),
    ("option.workers", "--workers"),
    ("option.index", "--index"),
    ("option.partial", "--partial"),
    ("option.mixed_engines", "--mixed-engines"),
];

/// `text` with every field the library names in backticks written as its flag.
pub(crate) fn as_flags(text: &str) -> String {
    let mut text = text.to_string();
    for (field, flag) in FIELD_FLAGS {
        let quoted = format!("`{field}`");
        if text.contains(&quoted) {
            text = text.replace(&quoted, flag);
        }
    }
    text
}
