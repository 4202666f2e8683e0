//! Bad and hostile input: names that would become paths outside the
//! output directory, manifests that lie about robot or version or are not grouped, runs
//! that would be silently replaced or double-counted, imports that would half-write.
//! Each is a clear error (or a correct result), never a panic, never a file outside the
//! directory it was meant for.

use std::path::Path;
use std::process::Command;
use std::time::Duration;
use thorarena::sim::motion::{DatasetWriter, MANIFEST};

mod common;
use common::{failure, g1, run_bin as thorarena, sample_sequence};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

/// A two-sequence dataset in `dir` whose manifest is then edited by `edit`.
fn dataset_with_manifest(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let robot = g1();
    let mut w = DatasetWriter::create(dir, &robot).unwrap();
    for (task, id) in [("clean_table", "a"), ("liftup_water", "b")] {
        let mut s = sample_sequence(&robot, id);
        s.task = task.into();
        w.add(&s).unwrap();
    }
    w.finish().unwrap();
    let path = dir.join(MANIFEST);
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut m);
    std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap()).unwrap();
}

#[test]
fn hostile_ids_in_a_manifest_are_refused_before_any_path_is_made() {
    let tmp = tempfile::tempdir().unwrap();
    for (field, value) in [
        ("task", "../../evil"),
        ("sequence_id", "/etc/passwd"),
        ("sequence_id", ".."),
        ("task", ""),
    ] {
        let ds = tmp.path().join("ds");
        let _ = std::fs::remove_dir_all(&ds);
        dataset_with_manifest(&ds, |m| m["sequences"][0][field] = value.into());
        let e = failure(&thorarena(
            tmp.path(),
            &["eval", "--dataset", ds.to_str().unwrap(), "--out", "run"],
        ));
        assert!(e.contains(&format!("sequences[0].{field}")), "{e}");
        assert!(e.contains("cannot become a file name"), "{e}");
        assert!(!tmp.path().join("run").join("traces").exists());
    }
    assert!(!tmp.path().parent().unwrap().join("evil").exists());
}

#[test]
fn a_hostile_task_name_on_import_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("walk.csv");
    std::fs::write(&csv, "frame,x\n").unwrap();
    for task in ["../../x", "/tmp/x", "a b", ""] {
        let e = failure(&thorarena(
            tmp.path(),
            &[
                "data",
                "import",
                "--format",
                "lafan-csv",
                csv.to_str().unwrap(),
                "--out",
                "ds",
                "--task",
                task,
            ],
        ));
        assert!(e.contains("--task"), "{task}: {e}");
        assert!(!tmp.path().join("ds").exists(), "{task}: nothing written");
    }
}

#[test]
fn a_manifest_for_another_robot_or_schema_is_refused_plainly() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("h1");
    dataset_with_manifest(&ds, |m| m["robot"] = "h1".into());
    let e = failure(&thorarena(
        tmp.path(),
        &["eval", "--dataset", ds.to_str().unwrap(), "--out", "run"],
    ));
    assert!(
        e.contains("robot") && e.contains("`h1`") && e.contains("g1_29dof"),
        "{e}"
    );

    let ds = tmp.path().join("future");
    dataset_with_manifest(&ds, |m| m["schema_version"] = (1u64 << 33 | 1).into());
    let e = failure(&thorarena(
        tmp.path(),
        &["data", "info", ds.to_str().unwrap()],
    ));
    assert!(e.contains("schema version 8589934593"), "{e}");
}

#[test]
fn runs_are_never_silently_replaced_double_counted_or_empty() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    dataset_with_manifest(&ds, |_| {});
    let d = ds.to_str().unwrap();
    let eval = |extra: &[&str]| {
        let mut a = vec!["eval", "--dataset", d, "--policy", "hold", "--out", "run"];
        a.extend(extra);
        thorarena(tmp.path(), &a)
    };
    assert!(eval(&[]).status.success());
    let before = std::fs::read(tmp.path().join("run/episodes.jsonl")).unwrap();
    let e = failure(&eval(&[]));
    assert!(
        e.contains("already holds a run") && e.contains("--overwrite"),
        "{e}"
    );
    assert_eq!(
        std::fs::read(tmp.path().join("run/episodes.jsonl")).unwrap(),
        before
    );
    assert!(eval(&["--resume"]).status.success());
    assert!(eval(&["--overwrite"]).status.success());
    assert_eq!(
        std::fs::read(tmp.path().join("run/episodes.jsonl"))
            .unwrap()
            .len(),
        before.len()
    );

    let e = failure(&eval(&["--settings", "force,force", "--overwrite"]));
    assert!(e.contains("`force` twice"), "{e}");
    // Two spellings of one load: each episode would run twice under two names.
    for pair in ["1,force", "push:0,no-force", "push:50@-90,push:50@270"] {
        let e = failure(&eval(&["--settings", pair, "--overwrite"]));
        assert!(e.contains("the same load on the robot"), "{pair}: {e}");
    }
    for absurd in ["1e308", "push:1e300", "50", "push:-5000"] {
        let e = failure(&eval(&["--settings", absurd, "--overwrite"]));
        assert!(
            e.contains("within ±10") && e.contains("≤ 1000"),
            "{absurd}: {e}"
        );
    }

    let empty = tmp.path().join("empty");
    dataset_with_manifest(&empty, |m| m["sequences"] = serde_json::json!([]));
    let e = failure(&thorarena(
        tmp.path(),
        &[
            "eval",
            "--dataset",
            empty.to_str().unwrap(),
            "--out",
            "empty-run",
        ],
    ));
    assert!(e.contains("holds no sequence"), "{e}");
    assert!(!tmp.path().join("empty-run/tables.md").exists());
}

#[test]
fn no_command_writes_over_a_run_or_its_own_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    dataset_with_manifest(&ds, |_| {});
    let d = ds.to_str().unwrap();
    for (out, policy) in [("a", "hold"), ("b", "replay")] {
        let o = thorarena(
            tmp.path(),
            &["eval", "--dataset", d, "--policy", policy, "--out", out],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let run_files = |run: &str| -> Vec<Vec<u8>> {
        ["run.json", "episodes.jsonl", "summary.json", "tables.md"]
            .iter()
            .map(|f| std::fs::read(tmp.path().join(run).join(f)).unwrap())
            .collect()
    };
    let (a, b) = (run_files("a"), run_files("b"));
    let unchanged = || {
        assert_eq!(run_files("a"), a, "run a changed");
        assert_eq!(run_files("b"), b, "run b changed");
    };

    // `merge --out` onto another run: refused without --overwrite.
    let e = failure(&thorarena(tmp.path(), &["merge", "a", "--out", "b"]));
    assert!(
        e.contains("already holds a run") && e.contains("--overwrite"),
        "{e}"
    );
    unchanged();
    // ... onto its own input: refused even with it.
    let e = failure(&thorarena(
        tmp.path(),
        &["merge", "a", "--out", "a", "--overwrite"],
    ));
    assert!(e.contains("input"), "{e}");
    unchanged();
    // `report` over a run's own data, or over another run's files.
    for (args, why) in [
        (
            &["report", "a", "--out", "a/episodes.jsonl", "--overwrite"][..],
            "input",
        ),
        (
            &["report", "a", "--out", "a/tables.html", "--overwrite"][..],
            "input",
        ),
        (
            &["report", "a", "--out", "b/tables.html"][..],
            "--overwrite",
        ),
    ] {
        let e = failure(&thorarena(tmp.path(), args));
        assert!(e.contains(why), "{args:?}: {e}");
        unchanged();
    }
    // `data export` into the dataset it exports, or into a run.
    let e = failure(&thorarena(
        tmp.path(),
        &["data", "export", d, "--out", d, "--overwrite"],
    ));
    assert!(e.contains("input"), "{e}");
    let e = failure(&thorarena(tmp.path(), &["data", "export", d, "--out", "a"]));
    assert!(e.contains("already holds a run"), "{e}");
    unchanged();
    // What stays allowed: a new report next to a run, replaced on the next call.
    for _ in 0..2 {
        let o = thorarena(tmp.path(), &["report", "a", "b", "--out", "cmp.html"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
}

#[test]
fn an_edited_or_planted_data_cache_is_never_used() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    dataset_with_manifest(&ds, |_| {});
    let cache = tmp.path().join("cache");
    let eval = |out: &str| {
        let o = Command::new(BIN)
            .current_dir(tmp.path())
            .env("XDG_CACHE_HOME", &cache)
            .env_remove("THORARENA_DATA_DIR")
            .args([
                "eval",
                "--dataset",
                ds.to_str().unwrap(),
                "--policy",
                "balance",
            ])
            .args(["--settings", "force", "--out", out])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(tmp.path().join(out).join("summary.json")).unwrap(),
        )
        .unwrap();
        // The scores (the latency of the in-process policy varies run to run).
        let scores = summary["settings"].clone();
        (scores, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (honest, _) = eval("honest");
    // The knee gain in the cached default profile, 600 → 60 (FATS 95 → 65 on balance).
    let copies: Vec<_> = std::fs::read_dir(cache.join("thorarena"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("data-")
        })
        .collect();
    assert_eq!(copies.len(), 1, "{copies:?}");
    let profile = copies[0].join("profiles/default.toml");
    let text = std::fs::read_to_string(&profile).unwrap();
    assert!(text.contains("knee = 600.0"), "{text}");
    std::fs::write(&profile, text.replace("knee = 600.0", "knee = 60.0")).unwrap();
    let (after_edit, stderr) = eval("after-edit");
    assert_eq!(after_edit, honest, "the edited cache was used");
    assert!(
        stderr.contains("differs from this binary's data"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(&profile).unwrap(), text);
}

#[test]
fn a_failed_record_write_is_reported_naming_the_file_once() {
    // A file-size limit (SIGXFSZ ignored, so the write fails with EFBIG) stands in for a
    // full disk: run.json (2 KB) fits under 64 KiB, the appended record log (some 120 KB
    // per episode here: `hold` stands through the sample's clips without force) does not. A link to /dev/full no longer can: output files are
    // never opened through a link (`tests/planted_links.rs`). Whole files' failure mid-way
    // is `tests/one_writer.rs`'.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let cmd = format!(
        "trap '' XFSZ; ulimit -f 64; exec {} eval --dataset {SAMPLE} --policy hold --settings no-force --shard 0/6 --out {}",
        env!("CARGO_BIN_EXE_thorarena"),
        out.display()
    );
    let o = Command::new("bash").args(["-c", &cmd]).output().unwrap();
    let e = failure(&o);
    assert!(
        e.contains("episodes.jsonl") && e.contains("File too large"),
        "{e}"
    );
    assert_eq!(e.matches("File too large").count(), 1, "{e}");
}

#[test]
fn data_info_lists_each_task_once_however_the_manifest_is_ordered() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    let robot = g1();
    let mut w = DatasetWriter::create(&ds, &robot).unwrap();
    for (task, id) in [
        ("clean_table", "a"),
        ("liftup_water", "b"),
        ("clean_table", "c"),
    ] {
        let mut s = sample_sequence(&robot, id);
        s.task = task.into();
        w.add(&s).unwrap();
    }
    w.finish().unwrap();
    // Ungroup the manifest: a, b, c → clean_table, liftup_water, clean_table.
    let path = ds.join(MANIFEST);
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let seqs = m["sequences"].as_array_mut().unwrap();
    seqs.sort_by_key(|e| e["sequence_id"].as_str().unwrap().to_string());
    std::fs::write(&path, serde_json::to_string(&m).unwrap()).unwrap();
    let o = thorarena(tmp.path(), &["data", "info", ds.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let rows = |task: &str| text.lines().filter(|l| l.starts_with(task)).count();
    assert_eq!(rows("clean_table"), 1, "{text}");
    assert_eq!(rows("liftup_water"), 1, "{text}");
}

#[test]
fn an_import_with_a_taken_or_repeated_sequence_id_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    // Two LAFAN-style files with the same name in different folders.
    let lafan = |dir: &Path| {
        let p = dir.join("walk.csv");
        let q0 = g1().default_pose();
        let text: String = (0..45)
            .map(|k| {
                let mut row = vec![0.02 * k as f64, 0.0, 0.78, 0.0, 0.0, 0.0, 1.0];
                row.extend(&q0);
                let cells: Vec<String> = row.iter().map(|v| v.to_string()).collect();
                cells.join(",") + "\n"
            })
            .collect();
        std::fs::write(&p, text).unwrap();
        p
    };
    let (pa, pb) = (lafan(&a), lafan(&b));
    let import = |inputs: &[&Path]| {
        let mut args = vec!["data", "import", "--format", "lafan-csv"];
        args.extend(inputs.iter().map(|p| p.to_str().unwrap()));
        args.extend(["--out", "ds", "--task", "walk"]);
        thorarena(tmp.path(), &args)
    };
    let e = failure(&import(&[&pa, &pb]));
    assert!(e.contains("two inputs are named `walk`"), "{e}");
    assert!(
        !tmp.path().join("ds/walk").exists(),
        "no orphan sequence file"
    );
    let first = import(&[&pa]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let manifest = std::fs::read(tmp.path().join("ds").join(MANIFEST)).unwrap();
    let e = failure(&import(&[&pb]));
    assert!(e.contains("walk/walk is already in"), "{e}");
    assert_eq!(
        std::fs::read(tmp.path().join("ds").join(MANIFEST)).unwrap(),
        manifest
    );
}

#[test]
fn a_deeply_nested_pickle_is_an_error_not_a_stack_overflow() {
    let tmp = tempfile::tempdir().unwrap();
    // {'fps': [[[…]]]}: 10 000 nested lists in about 20 KB (protocol 2 opcodes).
    let n = 10_000;
    let mut p = vec![0x80, 2, b'}', b'X', 3, 0, 0, 0];
    p.extend(b"fps");
    p.extend(std::iter::repeat_n(b']', n));
    p.extend(std::iter::repeat_n(b'a', n - 1));
    p.extend([b's', b'.']);
    assert!(p.len() < 21_000);
    let file = tmp.path().join("deep.pkl");
    std::fs::write(&file, &p).unwrap();
    let o = thorarena(
        tmp.path(),
        &[
            "data",
            "import",
            "--format",
            "twist-pkl",
            file.to_str().unwrap(),
            "--task",
            "t",
            "--out",
            "ds",
        ],
    );
    let e = failure(&o);
    assert_eq!(o.status.code(), Some(1), "an error exit, not an abort: {e}");
    assert!(
        e.contains("deep.pkl") && e.contains("nest more than 100 levels"),
        "{e}"
    );
    assert!(!tmp.path().join("ds").exists(), "nothing written");
}

#[test]
fn absurd_durations_and_steps_are_errors_not_panics_or_endless_runs() {
    // Issue 22: `--connect-timeout 1e20` aborted eval and client ("cannot convert float
    // seconds to Duration"); `--physics-dt 1e-9` ran 2·10⁷ physics steps per control step.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let out = out.to_str().unwrap();
    for (args, expected) in [
        (
            vec![
                "eval",
                "--policy",
                "ipc:absurd-timeout",
                "--connect-timeout",
                "1e20",
                "--out",
                out,
            ],
            "1e20 s: give 0 (wait forever) to 86400 s",
        ),
        (
            vec![
                "client",
                "--session",
                "absurd-timeout",
                "--policy",
                "hold",
                "--connect-timeout",
                "1e20",
            ],
            "1e20 s: give more than 0 s, at most 86400 s",
        ),
        (
            vec![
                "eval",
                "--policy",
                "hold",
                "--dataset",
                SAMPLE,
                "--physics-dt",
                "1e-9",
                "--out",
                out,
            ],
            "20000000 physics steps per control step of 0.02 s; at most 1000",
        ),
        (
            vec![
                "eval",
                "--policy",
                "hold",
                "--envs",
                "18446744073709551615",
                "--out",
                out,
            ],
            "at most 4096 environment slots",
        ),
        (
            vec![
                "eval",
                "--policy",
                "hold",
                "--workers",
                "100000",
                "--out",
                out,
            ],
            "at most 1024 threads",
        ),
        (
            vec![
                "data",
                "synth",
                "--out",
                out,
                "--per-task",
                "18446744073709551615",
            ],
            "give 1 to 100000 sequences per task",
        ),
        (
            // A budget too long for a duration once panicked in the parser.
            vec![
                "eval",
                "--policy",
                "hold",
                "--budget",
                "100000000000000000000000000000s",
                "--out",
                out,
            ],
            "a budget is 1 us to 60 s (or none), not 1e29",
        ),
    ] {
        let started = std::time::Instant::now();
        let e = failure(&thorarena(dir.path(), &args));
        assert!(e.contains(expected), "{args:?}: {e}");
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "{args:?} took {:?}",
            started.elapsed()
        );
    }
}

/// Issue 42, probe item 7: import accepted what an evaluation never finishes or what
/// silently drops the forces — a frame rate of 1e-300 Hz (a 6e301 s motion), a force
/// offset of NaN, 100 s or 1e300 s (force logs that were all 0 N once offset), and a
/// force log covering 0.02 s of a 5 s motion. Each is refused, naming the file and what
/// is wrong, and nothing is written.
#[test]
fn import_refuses_frame_rates_and_force_alignments_that_lose_the_motion_or_its_forces() {
    let dir = tempfile::tempdir().unwrap();
    let robot = g1();
    let q0 = robot.default_pose();
    // 150 frames at 30 fps: a 5 s motion.
    let csv: String = (0..150)
        .map(|k| {
            let mut row = vec![0.002 * k as f64, 0.0, 0.78, 0.0, 0.0, 0.0, 1.0];
            row.extend(&q0);
            row.iter().map(f64::to_string).collect::<Vec<_>>().join(",") + "\n"
        })
        .collect();
    let motion = dir.path().join("motion.csv");
    std::fs::write(&motion, csv).unwrap();
    let log = |name: &str, seconds: f64| {
        let path = dir.path().join(name);
        let rows: String = std::iter::once("time,fx,fy,fz\n".to_string())
            .chain(
                (0..=((seconds * 100.0).round() as usize))
                    .map(|k| format!("{},10,0,0\n", k as f64 * 0.01)),
            )
            .collect();
        std::fs::write(&path, rows).unwrap();
        path.to_str().unwrap().to_string()
    };
    let (full_l, full_r) = (log("left.csv", 5.0), log("right.csv", 5.0));
    let (short_l, short_r) = (log("left-short.csv", 0.02), log("right-short.csv", 0.02));
    let out = dir.path().join("out");
    let import = |extra: &[&str]| {
        let mut args = vec![
            "data",
            "import",
            "--format",
            "lafan-csv",
            motion.to_str().unwrap(),
            "--task",
            "walk",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        thorarena(dir.path(), &args)
    };
    // The fixture imports as it is.
    let fine = import(&["--forces", &full_l, &full_r]);
    assert!(
        fine.status.success(),
        "{}",
        String::from_utf8_lossy(&fine.stderr)
    );
    std::fs::remove_dir_all(&out).unwrap();
    // A log covering half the motion imports, and says so (issue 52, probe item 8: it
    // said nothing, and the frames it misses replay no force).
    let (half_l, half_r) = (log("left-half.csv", 2.5), log("right-half.csv", 2.5));
    let half = import(&["--forces", &half_l, &half_r]);
    let said = String::from_utf8_lossy(&half.stderr);
    assert!(half.status.success(), "{said}");
    assert!(
        said.contains("note: the left force log covers")
            && said.contains("of the motion's 150 frames")
            && said.contains("--force-offset"),
        "{said}"
    );
    std::fs::remove_dir_all(&out).unwrap();
    for (extra, wants) in [
        (vec!["--fps", "1e-300"], vec!["fps", "1 to 1000 Hz"]),
        (
            vec!["--forces", &full_l, &full_r, "--force-offset", "NaN"],
            vec!["force offset", "not a time offset"],
        ),
        (
            vec!["--forces", &full_l, &full_r, "--force-offset", "100"],
            vec!["left force log", "covers 0 of the motion's 150 frames"],
        ),
        (
            vec!["--forces", &full_l, &full_r, "--force-offset", "1e300"],
            vec!["left force log", "covers 0 of"],
        ),
        (
            vec!["--forces", &short_l, &short_r],
            vec!["left force log", "covers 1 of the motion's 150 frames"],
        ),
    ] {
        let o = import(&extra);
        let e = failure(&o);
        assert!(e.contains("motion.csv"), "{extra:?}: {e}");
        for w in wants {
            assert!(e.contains(w), "{extra:?}: {e}");
        }
        assert!(!out.join(MANIFEST).exists(), "{extra:?} wrote a dataset");
    }
}

/// Issue 42, probe item 10: ids like `=1+2`, `@SUM` and `-2+3` (plain names, allowed as
/// ids) went unescaped into `episodes.csv` and a report's CSV, where a spreadsheet runs
/// them as formulas. Every text cell that would read as one starts with `'`.
#[test]
fn csv_cells_never_read_as_spreadsheet_formulas() {
    let tmp = tempfile::tempdir().unwrap();
    let robot = g1();
    let ds = tmp.path().join("ds");
    let mut w = DatasetWriter::create(&ds, &robot).unwrap();
    for (task, id) in [("=SUM", "=1+2"), ("=SUM", "@SUM"), ("-2+3", "-2+3")] {
        let mut seq = sample_sequence(&robot, id);
        seq.task = task.into();
        w.add(&seq).unwrap();
    }
    w.finish().unwrap();
    let d = ds.to_str().unwrap();
    let o = thorarena(
        tmp.path(),
        &["eval", "--dataset", d, "--policy", "hold", "--out", "run"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = thorarena(tmp.path(), &["report", "run", "--out", "report.html"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for file in ["run/episodes.csv", "report-fats.csv"] {
        let text = std::fs::read_to_string(tmp.path().join(file)).unwrap();
        for line in text.lines().skip(1) {
            for cell in line.split(',') {
                let cell = cell.trim_matches('"');
                assert!(
                    !cell.starts_with(['=', '@', '+']) && !cell.starts_with("-2"),
                    "{file}: a cell reads as a formula: {cell:?} in {line:?}"
                );
            }
        }
        assert!(
            text.contains("'=SUM") || text.contains("'=1+2"),
            "{file}: {text}"
        );
    }
    let rows = std::fs::read_to_string(tmp.path().join("run/episodes.csv")).unwrap();
    assert!(rows.contains("'@SUM") && rows.contains("'-2+3"), "{rows}");
}

/// Issue 42, probe item 15: commands wrote where the others refuse to — a report into a
/// run directory, a run into its own dataset, a dataset over a run, a leaderboard over
/// another command's report. Each is refused before anything is written.
#[test]
fn no_command_writes_into_a_run_a_dataset_or_another_commands_output() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("ds");
    dataset_with_manifest(&ds, |_| {});
    let d = ds.to_str().unwrap();
    let o = thorarena(
        tmp.path(),
        &["eval", "--dataset", d, "--policy", "hold", "--out", "run"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::create_dir(tmp.path().join("mine")).unwrap();
    std::fs::write(tmp.path().join("mine/report.html"), "x").unwrap();
    let leaderboard_into = |out| {
        vec![
            "leaderboard",
            "--policy",
            "hold",
            "--dataset",
            d,
            "--engines",
            "rapier",
            "--out",
            out,
        ]
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["report", "run", "--out", "run/x.html"], "run/x.html"),
        (
            vec!["report", "run", "--out", "run/x.html", "--overwrite"],
            "part of this command's input",
        ),
        (
            vec!["eval", "--dataset", d, "--policy", "hold", "--out", d],
            "holds a dataset",
        ),
        (
            vec![
                "eval",
                "--dataset",
                d,
                "--policy",
                "hold",
                "--out",
                "ds/inner",
            ],
            "this command's input",
        ),
        (
            vec![
                "dds",
                "--dataset",
                d,
                "--sequence",
                "clean_table/a",
                "--out",
                d,
            ],
            "holds a dataset",
        ),
        (
            vec!["data", "synth", "--per-task", "1", "--out", "run"],
            "holds a run",
        ),
        (leaderboard_into("mine"), "report.html no leaderboard wrote"),
        (leaderboard_into("run"), "it holds a run"),
    ];
    let before = std::fs::read(tmp.path().join("run/summary.json")).unwrap();
    for (args, wants) in cases {
        let e = failure(&thorarena(tmp.path(), &args));
        assert!(e.contains(wants), "{args:?}: {e}");
    }
    assert!(!tmp.path().join("run/x.html").exists());
    assert!(!tmp.path().join("ds/inner").exists());
    assert_eq!(
        std::fs::read(tmp.path().join("run/summary.json")).unwrap(),
        before
    );
    assert_eq!(
        std::fs::read(tmp.path().join("mine/report.html")).unwrap(),
        b"x"
    );
}
