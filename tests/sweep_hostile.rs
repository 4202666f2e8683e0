//! Issue 22 for sweeps, "trust nothing that crosses a boundary": a sweep directory, a
//! binary path or a dataset path with shell or sbatch syntax in it; a policy that dies
//! mid-run; task runs, plan entries and task records that were replaced, edited or
//! misplaced; policy output that is huge or holds terminal escapes; a dataset changed
//! before `collect`; spec values that are absurd, equivalent or negative; files that
//! cannot be written. Each is an end-to-end test that failed on the code before its fix.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

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

/// The error output of a command that must fail cleanly (an error, not a panic).
fn err(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(
        !o.status.success(),
        "expected a failure; stdout:\n{}",
        out(o)
    );
    assert_ne!(o.status.code(), Some(101), "a panic, not an error:\n{e}");
    assert!(!e.contains("panicked"), "a panic, not an error:\n{e}");
    e
}

fn out(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn spec(dir: &Path, body: &str) -> PathBuf {
    let p = dir.join("spec.toml");
    std::fs::write(&p, body).unwrap();
    p
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

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// One in-process policy, two settings, two shards: four quick tasks.
fn four_tasks(tmp: &Path) -> PathBuf {
    spec(
        tmp,
        &format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\", \"force\"]\nshards = 2\n[[policy]]\npolicy = \"hold\"\n"
        ),
    )
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let dest = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).unwrap();
        }
    }
}

// ---------------------------------------------------------------- B: placeholders

#[test]
fn the_binary_path_and_dataset_path_are_data_not_shell_or_placeholders() {
    let tmp = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).unwrap();
    // The binary under a directory whose name is a command substitution.
    let bindir = tmp.path().join("b$(touch pwned)");
    std::fs::create_dir(&bindir).unwrap();
    let exe = bindir.join("thorarena");
    if std::fs::hard_link(BIN, &exe).is_err() {
        std::fs::copy(BIN, &exe).unwrap();
    }
    // A dataset whose directory holds a placeholder's spelling.
    let ds = tmp.path().join("x{session}y");
    copy_dir(Path::new(SAMPLE), &ds);
    let workdir = tmp.path().join("specs");
    std::fs::create_dir(&workdir).unwrap();
    let spec_path = spec(
        &workdir,
        &format!(
            "datasets = [\"{}\"]\nsettings = [\"no-force\"]\n[[policy]]\nname = \"ipc\"\ncommand = \"{{thorarena}} client --session {{session}} --policy hold\"\nconnect_timeout_s = 30\n",
            ds.display()
        ),
    );
    let dir = tmp.path().join("sweep");
    let o = Command::new(&exe)
        .args(["sweep", "plan", s(&spec_path), "--out", s(&dir)])
        .output()
        .unwrap();
    ok(o);
    let plan_text = std::fs::read_to_string(dir.join("plan.json")).unwrap();
    assert!(plan_text.contains("x{session}y"), "{plan_text}");
    let o = Command::new(&exe)
        .args(["sweep", "task", s(&dir), "--index", "0", "--workers", "2"])
        .output()
        .unwrap();
    assert!(
        !workdir.join("pwned").exists(),
        "the binary's path ran as shell"
    );
    ok(o);
    let header: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("tasks/000000/run/run.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        header["dataset"].as_str().unwrap(),
        std::fs::canonicalize(&ds).unwrap().to_str().unwrap()
    );
}

// ---------------------------------------------------------------- D: runs and plan entries

/// Loads plan.json as JSON, lets `edit` change it, writes it back.
fn edit_plan(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join("plan.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
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
            "another policy in eval_args",
            Box::new(|v| {
                let args = v["tasks"][1]["eval_args"].as_array_mut().unwrap();
                for a in args.iter_mut() {
                    if a.as_str().is_some_and(|s| s.contains("hold")) {
                        *a = serde_json::json!(a.as_str().unwrap().replace("hold", "balance"));
                    }
                }
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
