//! Issue 22 for sweeps, "trust nothing that crosses a boundary": a policy that dies
//! mid-run; task runs, plan entries and task records that were replaced, edited or
//! misplaced; policy output that is huge or holds terminal escapes; a dataset changed
//! before `collect`; spec values that are absurd, equivalent or negative; files that
//! cannot be written. Each is an end-to-end test that failed on the code before its fix.
//! (Hostile paths in the Slurm script and the Kubernetes manifest: `sweep_cluster_hostile.rs`.)

mod sweep_support;

use std::path::Path;
use std::process::Command;
use sweep_support::*;

// ---------------------------------------------------------------- C: a dead policy

#[test]
fn a_policy_that_dies_mid_run_fails_its_task_and_collect_will_not_score_it() {
    // Two episodes, both in flight when the policy dies: `eval` itself may end well.
    let tmp = tempfile::tempdir().unwrap();
    let ds = small_dataset(tmp.path(), 2);
    let spec_path = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{}\"]\nsettings = [\"no-force\"]\n[[policy]]\nname = \"dies\"\ncommand = \"{{thorarena}} client --session {{session}} --policy hold --die-after-steps 100\"\nconnect_timeout_s = 30\n",
            ds.display()
        ),
    );
    let dir = tmp.path().join("sweep");
    plan(&spec_path, &dir);
    let o = thorarena(&["sweep", "run", s(&dir), "--jobs", "1"]);
    let e = err(&o);
    // eval exits non-zero when episodes ended `policy_failed` (it once exited 0: the case
    // this is about, which the task's own check of the records also catches); on a loaded
    // machine it may still be writing when the task stops it 3 s after the policy died.
    // Either way the task failed.
    assert!(
        e.contains("thorarena eval failed")
            || e.contains("ended policy_failed")
            || e.contains("the policy command exited"),
        "{e}"
    );
    assert!(!dir.join("tasks/000000/done.json").exists());
    let status = out(&ok(thorarena(&["sweep", "status", s(&dir)])));
    assert!(status.contains("0 done, 1 failed"), "{status}");
    assert!(status.contains("not done (--array): 0"), "{status}");
    let e = err(&thorarena(&["sweep", "collect", s(&dir)]));
    assert!(e.contains("unfinished"), "{e}");
    ok(thorarena(&["sweep", "collect", s(&dir), "--partial"]));
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let row = csv.lines().nth(1).unwrap();
    assert!(row.contains(",false,"), "the cell is marked partial: {csv}");
}

/// Rewrites the first record of `episodes` (an `episodes.jsonl`) as a dead policy's
/// cut it short: termination `policy_failed`.
fn mark_first_policy_failed(episodes: &Path) {
    let text = std::fs::read_to_string(episodes).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut r: serde_json::Value = serde_json::from_str(&lines[0]).unwrap();
    r["termination"] = serde_json::json!("policy_failed");
    lines[0] = serde_json::to_string(&r).unwrap();
    std::fs::write(episodes, lines.join("\n") + "\n").unwrap();
}

#[test]
fn a_done_task_whose_run_no_longer_counts_is_not_done_and_runs_again() {
    // done.json was true when it was written (or written by a ThorArena that trusted the
    // count); afterwards task 1's run lost an episode to a "dead policy" and task 2's run
    // was replaced by task 3's (another shard).
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sweep");
    plan(&four_tasks(tmp.path()), &dir);
    ok(thorarena(&["sweep", "run", s(&dir), "--jobs", "2"]));
    let episodes = dir.join("tasks/000001/run/episodes.jsonl");
    mark_first_policy_failed(&episodes);
    let e = err(&thorarena(&["sweep", "collect", s(&dir)]));
    assert!(e.contains("policy_failed") && e.contains("task 1"), "{e}");
    ok(thorarena(&["sweep", "collect", s(&dir), "--partial"]));
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[1].contains(",false,"), "{csv}");
    assert!(rows[2].contains(",true,"), "{csv}");
    let (two, three) = (dir.join("tasks/000002/run"), dir.join("tasks/000003/run"));
    std::fs::remove_dir_all(&two).unwrap();
    copy_dir(&three, &two);
    assert!(dir.join("tasks/000001/done.json").exists());

    let status = out(&ok(thorarena(&["sweep", "status", s(&dir)])));
    assert!(
        status.contains("2 done, 0 failed") && status.contains("2 marked done whose run"),
        "{status}"
    );
    assert!(
        status.contains("not counted: task 1") && status.contains("policy_failed"),
        "{status}"
    );
    assert!(
        status.contains("not counted: task 2") && status.contains("not task 2's run"),
        "{status}"
    );
    assert!(status.contains("not done (--array): 1-2"), "{status}");

    // `sweep run` no longer skips them: task 1 runs its missing episode, task 2 is refused.
    let e = err(&thorarena(&["sweep", "run", s(&dir), "--jobs", "2"]));
    assert!(
        e.contains("not task 2's run") && e.contains("remove"),
        "{e}"
    );
    let status = out(&ok(thorarena(&["sweep", "status", s(&dir)])));
    assert!(status.contains("3 done, 1 failed"), "{status}");
    assert!(!status.contains("not counted"), "{status}");
    assert!(status.contains("not done (--array): 2"), "{status}");
    let rerun = std::fs::read_to_string(&episodes).unwrap();
    assert!(!rerun.contains("policy_failed"), "{rerun}");

    // Removing the foreign run, as the message says, lets the sweep finish.
    std::fs::remove_dir_all(&two).unwrap();
    ok(thorarena(&["sweep", "run", s(&dir), "--jobs", "2"]));
    ok(thorarena(&["sweep", "collect", s(&dir)]));
}

// ---------------------------------------------------------------- D: runs and plan entries

#[test]
fn collect_refuses_a_task_run_that_is_not_its_cells() {
    let tmp = tempfile::tempdir().unwrap();
    let spec_path = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\n[[policy]]\npolicy = \"hold\"\n[[policy]]\npolicy = \"balance\"\n"
        ),
    );
    let dir = tmp.path().join("sweep");
    plan(&spec_path, &dir);
    ok(thorarena(&["sweep", "run", s(&dir), "--jobs", "2"]));
    ok(thorarena(&["sweep", "collect", s(&dir)]));
    // Task 0 (hold) now holds task 1's run (balance).
    let (a, b) = (dir.join("tasks/000000/run"), dir.join("tasks/000001/run"));
    std::fs::remove_dir_all(&a).unwrap();
    copy_dir(&b, &a);
    let e = err(&thorarena(&["sweep", "collect", s(&dir)]));
    assert!(
        e.contains("tasks/000000/run") && e.contains("policy") && e.contains("balance"),
        "{e}"
    );
}

/// Loads plan.json as JSON, lets `edit` change it, writes it back.
fn edit_plan(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join("plan.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
}

/// Issue 42: a policy command edited in `plan.json` was executed (the plan was only
/// checked for consistency, and a command is consistent with anything). The plan is
/// sealed: an edit is refused before any of it runs.
#[test]
fn an_edited_policy_command_in_plan_json_is_never_run() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\nshards = 1\n[[policy]]\nname = \"proc\"\ncommand = \"{{thorarena}} client --session {{session}} --policy hold\"\n"
        ),
    );
    let dir = tmp.path().join("sweep");
    plan(&spec, &dir);
    let marker = tmp.path().join("MARKER");
    edit_plan(&dir, |v| {
        // A launched policy is planned as its command's table (plan format 5).
        let command = v["cells"][0]["policy"]["policy"]["command"]
            .as_str()
            .unwrap()
            .to_string();
        let edited = serde_json::json!(format!("touch {}; {command}", marker.display()));
        v["cells"][0]["policy"]["policy"]["command"] = edited.clone();
        // The task's request too: an edit consistent with itself, which only the seal
        // can tell from the plan as planned.
        v["tasks"][0]["request"]["policy"]["command"] = edited;
    });
    for args in [vec!["task", "--index", "0"], vec!["run"], vec!["status"]] {
        let mut full = vec!["sweep", args[0], s(&dir)];
        full.extend(&args[1..]);
        let e = err(&thorarena(&full));
        assert!(
            e.contains("plan.json") && e.contains("seal"),
            "{args:?}: {e}"
        );
    }
    assert!(!marker.exists(), "the edited command ran");
}

#[test]
fn a_tampered_plan_is_an_error_naming_plan_json_never_a_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = four_tasks(tmp.path());
    let pristine = tmp.path().join("pristine");
    plan(&spec, &pristine);
    ok(thorarena(&["sweep", "task", s(&pristine), "--index", "0"]));
    type Edit = Box<dyn Fn(&mut serde_json::Value)>;
    let cases: Vec<(&str, Edit)> = vec![
        (
            "another policy in a task's request",
            Box::new(|v| {
                let policy = &mut v["tasks"][1]["request"]["policy"];
                assert_eq!(policy, "hold", "the edit must change something");
                *policy = serde_json::json!("balance");
            }),
        ),
        (
            "duplicate task index",
            Box::new(|v| {
                let t0 = v["tasks"][0].clone();
                v["tasks"][1] = t0;
            }),
        ),
        (
            "cell out of range",
            Box::new(|v| v["tasks"][3]["cell"] = serde_json::json!(99)),
        ),
        ("no tasks", Box::new(|v| v["tasks"] = serde_json::json!([]))),
        ("no cells", Box::new(|v| v["cells"] = serde_json::json!([]))),
        (
            "shard out of range",
            Box::new(|v| v["tasks"][1]["shard"] = serde_json::json!([5, 2])),
        ),
    ];
    for (what, edit) in cases {
        let dir = tmp.path().join(what.replace(' ', "-"));
        copy_dir(&pristine, &dir);
        edit_plan(&dir, edit);
        for args in [
            vec!["status"],
            vec!["collect", "--partial"],
            vec!["task", "--index", "1"],
            vec!["run"],
            vec!["slurm"],
        ] {
            let mut full = vec!["sweep", args[0], s(&dir)];
            full.extend(&args[1..]);
            let e = err(&thorarena(&full));
            assert!(e.contains("plan.json"), "{what}, {args:?}: {e}");
        }
    }
}

// ---------------------------------------------------------------- E: task records

#[test]
fn a_task_record_counts_for_the_directory_it_lies_in() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("sweep");
    plan(&four_tasks(tmp.path()), &dir);
    let t0 = dir.join("tasks/000000");
    std::fs::create_dir_all(&t0).unwrap();
    for task in [1, 99999] {
        std::fs::write(
            t0.join("failed.json"),
            format!("{{\"task\": {task}, \"reason\": \"x\", \"log_tail\": []}}"),
        )
        .unwrap();
        let o = thorarena(&["sweep", "status", s(&dir)]);
        if o.status.success() {
            // Location decides: task 0 is the failed one.
            let status = out(&o);
            assert!(
                status.contains("failed: task 0") && status.contains("not done (--array): 0-3"),
                "{status}"
            );
        } else {
            let e = err(&o);
            assert!(e.contains("tasks/000000/failed.json"), "{e}");
        }
    }
}

#[test]
fn policy_output_in_task_records_is_bounded_and_cannot_drive_the_terminal() {
    let tmp = tempfile::tempdir().unwrap();
    let body = r#"
datasets = ["SAMPLE"]
settings = ["no-force"]
[[policy]]
name = "huge"
command = '''echo {session} >/dev/null; head -c 30000000 /dev/zero | tr '\0' a; echo; exit 3'''
connect_timeout_s = 20
[[policy]]
name = "escapes"
command = '''echo {session} >/dev/null; printf '\033]0;pwned\007\033[2J\033[31mred\n' >&2; exit 3'''
connect_timeout_s = 20
"#;
    let spec_path = spec(tmp.path(), &body.replace("SAMPLE", SAMPLE));
    let dir = tmp.path().join("sweep");
    plan(&spec_path, &dir);
    let o = thorarena(&["sweep", "run", s(&dir), "--jobs", "2"]);
    let e = err(&o);
    assert!(!e.contains('\u{1b}'), "raw escapes in sweep run's output");
    let failed = dir.join("tasks/000000/failed.json");
    let size = std::fs::metadata(&failed).unwrap().len();
    assert!(size < 20_000, "{}: {size} bytes", failed.display());
    let o = ok(thorarena(&["sweep", "status", s(&dir)]));
    let status = out(&o);
    assert!(status.contains("2 failed"), "{status}");
    assert!(
        !status.contains('\u{1b}') && !status.contains('\u{7}'),
        "{status:?}"
    );
    assert!(
        status.contains("pwned"),
        "the text itself is kept: {status}"
    );
    assert!(status.len() < 40_000, "{} bytes of status", status.len());
}

// ---------------------------------------------------------------- F: the dataset

#[test]
fn collect_refuses_a_dataset_changed_since_the_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = tmp.path().join("dataset");
    copy_dir(Path::new(SAMPLE), &ds);
    let spec_path = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{}\"]\nsettings = [\"no-force\"]\n[[policy]]\npolicy = \"hold\"\n",
            ds.display()
        ),
    );
    let dir = tmp.path().join("sweep");
    plan(&spec_path, &dir);
    ok(thorarena(&["sweep", "run", s(&dir)]));
    let manifest = ds.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest).unwrap()).unwrap();
    m["sequences"].as_array_mut().unwrap().pop();
    std::fs::write(&manifest, serde_json::to_string(&m).unwrap()).unwrap();
    let e = err(&thorarena(&["sweep", "collect", s(&dir)]));
    assert!(e.contains("changed") && e.contains(s(&ds)), "{e}");
    assert!(!dir.join("results.csv").exists());
    // Issue 42: `status` said every task done where `collect` refused them all.
    let status = out(&ok(thorarena(&["sweep", "status", s(&dir)])));
    assert!(
        status.contains("changed since the sweep was planned") && status.contains(" 0 done"),
        "{status}"
    );
}

// ---------------------------------------------------------------- G, H, I: spec values

fn plan_error(tmp: &Path, body: &str) -> String {
    let p = spec(tmp, body);
    let out = tmp.join("never");
    let e = err(&thorarena(&["sweep", "plan", s(&p), "--out", s(&out)]));
    assert!(!out.exists(), "nothing may be written: {e}");
    e
}

#[test]
fn shards_beyond_the_episodes_are_refused_naming_the_maximum() {
    let tmp = tempfile::tempdir().unwrap();
    for shards in ["13", "1000000000"] {
        let e = plan_error(
            tmp.path(),
            &format!(
                "datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\nshards = {shards}\n[[policy]]\npolicy = \"hold\"\n"
            ),
        );
        assert!(e.contains("shards") && e.contains("at most 12"), "{e}");
    }
}

#[test]
fn equivalent_axis_values_are_refused_naming_both_spellings() {
    let tmp = tempfile::tempdir().unwrap();
    let dotted = SAMPLE.replace("/data/sample", "/data/./sample");
    let cases = [
        (
            format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"force\", \"1\"]\n[[policy]]\npolicy = \"hold\"\n"),
            vec!["`force`", "`1`"],
        ),
        (
            format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"0.5\", \"push:0\", \"0.50\"]\n[[policy]]\npolicy = \"hold\"\n"),
            vec!["`0.5`", "`0.50`"],
        ),
        (
            format!("datasets = [\"{SAMPLE}\", \"{dotted}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"hold\"\n"),
            vec![SAMPLE, dotted.as_str()],
        ),
        (
            format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"hold\"\n[[engine]]\nengine = \"rapier\"\n[[engine]]\nengine = \"rapier\"\n"),
            vec!["[[engine]] #1", "[[engine]] #2"],
        ),
    ];
    for (body, needles) in cases {
        let e = plan_error(tmp.path(), &body);
        for n in needles {
            assert!(e.contains(n), "`{n}` not in: {e}");
        }
    }
}

#[test]
fn negative_spec_values_reach_eval_as_values_not_flags() {
    let tmp = tempfile::tempdir().unwrap();
    // A negative replay coefficient is a valid setting.
    let p = spec(
        tmp.path(),
        &format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"-1\"]\n[[policy]]\npolicy = \"hold\"\n"),
    );
    plan(&p, &tmp.path().join("negative"));
    for (body, needle) in [
        (
            format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"hold\"\n[[latency]]\nbudget = \"-5ms\"\n"),
            "-5ms",
        ),
        (
            format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"hold\"\n[[engine]]\nengine = \"rapier\"\nphysics_dt_s = -0.001\n"),
            "physics",
        ),
    ] {
        let e = plan_error(tmp.path(), &body);
        assert!(!e.contains("unexpected argument"), "{e}");
        assert!(e.contains(needle), "`{needle}` not in: {e}");
    }
}

// ---------------------------------------------------------------- J: files

#[test]
fn unwritable_sweep_files_are_errors_naming_them_and_leave_no_temp_file() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = four_tasks(tmp.path());
    let dir = tmp.path().join("sweep");
    plan(&spec, &dir);
    ok(thorarena(&["sweep", "run", s(&dir), "--jobs", "2"]));
    // `cells` is a file.
    std::fs::write(dir.join("cells"), "").unwrap();
    let e = err(&thorarena(&["sweep", "collect", s(&dir)]));
    assert!(e.contains("cells"), "{e}");
    // `slurm` and `k8s` are files (and a task is left to submit).
    std::fs::remove_file(dir.join("tasks/000003/done.json")).unwrap();
    std::fs::write(dir.join("slurm"), "").unwrap();
    let e = err(&thorarena(&["sweep", "slurm", s(&dir)]));
    assert!(e.contains("slurm"), "{e}");
    std::fs::write(dir.join("k8s"), "").unwrap();
    let e = err(&thorarena(&[
        "sweep",
        "k8s",
        s(&dir),
        "--image",
        "i",
        "--claim",
        "c",
    ]));
    assert!(e.contains("k8s"), "{e}");

    // A task's logs cannot be created.
    for log in ["eval.log", "policy.log"] {
        let d = tmp.path().join(format!("logs-{log}"));
        let body = format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\ncommand = \"{{thorarena}} client --session {{session}}\"\n"
        );
        let sub = tmp.path().join(format!("spec-{log}"));
        std::fs::create_dir(&sub).unwrap();
        let p = sub.join("spec.toml");
        std::fs::write(&p, body).unwrap();
        plan(&p, &d);
        std::fs::create_dir_all(d.join("tasks/000000").join(log)).unwrap();
        let e = err(&thorarena(&["sweep", "task", s(&d), "--index", "0"]));
        assert!(e.contains(log), "{e}");
    }

    // A full disk (a file size limit: writes fail with EFBIG) while writing plan.json.
    let full = tmp.path().join("full");
    let o = Command::new("bash")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 1; exec \"$0\" sweep plan \"$1\" --out \"$2\"")
        .arg(BIN)
        .arg(&spec)
        .arg(&full)
        .output()
        .unwrap();
    let e = err(&o);
    assert!(e.contains("plan"), "{e}");
    let left: Vec<String> = names(&full)
        .into_iter()
        .filter(|n| n.contains("tmp"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    assert!(!full.join("plan.json").exists());
}

#[test]
fn a_policy_process_the_sweep_does_not_start_is_refused_at_once() {
    // `policy = "ipc:NAME"` once made `sweep plan` serve the session and wait forever.
    let tmp = tempfile::tempdir().unwrap();
    let start = std::time::Instant::now();
    let e = plan_error(
        tmp.path(),
        &format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"ipc:elsewhere\"\n"),
    );
    assert!(
        e.contains("ipc:elsewhere") && e.contains("give `command`"),
        "{e}"
    );
    assert!(start.elapsed().as_secs() < 20, "took {:?}", start.elapsed());
}

#[test]
fn a_cell_without_a_profile_takes_its_policy_familys() {
    let tmp = tempfile::tempdir().unwrap();
    let p = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"hold\"\n[[policy]]\npolicy = \"twist2:missing.onnx\"\nprofile = \"default\"\n"
        ),
    );
    // A TWIST2 network on the default profile: refused when planning, naming both.
    let e = err(&thorarena(&[
        "sweep",
        "plan",
        s(&p),
        "--out",
        s(&tmp.path().join("a")),
    ]));
    assert!(e.contains("trained for the `twist2` profile"), "{e}");
    // Without `profile`, each cell's is its family's.
    let p = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"force\"]\n[[policy]]\npolicy = \"hold\"\n"
        ),
    );
    let out = tmp.path().join("b");
    plan(&p, &out);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    assert_eq!(plan["cells"][0]["policy"]["profile"], "default", "{plan}");
}
