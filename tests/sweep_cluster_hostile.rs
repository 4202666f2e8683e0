//! Issue 22 for what a sweep writes for the cluster engines, "trust nothing that crosses a
//! boundary": a sweep directory, a binary path or a dataset path with shell, sbatch or
//! YAML syntax in it reaches the Slurm script and the Kubernetes manifest as data, never
//! as code or a placeholder. Each is an end-to-end test that failed on the code before
//! its fix. (The rest of issue 22 for sweeps: `sweep_hostile.rs`.)

mod sweep_support;

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::process::Command;
use sweep_support::*;

// ---------------------------------------------------------------- A: the Slurm script

#[test]
fn slurm_values_that_sbatch_cannot_quote_are_refused_and_nothing_reaches_the_shell() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = four_tasks(tmp.path());
    let stub = tmp.path().join("stub-thorarena");
    std::fs::write(&stub, "#!/bin/sh\nexit 0\n").unwrap();
    std::fs::set_permissions(&stub, std::fs::Permissions::from_mode(0o755)).unwrap();

    // A newline in the sweep directory used to end the #SBATCH line and start a command.
    let work = tmp.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let dir = tmp.path().join("s\ntouch injected;x");
    plan(&spec, &dir);
    let o = thorarena(&["sweep", "slurm", s(&dir), "--thorarena", s(&stub)]);
    if o.status.success() {
        let script = dir.join("slurm/sweep.sbatch");
        let _ = Command::new("bash")
            .arg(&script)
            .current_dir(&work)
            .output()
            .unwrap();
        assert!(
            !work.join("injected").exists(),
            "the sweep directory's name ran as a command:\n{}",
            std::fs::read_to_string(&script).unwrap()
        );
    } else {
        let e = err(&o);
        assert!(e.contains("newline") || e.contains("control"), "{e}");
    }

    // Newlines in --partition and --time.
    let good = tmp.path().join("good");
    plan(&spec, &good);
    for (flag, value) in [
        ("--partition", "cpu\ntouch injected"),
        ("--time", "01:00:00\ntouch injected"),
        ("--partition", "cpu gpu"),
        ("--time", "1:00 #x"),
    ] {
        let o = thorarena(&[
            "sweep",
            "slurm",
            s(&good),
            flag,
            value,
            "--thorarena",
            s(&stub),
        ]);
        let e = err(&o);
        assert!(e.contains(flag), "{flag} {value:?}: {e}");
    }

    // Quotes, spaces and `#` in the directory would change the #SBATCH line: refused,
    // naming the directory; `%` (a filename pattern) is escaped.
    for name in ["with space", "quote'd", "dq\"x", "hash#x"] {
        let d = tmp.path().join(name);
        plan(&spec, &d);
        let e = err(&thorarena(&[
            "sweep",
            "slurm",
            s(&d),
            "--thorarena",
            s(&stub),
        ]));
        assert!(e.contains(name), "{name}: {e}");
    }
    let pct = tmp.path().join("at-100%a");
    plan(&spec, &pct);
    ok(thorarena(&[
        "sweep",
        "slurm",
        s(&pct),
        "--thorarena",
        s(&stub),
    ]));
    let script = std::fs::read_to_string(pct.join("slurm/sweep.sbatch")).unwrap();
    assert!(
        script.contains("/at-100%%a/slurm/logs/task-%a.log"),
        "{script}"
    );
}

#[test]
fn the_kubernetes_manifest_names_a_hostile_directory_exactly() {
    // Already safe (JSON-quoted YAML scalars); kept so.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("k8s \"q\" 'q'\n$(touch M)#x: y%a");
    plan(&four_tasks(tmp.path()), &dir);
    ok(thorarena(&[
        "sweep",
        "k8s",
        s(&dir),
        "--image",
        "img: x",
        "--claim",
        "c\nd",
    ]));
    let text = std::fs::read_to_string(dir.join("k8s/job.yaml")).unwrap();
    let y: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let c = &y["spec"]["template"]["spec"]["containers"][0];
    let canonical = std::fs::canonicalize(&dir).unwrap();
    assert_eq!(c["command"][3].as_str(), canonical.to_str(), "{text}");
    assert_eq!(
        c["volumeMounts"][0]["mountPath"].as_str(),
        canonical.to_str()
    );
    assert_eq!(c["image"].as_str(), Some("img: x"));
    assert_eq!(
        y["spec"]["template"]["spec"]["volumes"][0]["persistentVolumeClaim"]["claimName"].as_str(),
        Some("c\nd")
    );
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
