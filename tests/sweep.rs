//! `thorarena sweep`: a sweep's collected episodes equal separate `eval` runs of its cells
//! bit for bit (any `--jobs`, any task order, policies in or out of process); a killed
//! `sweep run` resumes without losing or duplicating an episode; a failing policy command
//! fails its task alone; bad specs and sweep directories are clear errors that write
//! nothing; the Kubernetes manifest is an Indexed Job.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .output()
        .expect("thorarena runs")
}

fn ok(o: Output) -> Output {
    assert!(
        o.status.success(),
        "stdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn err(o: &Output) -> String {
    assert!(!o.status.success(), "expected a failure");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `body` as `spec.toml` in `dir` (datasets given absolute in the body).
fn spec(dir: &Path, body: &str) -> PathBuf {
    let p = dir.join("spec.toml");
    std::fs::write(&p, body).unwrap();
    p
}

const TWO_CELLS: &str = r#"
datasets = ["DATA"]
settings = ["no-force", "force"]
shards = 2
[[policy]]
policy = "balance"
"#;

fn two_cells(dir: &Path) -> PathBuf {
    spec(dir, &TWO_CELLS.replace("DATA", SAMPLE))
}

fn plan(spec: &Path, out: &Path) {
    ok(thorarena(&[
        "sweep",
        "plan",
        spec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
}

/// A run's episode records, one JSON line each, byte for byte, in a canonical order
/// (`episodes.jsonl` is written in the order episodes finish, which depends on workers).
fn records(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    lines.sort();
    lines
}

/// `eval` of each cell on its own, unsharded: the reference a sweep must equal.
fn separate_evals(tmp: &Path, policy: &str) -> Vec<Vec<String>> {
    ["no-force", "force"]
        .iter()
        .map(|setting| {
            let out = tmp.join(format!("eval-{policy}-{setting}"));
            ok(thorarena(&[
                "eval",
                "--dataset",
                SAMPLE,
                "--policy",
                policy,
                "--settings",
                setting,
                "--out",
                out.to_str().unwrap(),
            ]));
            records(&out.join("episodes.jsonl"))
        })
        .collect()
}

fn collected(sweep: &Path) -> Vec<Vec<String>> {
    ok(thorarena(&["sweep", "collect", sweep.to_str().unwrap()]));
    (0..2)
        .map(|c| records(&sweep.join(format!("cells/{c:06}/episodes.jsonl"))))
        .collect()
}

/// Equal record sets, reported by count and first differing record, not by dumping them.
fn assert_same(got: &[Vec<String>], want: &[Vec<String>], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: cells");
    for (c, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.len(), w.len(), "{what}: cell {c} episodes");
        if let Some(i) = (0..g.len()).find(|&i| g[i] != w[i]) {
            panic!(
                "{what}: cell {c}, record {i} differs: {} … vs {} …",
                &g[i][..g[i].len().min(120)],
                &w[i][..w[i].len().min(120)]
            );
        }
    }
}

#[test]
fn a_sweep_equals_separate_evals_for_any_jobs_order_and_kill() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = two_cells(tmp.path());
    let reference = separate_evals(tmp.path(), "balance");
    assert_eq!(reference[0].len(), 12);

    // The pool, two at a time.
    let a = tmp.path().join("a");
    plan(&spec, &a);
    ok(thorarena(&[
        "sweep",
        "run",
        a.to_str().unwrap(),
        "--jobs",
        "2",
    ]));
    assert_same(&collected(&a), &reference, "sweep run --jobs 2");
    let csv = std::fs::read_to_string(a.join("results.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        3,
        "a header and one row per cell:\n{csv}"
    );
    let plots = report_plots(&a);
    assert!(
        plots.contains(&"sweep-fats-vs-coefficient".to_string()),
        "{plots:?}"
    );
    assert!(
        plots.contains(&"sweep-survival-vs-coefficient".to_string()),
        "{plots:?}"
    );
    assert!(
        !plots
            .iter()
            .any(|p| p.contains("budget") || p.contains("push")),
        "axes that did not vary are not plotted: {plots:?}"
    );
    assert_eq!(
        report_title_and_figures(&a),
        ("sweep: 1 policy × 2 force coefficients".to_string(), true)
    );

    // One task per process, last first (as a cluster may run them).
    let b = tmp.path().join("b");
    plan(&spec, &b);
    for i in (0..4).rev() {
        ok(Command::new(BIN)
            .args(["sweep", "task", b.to_str().unwrap()])
            .env("SLURM_ARRAY_TASK_ID", i.to_string())
            .output()
            .unwrap());
    }
    // A finished task run again is skipped, not redone.
    let again = ok(thorarena(&[
        "sweep",
        "task",
        b.to_str().unwrap(),
        "--index",
        "0",
    ]));
    assert!(String::from_utf8_lossy(&again.stdout).contains("already done"));
    assert_same(&collected(&b), &reference, "tasks in reverse order");

    // `sweep run` killed part-way, then run again.
    let c = tmp.path().join("c");
    plan(&spec, &c);
    let mut run = Command::new(BIN)
        .args(["sweep", "run", c.to_str().unwrap(), "--jobs", "1"])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let done = c.join("tasks/000000/done.json").exists();
        let started = std::fs::read_to_string(c.join("tasks/000001/run/episodes.jsonl"))
            .is_ok_and(|t| t.lines().count() >= 1);
        if done && started {
            break;
        }
        assert!(Instant::now() < deadline, "the sweep did not get going");
        std::thread::sleep(Duration::from_millis(20));
    }
    run.kill().unwrap(); // SIGKILL
    run.wait().unwrap();
    let status = ok(thorarena(&["sweep", "status", c.to_str().unwrap()]));
    let status = String::from_utf8_lossy(&status.stdout).into_owned();
    assert!(status.contains("not done (--array): 1-3"), "{status}");
    ok(thorarena(&[
        "sweep",
        "run",
        c.to_str().unwrap(),
        "--jobs",
        "2",
    ]));
    assert_same(&collected(&c), &reference, "killed and run again");
}

#[test]
fn an_out_of_process_policy_gives_the_in_process_episodes_and_a_dead_one_fails_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let body = format!(
        r#"
datasets = ["{SAMPLE}"]
settings = ["no-force", "force"]
[[policy]]
name = "balance-ipc"
command = "{{thorarena}} client --session {{session}} --policy balance"
connect_timeout_s = 30
"#
    );
    let spec_path = spec(tmp.path(), &body);
    let reference = separate_evals(tmp.path(), "balance");
    let dir = tmp.path().join("ipc");
    plan(&spec_path, &dir);
    let run = thorarena(&["sweep", "run", dir.to_str().unwrap(), "--jobs", "2"]);
    if !run.status.success() {
        // Why a task failed is in its logs: `sweep status` shows their tails.
        let status = thorarena(&["sweep", "status", dir.to_str().unwrap()]);
        panic!(
            "sweep run failed:\n{}\nsweep status:\n{}{}",
            String::from_utf8_lossy(&run.stderr),
            String::from_utf8_lossy(&status.stdout),
            String::from_utf8_lossy(&status.stderr)
        );
    }
    assert_same(&collected(&dir), &reference, "policy process");

    // A policy command that exits at once: its tasks fail, named by status, the others
    // (another policy) finish.
    let body = format!(
        r#"
datasets = ["{SAMPLE}"]
settings = ["no-force"]
[[policy]]
policy = "hold"
[[policy]]
name = "broken"
command = "echo 'cannot load the checkpoint {{session}}' >&2; exit 3"
connect_timeout_s = 20
"#
    );
    let spec_path = spec(tmp.path(), &body);
    let dir = tmp.path().join("broken");
    plan(&spec_path, &dir);
    let o = thorarena(&["sweep", "run", dir.to_str().unwrap(), "--jobs", "2"]);
    assert!(err(&o).contains("1 task(s) failed"), "{}", err(&o));
    let status = ok(thorarena(&["sweep", "status", dir.to_str().unwrap()]));
    let status = String::from_utf8_lossy(&status.stdout).into_owned();
    assert!(status.contains("1 done, 1 failed"), "{status}");
    assert!(
        status.contains("failed: task 1") && status.contains("policy `broken`"),
        "{status}"
    );
    assert!(status.contains("policy command exited"), "{status}");
    assert!(status.contains("cannot load the checkpoint"), "{status}");
    assert!(status.contains("not done (--array): 1"), "{status}");
    // Collect refuses the unfinished cell, and --partial marks it.
    let o = thorarena(&["sweep", "collect", dir.to_str().unwrap()]);
    assert!(err(&o).contains("unfinished"), "{}", err(&o));
    ok(thorarena(&[
        "sweep",
        "collect",
        dir.to_str().unwrap(),
        "--partial",
    ]));
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(
        rows[1].contains(",hold,") && rows[1].contains(",true,"),
        "{csv}"
    );
    assert!(
        rows[2].contains(",broken,") && rows[2].contains(",0,12,false,"),
        "{csv}"
    );
}

#[test]
fn two_copies_of_one_task_racing_leave_one_complete_run() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("race");
    plan(&two_cells(tmp.path()), &dir);
    let d = dir.to_str().unwrap();
    let copies: Vec<_> = (0..2)
        .map(|_| {
            Command::new(BIN)
                .args(["sweep", "task", d, "--index", "1", "--workers", "1"])
                .stdout(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let said: Vec<String> = copies
        .into_iter()
        .map(|c| String::from_utf8_lossy(&ok(c.wait_with_output().unwrap()).stdout).into_owned())
        .collect();
    // One ran it, the other waited for it and found it done.
    assert_eq!(
        said.iter().filter(|s| s.contains("task 1: done")).count(),
        1,
        "{said:?}"
    );
    assert_eq!(
        said.iter().filter(|s| s.contains("already done")).count(),
        1,
        "{said:?}"
    );
    let run = records(&dir.join("tasks/000001/run/episodes.jsonl"));
    assert_eq!(run.len(), 6, "shard 1 of 2 of 12 sequences, each once");
}

/// A collected sweep's report's title, and whether each declared plot also has its SVG
/// file in `report-figures/`.
fn report_title_and_figures(sweep: &Path) -> (String, bool) {
    let html = std::fs::read_to_string(sweep.join("report.html")).unwrap();
    let start = html.find("<title>").unwrap() + "<title>".len();
    let end = html.find("</title>").unwrap();
    let svgs = report_plots(sweep).iter().all(|id| {
        sweep
            .join("report-figures")
            .join(format!("{id}.svg"))
            .is_file()
    });
    (html[start..end].to_string(), svgs)
}

/// The canvas ids a collected sweep's report declares.
fn report_plots(sweep: &Path) -> Vec<String> {
    let html = std::fs::read_to_string(sweep.join("report.html")).unwrap();
    let start = html.find("id=\"report-data\"").expect("report data");
    let json_start = start + html[start..].find('>').unwrap() + 1;
    let json_end = json_start + html[json_start..].find("</script>").unwrap();
    let data: serde_json::Value = serde_json::from_str(&html[json_start..json_end]).unwrap();
    data["plots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn latency_budgets_under_measured_latency_are_plotted_against_fats() {
    let tmp = tempfile::tempdir().unwrap();
    let body = format!(
        r#"
datasets = ["{SAMPLE}"]
settings = ["no-force"]
[[policy]]
name = "hold"
command = "{{thorarena}} client --session {{session}} --policy hold"
connect_timeout_s = 30
[[latency]]
name = "lock-step"
[[latency]]
budget = "5ms"
mode = "measured"
[[latency]]
budget = "10ms"
mode = "measured"
"#
    );
    let dir = tmp.path().join("latency");
    plan(&spec(tmp.path(), &body), &dir);
    ok(thorarena(&["sweep", "run", dir.to_str().unwrap()]));
    ok(thorarena(&["sweep", "collect", dir.to_str().unwrap()]));
    let plots = report_plots(&dir);
    assert_eq!(
        plots
            .iter()
            .filter(|p| p.starts_with("sweep-"))
            .collect::<Vec<_>>(),
        ["sweep-fats-vs-budget"],
        "one setting: no force curve; two measured budgets: the latency curve"
    );
    assert_eq!(
        report_title_and_figures(&dir),
        (
            "sweep: 1 policy × 3 latency rules × 1 force coefficient".to_string(),
            true
        )
    );
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    assert!(
        csv.contains(",5ms,measured,hold,") && csv.contains(",10ms,measured,hold,"),
        "{csv}"
    );
}

/// A budget times a policy process's round trip: a policy in process is planned under the
/// rules that do not time it (no flat "tolerates any latency" curve over rules never
/// applied), and refused when every rule would.
#[test]
fn an_in_process_policy_is_planned_only_under_rules_it_can_honour() {
    let tmp = tempfile::tempdir().unwrap();
    let rules =
        "[[latency]]\nbudget = \"5ms\"\nmode = \"measured\"\n[[latency]]\nbudget = \"1us\"\n";
    let body = |lock_step: &str| {
        format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\n[[policy]]\npolicy = \"hold\"\n{lock_step}{rules}"
        )
    };
    let dir = tmp.path().join("some");
    plan(
        &spec(tmp.path(), &body("[[latency]]\nname = \"lock-step\"\n")),
        &dir,
    );
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("plan.json")).unwrap()).unwrap();
    let cells = plan["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 1, "{cells:?}");
    assert_eq!(cells[0]["latency"]["name"], "lock-step");
    let dir = tmp.path().join("none");
    let e = err(&thorarena(&[
        "sweep",
        "plan",
        spec(tmp.path(), &body("")).to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]));
    assert!(
        e.contains("runs in process") && e.contains("lock-step"),
        "{e}"
    );
    assert!(!dir.join("plan.json").exists());
}

#[test]
fn bad_specs_and_sweep_directories_are_clear_errors_that_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sweep");
    let out_s = out.to_str().unwrap().to_string();
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown key",
            TWO_CELLS.replace("DATA", SAMPLE).replace("shards", "shard"),
            "unknown field `shard`",
        ),
        (
            "unknown policy key",
            TWO_CELLS.replace("DATA", SAMPLE).replace(
                "policy = \"balance\"",
                "policy = \"balance\"\nprofil = \"x\"",
            ),
            "unknown field `profil`",
        ),
        (
            "empty axis",
            TWO_CELLS
                .replace("DATA", SAMPLE)
                .replace("[\"no-force\", \"force\"]", "[]"),
            "the axis `settings` is empty",
        ),
        (
            "missing dataset",
            TWO_CELLS.replace("DATA", "/nonexistent/dataset"),
            "/nonexistent/dataset",
        ),
        (
            "missing ONNX",
            TWO_CELLS
                .replace("DATA", SAMPLE)
                .replace("\"balance\"", "\"twist2:missing.onnx\""),
            "missing.onnx",
        ),
        (
            "bad setting",
            TWO_CELLS
                .replace("DATA", SAMPLE)
                .replace("\"force\"]", "\"fore\"]"),
            "`fore` is not force, no-force",
        ),
        (
            "bad budget",
            TWO_CELLS.replace("DATA", SAMPLE) + "[[latency]]\nbudget = \"5 parsecs\"\n",
            "5 parsecs",
        ),
        (
            "command without session",
            TWO_CELLS
                .replace("DATA", SAMPLE)
                .replace("policy = \"balance\"", "command = \"python3 policy.py\""),
            "{session}",
        ),
    ];
    for (what, body, needle) in cases {
        let p = spec(tmp.path(), &body);
        let o = thorarena(&["sweep", "plan", p.to_str().unwrap(), "--out", &out_s]);
        let e = err(&o);
        assert!(e.contains(needle), "{what}: `{needle}` not in: {e}");
        assert!(!out.exists(), "{what}: nothing may be written");
    }

    // A changed spec against an existing plan.
    let p = two_cells(tmp.path());
    plan(&p, &out);
    let before = std::fs::read(out.join("plan.json")).unwrap();
    ok(thorarena(&[
        "sweep",
        "plan",
        p.to_str().unwrap(),
        "--out",
        &out_s,
    ]));
    let changed = spec(
        tmp.path(),
        &TWO_CELLS
            .replace("DATA", SAMPLE)
            .replace("\"force\"]", "\"0.5\"]"),
    );
    let e = err(&thorarena(&[
        "sweep",
        "plan",
        changed.to_str().unwrap(),
        "--out",
        &out_s,
    ]));
    assert!(e.contains("cell 1: setting `force` → `0.5`"), "{e}");
    assert_eq!(std::fs::read(out.join("plan.json")).unwrap(), before);

    // `sweep task` without an index, or beyond the plan.
    let e = err(&Command::new(BIN)
        .args(["sweep", "task", &out_s])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .output()
        .unwrap());
    assert!(
        e.contains("SLURM_ARRAY_TASK_ID") && e.contains("JOB_COMPLETION_INDEX"),
        "{e}"
    );
    let e = err(&thorarena(&["sweep", "task", &out_s, "--index", "99"]));
    assert!(e.contains("the plan has tasks 0..4"), "{e}");

    // A sweep directory of another format version.
    let text = String::from_utf8(before).unwrap();
    std::fs::write(
        out.join("plan.json"),
        text.replacen(
            &format!("\"format\":{}", thorarena::campaign::sweep::PLAN_FORMAT),
            "\"format\":99",
            1,
        ),
    )
    .unwrap();
    let e = err(&thorarena(&["sweep", "status", &out_s]));
    assert!(e.contains("sweep format 99"), "{e}");

    // A plan of format 3, whose tasks held `eval` arguments instead of a request: refused
    // by every command, saying to plan again.
    let mut old: serde_json::Value = serde_json::from_str(&text).unwrap();
    old["format"] = serde_json::json!(3);
    for t in old["tasks"].as_array_mut().unwrap() {
        let request = t.as_object_mut().unwrap().remove("request").unwrap();
        let policy = request["policy"].as_str().unwrap().to_string();
        t["eval_args"] = serde_json::json!(["eval", format!("--policy={policy}")]);
    }
    std::fs::write(out.join("plan.json"), old.to_string()).unwrap();
    for command in ["status", "run", "collect"] {
        let e = err(&thorarena(&["sweep", command, &out_s]));
        assert!(
            e.contains("sweep format 3") && e.contains("plan the sweep again"),
            "{command}: {e}"
        );
    }
}

#[test]
fn the_kubernetes_manifest_is_an_indexed_job_over_every_task() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sweep");
    plan(&two_cells(tmp.path()), &out);
    ok(thorarena(&[
        "sweep",
        "k8s",
        out.to_str().unwrap(),
        "--image",
        "registry.example/thorarena:0.1",
        "--claim",
        "sweeps",
        "--parallelism",
        "3",
    ]));
    let text = std::fs::read_to_string(out.join("k8s/job.yaml")).unwrap();
    let y: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    assert_eq!(y["apiVersion"], "batch/v1");
    assert_eq!(y["kind"], "Job");
    let spec = &y["spec"];
    assert_eq!(spec["completionMode"], "Indexed");
    assert_eq!(spec["completions"].as_u64(), Some(4));
    assert_eq!(spec["parallelism"].as_u64(), Some(3));
    let pod = &spec["template"]["spec"];
    assert_eq!(pod["restartPolicy"], "Never");
    let c = &pod["containers"][0];
    assert_eq!(c["image"], "registry.example/thorarena:0.1");
    let dir = std::fs::canonicalize(&out).unwrap();
    let cmd: Vec<&str> = c["command"]
        .as_sequence()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(
        cmd[..4],
        ["thorarena", "sweep", "task", dir.to_str().unwrap()]
    );
    assert_eq!(c["volumeMounts"][0]["mountPath"], dir.to_str().unwrap());
    assert_eq!(
        pod["volumes"][0]["persistentVolumeClaim"]["claimName"],
        "sweeps"
    );
    assert_eq!(c["volumeMounts"][0]["name"], pod["volumes"][0]["name"]);
}

#[test]
fn the_slurm_script_is_an_array_over_the_tasks_not_done() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sweep");
    plan(&two_cells(tmp.path()), &out);
    ok(thorarena(&[
        "sweep",
        "task",
        out.to_str().unwrap(),
        "--index",
        "2",
    ]));
    ok(thorarena(&[
        "sweep",
        "slurm",
        out.to_str().unwrap(),
        "--partition",
        "cpu",
        "--time",
        "00:30:00",
        "--cpus-per-task",
        "2",
        "--max-parallel",
        "8",
    ]));
    let script = std::fs::read_to_string(out.join("slurm/sweep.sbatch")).unwrap();
    for line in [
        "#SBATCH --array=0-1,3%8",
        "#SBATCH --cpus-per-task=2",
        "#SBATCH --partition=cpu",
        "#SBATCH --time=00:30:00",
    ] {
        assert!(script.contains(line), "`{line}` missing:\n{script}");
    }
    assert!(script.contains("/slurm/logs/task-%a.log"), "{script}");
    assert!(script.contains(" sweep task "), "{script}");
}

/// A sweep's `tasks` and `sequences` reach every task's `eval`: the cells plan, run and
/// collect only those episodes, and their runs record the selection.
#[test]
fn a_sweep_of_some_tasks_runs_and_records_only_those() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = spec(
        tmp.path(),
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\ntasks = [\"push_chair\", \"pull_chair\"]\nsequences = [\"pull_chair_000\", \"push_chair/push_chair_001\"]\nshards = 2\n[[policy]]\npolicy = \"hold\"\n"
        ),
    );
    let dir = tmp.path().join("s");
    plan(&spec, &dir);
    let plan_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("plan.json")).unwrap()).unwrap();
    assert_eq!(plan_json["cells"][0]["episodes"], 2);
    ok(thorarena(&[
        "sweep",
        "run",
        dir.to_str().unwrap(),
        "--jobs",
        "2",
    ]));
    let got = collected_cell(&dir);
    let mut ids: Vec<String> = got
        .iter()
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).unwrap()["sequence_id"]
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect();
    ids.sort();
    assert_eq!(ids, ["pull_chair_000", "push_chair_001"]);
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cells/000000/run.json")).unwrap())
            .unwrap();
    assert_eq!(header["subset"]["sequences"][0], "pull_chair_000");
    // results.csv: the dataset as the spec names it, FATS without an interval: each of
    // the two tasks has one episode, so there is nothing to resample (an interval would
    // be FATS to FATS, a precision nothing measured).
    let mut csv = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let head = csv.headers().unwrap().clone();
    let row = csv.records().next().unwrap().unwrap();
    let col = |name: &str| &row[head.iter().position(|h| h == name).unwrap()];
    assert!(col("fats").parse::<f64>().unwrap() > 0.0);
    assert_eq!((col("fats_ci95_low"), col("fats_ci95_high")), ("", ""));
    assert!(col("kp_error_mm").parse::<f64>().unwrap() > 1.0, "in mm");
    assert!(col("global_kp_mm").parse::<f64>().unwrap() > 1.0, "in mm");
    // A built-in baseline has no force training to be outside of.
    assert_eq!(col("outside_training"), "");
    // A name the dataset does not hold fails at planning, not in every task.
    let bad = tmp.path().join("bad-spec");
    std::fs::create_dir_all(&bad).unwrap();
    let bad_spec = spec_text_with(&bad, "tasks = [\"push_chiar\"]");
    let e = err(&thorarena(&[
        "sweep",
        "plan",
        bad_spec.to_str().unwrap(),
        "--out",
        tmp.path().join("never").to_str().unwrap(),
    ]));
    assert!(e.contains("no task `push_chiar`"), "{e}");
}

fn collected_cell(sweep: &Path) -> Vec<String> {
    ok(thorarena(&["sweep", "collect", sweep.to_str().unwrap()]));
    records(&sweep.join("cells/000000/episodes.jsonl"))
}

fn spec_text_with(dir: &Path, line: &str) -> PathBuf {
    spec(
        dir,
        &format!("datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\n{line}\n[[policy]]\npolicy = \"hold\"\n"),
    )
}

#[test]
fn a_policy_marked_unchecked_is_planned_with_eval_unchecked() {
    let d = tempfile::tempdir().unwrap();
    let body = format!(
        "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\n[[policy]]\npolicy = \"hold\"\nunchecked = true\n[[policy]]\npolicy = \"balance\"\n"
    );
    let out = d.path().join("sweep");
    plan(&spec(d.path(), &body), &out);
    let planned: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    let unchecked: Vec<bool> = planned["tasks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["request"]["unchecked"] == true)
        .collect();
    // The first policy's task asks for an unchecked run, the second's does not.
    assert_eq!(unchecked, [true, false], "{planned}");
}
