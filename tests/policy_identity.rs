//! A run names the policy it ran by content — its network file's SHA-256 and size, the
//! profile's and the robot's fingerprints — and nothing joins two of them: `merge` and
//! `--resume` refuse another network or profile naming both hashes, a report tells two
//! networks of one family apart by hash, a run written before runs recorded it still
//! loads and says "network not recorded". A family's parameters are its declared ones and
//! its network fits its contract, or the argument is refused before anything runs.
//!
//! The networks are FALCON-shaped ([1, 575] → [1, 29]) and written by the test
//! (`common/onnx_model.rs`): two that differ only in their weights are two networks.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "common/onnx_model.rs"]
mod onnx_model;
use onnx_model::Network;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn error_of(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "expected an error: {e}");
    assert!(!e.contains("panicked"), "a panic: {e}");
    e
}

/// A network `[batch, inputs] → [batch, 29]` whose weights are all `fill`, at `dir/name`;
/// `batch` < 0 is a symbolic batch axis.
fn network(dir: &Path, name: &str, batch: i64, inputs: i64, fill: f32) -> PathBuf {
    let path = dir.join(name);
    let net = Network {
        inputs: vec![("obs", vec![batch, inputs])],
        outputs: vec![("actions", "obs", 29, fill)],
        metadata: Vec::new(),
    };
    std::fs::write(&path, net.bytes()).unwrap();
    path
}

fn sha256_of(path: &Path) -> String {
    thorarena::sim::motion::sha256_hex(&std::fs::read(path).unwrap())
}

fn run_json(run: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap()
}

/// `eval` of `policy` on one sample sequence under `no-force` and `force`, shard `shard`
/// (`0/2`: one episode each), into `out`, with `extra` flags.
fn eval_shard(policy: &str, shard: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "eval",
        "--dataset",
        SAMPLE,
        "--policy",
        policy,
        "--unchecked",
        "--sequences",
        "clean_table_000",
        "--settings",
        "no-force,force",
        "--shard",
        shard,
        "--workers",
        "1",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    thorarena(&args)
}

#[test]
fn run_json_names_the_network_and_merge_and_resume_refuse_another() {
    let tmp = tempfile::tempdir().unwrap();
    let a = network(tmp.path(), "a.onnx", 1, 575, 0.0);
    let b = network(tmp.path(), "b.onnx", 1, 575, 1e-4);
    let (sha_a, sha_b) = (sha256_of(&a), sha256_of(&b));
    assert_ne!(sha_a, sha_b);
    let (pa, pb) = (
        format!("falcon:{}", a.display()),
        format!("falcon:{}", b.display()),
    );
    let (ra, rb) = (tmp.path().join("ra"), tmp.path().join("rb"));
    ok(&eval_shard(&pa, "0/2", &ra, &[]));
    ok(&eval_shard(&pb, "1/2", &rb, &[]));

    let header = run_json(&ra);
    let identity = &header["identity"];
    assert_eq!(identity["network"]["sha256"], sha_a.as_str(), "{header}");
    assert_eq!(
        identity["network"]["bytes"],
        std::fs::metadata(&a).unwrap().len()
    );
    assert_eq!(identity["profile_sha256"].as_str().unwrap().len(), 64);
    assert_eq!(identity["robot_sha256"].as_str().unwrap().len(), 64);
    let tables = std::fs::read_to_string(ra.join("tables.md")).unwrap();
    assert!(
        tables.contains(&format!("network {}", &sha_a[..12])),
        "{tables}"
    );

    // merge: the shards of two networks are refused, naming both hashes.
    let merged = tmp.path().join("merged");
    let e = error_of(&thorarena(&[
        "merge",
        ra.to_str().unwrap(),
        rb.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]));
    assert!(
        e.contains(&sha_a[..12]) && e.contains(&sha_b[..12]),
        "merge did not name both networks: {e}"
    );
    assert!(!merged.join("summary.json").exists());

    // --resume onto a's run with b's network: refused, naming both.
    let e = error_of(&eval_shard(&pb, "0/2", &ra, &["--resume"]));
    assert!(
        e.contains(&sha_a[..12]) && e.contains(&sha_b[..12]),
        "the resume did not name both networks: {e}"
    );
    // The same network under another name resumes (the identity is the bytes).
    let copy = tmp.path().join("copy-of-a.onnx");
    std::fs::copy(&a, &copy).unwrap();
    let resumed = eval_shard(
        &format!("falcon:{}", copy.display()),
        "0/2",
        &ra,
        &["--resume"],
    );
    ok(&resumed);
    let said = String::from_utf8_lossy(&resumed.stderr);
    assert!(said.contains("(1 already done)"), "{said}");

    // A report of the two runs tells them apart by network, not by directory.
    let report = tmp.path().join("report.md");
    ok(&thorarena(&[
        "report",
        ra.to_str().unwrap(),
        rb.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]));
    let md = std::fs::read_to_string(&report).unwrap();
    for sha in [&sha_a, &sha_b] {
        assert!(
            md.contains(&format!("falcon (network {})", &sha[..12])),
            "{md}"
        );
    }
}

#[test]
fn a_profile_changed_between_shards_is_not_merged() {
    let tmp = tempfile::tempdir().unwrap();
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/profiles/default.toml");
    let mine = tmp.path().join("mine.toml");
    let text = std::fs::read_to_string(&bundled).unwrap();
    std::fs::write(&mine, &text).unwrap();
    let (r0, r1) = (tmp.path().join("r0"), tmp.path().join("r1"));
    let profile = ["--profile", mine.to_str().unwrap()];
    ok(&eval_shard("hold", "0/2", &r0, &profile));
    // The knee's stiffness cut tenfold.
    let cut = text.replacen("knee = 600.0", "knee = 60.0", 1);
    assert_ne!(cut, text, "the profile has no knee kp to cut");
    std::fs::write(&mine, cut).unwrap();
    ok(&eval_shard("hold", "1/2", &r1, &profile));
    let (p0, p1) = (
        run_json(&r0)["identity"]["profile_sha256"].clone(),
        run_json(&r1)["identity"]["profile_sha256"].clone(),
    );
    assert_ne!(p0, p1);
    let e = error_of(&thorarena(&[
        "merge",
        r0.to_str().unwrap(),
        r1.to_str().unwrap(),
        "--out",
        tmp.path().join("m").to_str().unwrap(),
    ]));
    assert!(
        e.contains("profile content")
            && e.contains(&p0.as_str().unwrap()[..12])
            && e.contains(&p1.as_str().unwrap()[..12]),
        "{e}"
    );
}

#[test]
fn a_run_written_before_identities_loads_and_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let (r0, r1) = (tmp.path().join("r0"), tmp.path().join("r1"));
    ok(&eval_shard("hold", "0/2", &r0, &[]));
    ok(&eval_shard("hold", "1/2", &r1, &[]));
    // As written before this change: no `identity`.
    let mut header = run_json(&r0);
    header.as_object_mut().unwrap().remove("identity");
    std::fs::write(
        r0.join("run.json"),
        serde_json::to_string_pretty(&header).unwrap(),
    )
    .unwrap();
    let report = tmp.path().join("old.md");
    ok(&thorarena(&[
        "report",
        r0.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]));
    let md = std::fs::read_to_string(&report).unwrap();
    assert!(md.contains("network not recorded"), "{md}");
    // It joins no run that records its identity.
    let e = error_of(&thorarena(&[
        "merge",
        r0.to_str().unwrap(),
        r1.to_str().unwrap(),
        "--out",
        tmp.path().join("m").to_str().unwrap(),
    ]));
    assert!(e.contains("not recorded"), "{e}");
}

#[test]
fn parameters_a_family_does_not_take_are_refused_before_anything_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let f = network(tmp.path(), "f.onnx", 1, 575, 0.0);
    for (policy, says) in [
        (
            format!("falcon:{}@stiffness=5", f.display()),
            "`falcon` has no parameter `stiffness`",
        ),
        (
            format!("twist2:{}@stiffness=5", f.display()),
            "`twist2` takes no parameters",
        ),
        (
            format!("wbc-mjlab:{}@x=1", f.display()),
            "`wbc-mjlab` takes no parameters",
        ),
        (
            format!("softmimic:{}@stiffness=100,stiffness=200", f.display()),
            "given twice",
        ),
        (
            format!("softmimic:{}@stiffness=1e300", f.display()),
            "outside 10 to 1000 N/m",
        ),
    ] {
        let out = tmp.path().join("never");
        let e = error_of(&eval_shard(&policy, "0/2", &out, &[]));
        assert!(e.contains(says), "{policy}: {e}");
        assert!(
            !out.exists(),
            "{policy}: a refused run left {}",
            out.display()
        );
    }
}

#[test]
fn a_network_of_another_family_is_refused_at_load_naming_both_widths() {
    let tmp = tempfile::tempdir().unwrap();
    // TWIST2's shape, with a symbolic batch axis: [batch, 1432] → [batch, 29].
    let twist = network(tmp.path(), "twist2-like.onnx", -1, 1432, 0.0);
    for family in ["falcon", "softmimic"] {
        let policy = format!("{family}:{}", twist.display());
        let e = error_of(&eval_shard(&policy, "0/2", &tmp.path().join(family), &[]));
        assert!(e.contains("1432"), "{policy}: {e}");
        let check = thorarena(&["policy", "check", &policy]);
        let e = error_of(&check);
        assert!(e.contains("1432"), "policy check {policy}: {e}");
        let printed = String::from_utf8_lossy(&check.stdout);
        assert!(
            !printed.contains("inference failed") && !e.contains("inference failed"),
            "{printed}{e}"
        );
    }
    // A network answering 12 values instead of 29.
    let narrow = tmp.path().join("narrow.onnx");
    let net = Network {
        inputs: vec![("obs", vec![1, 575])],
        outputs: vec![("actions", "obs", 12, 0.0)],
        metadata: Vec::new(),
    };
    std::fs::write(&narrow, net.bytes()).unwrap();
    let e = error_of(&eval_shard(
        &format!("falcon:{}", narrow.display()),
        "0/2",
        &tmp.path().join("narrow"),
        &[],
    ));
    assert!(
        e.contains("answers 12 values per row") && e.contains("29"),
        "{e}"
    );
}

#[test]
fn a_network_path_that_is_no_file_is_refused_plainly() {
    let tmp = tempfile::tempdir().unwrap();
    for (path, says) in [
        (tmp.path().to_path_buf(), "is a directory, not a file"),
        (PathBuf::from("/dev/zero"), "is a device, not a file"),
    ] {
        let policy = format!("falcon:{}", path.display());
        let e = error_of(&eval_shard(&policy, "0/2", &tmp.path().join("x"), &[]));
        assert!(e.contains(says), "{policy}: {e}");
    }
}

#[test]
fn every_policy_help_lists_every_family_of_the_registry() {
    use thorarena::policy::registry::{Runs, POLICY_FAMILIES};
    for (command, in_process_only) in [
        (vec!["eval", "--help"], false),
        (vec!["policy", "check", "--help"], true),
        (vec!["crosscheck", "--help"], true),
        (vec!["bench", "eval", "--help"], true),
    ] {
        let help = ok(&thorarena(&command));
        for f in &POLICY_FAMILIES {
            let listed = help.contains(f.spelling);
            let offered = !in_process_only || f.runs == Runs::InProcess;
            assert_eq!(
                listed,
                offered,
                "`{}` and family `{}`:\n{help}",
                command.join(" "),
                f.name
            );
        }
        if command[0] != "crosscheck" {
            assert!(help.contains("`falcon` for falcon"), "{help}");
        }
    }
}

/// A dataset of one sample sequence (`clean_table_000`), copied into `dir`.
fn one_sequence_dataset(dir: &Path) -> PathBuf {
    let ds = dir.join("one");
    std::fs::create_dir_all(ds.join("clean_table")).unwrap();
    let sample = Path::new(SAMPLE);
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sample.join("manifest.json")).unwrap())
            .unwrap();
    let sequences = manifest["sequences"].as_array_mut().unwrap();
    sequences.retain(|s| s["sequence_id"] == "clean_table_000");
    assert_eq!(sequences.len(), 1);
    std::fs::write(
        ds.join("manifest.json"),
        serde_json::to_string_pretty(&manifest).unwrap(),
    )
    .unwrap();
    std::fs::copy(
        sample.join("clean_table/clean_table_000.safetensors"),
        ds.join("clean_table/clean_table_000.safetensors"),
    )
    .unwrap();
    ds
}

#[test]
fn the_leaderboard_runs_a_row_again_when_its_network_file_changed() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = one_sequence_dataset(tmp.path());
    let mine = tmp.path().join("mynet.onnx");
    let other = network(tmp.path(), "other.onnx", 1, 575, 1e-4);
    std::fs::copy(network(tmp.path(), "first.onnx", 1, 575, 0.0), &mine).unwrap();
    let out = tmp.path().join("lb");
    let policy = format!("falcon:{}", mine.display());
    let board = || {
        thorarena(&[
            "leaderboard",
            "--policy",
            &policy,
            "--dataset",
            ds.to_str().unwrap(),
            "--settings",
            "no-force",
            "--engines",
            "rapier",
            "--unchecked",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    ok(&board());
    let run = std::fs::read_dir(out.join("runs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.join("run.json").is_file())
        .expect("the leaderboard's run");
    let sha_first = sha256_of(&mine);
    assert_eq!(
        run_json(&run)["identity"]["network"]["sha256"],
        sha_first.as_str()
    );
    // Unchanged: the finished run is kept.
    let again = board();
    ok(&again);
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("(1 already done)"),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    // Another network copied over the file: the row runs again, and says why.
    std::fs::copy(&other, &mine).unwrap();
    let changed = board();
    ok(&changed);
    let said = String::from_utf8_lossy(&changed.stderr);
    assert!(
        said.contains("ran another policy")
            && said.contains(&sha_first[..12])
            && said.contains(&sha256_of(&other)[..12])
            && said.contains("(0 already done)"),
        "{said}"
    );
    assert_eq!(
        run_json(&run)["identity"]["network"]["sha256"],
        sha256_of(&other).as_str()
    );
}

#[test]
fn a_sweep_task_refuses_a_network_replaced_since_planning() {
    let tmp = tempfile::tempdir().unwrap();
    let net = network(tmp.path(), "net.onnx", 1, 575, 0.0);
    let spec = tmp.path().join("spec.toml");
    std::fs::write(
        &spec,
        format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\", \"force\"]\nsequences = [\"clean_table_000\"]\n[[policy]]\npolicy = \"falcon:{}\"\nunchecked = true\n",
            net.display()
        ),
    )
    .unwrap();
    let dir = tmp.path().join("sweep");
    ok(&thorarena(&[
        "sweep",
        "plan",
        spec.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]));
    let planned = sha256_of(&net);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("plan.json")).unwrap()).unwrap();
    assert_eq!(
        plan["cells"][0]["policy"]["network_sha256"],
        planned.as_str()
    );
    let task = |i: &str| {
        thorarena(&[
            "sweep",
            "task",
            dir.to_str().unwrap(),
            "--index",
            i,
            "--workers",
            "1",
        ])
    };
    ok(&task("0"));
    network(tmp.path(), "net.onnx", 1, 575, 1e-4);
    let e = error_of(&task("1"));
    assert!(
        e.contains("changed since the sweep was planned")
            && e.contains(&planned[..12])
            && e.contains(&sha256_of(&net)[..12]),
        "{e}"
    );
}

#[test]
fn a_sweep_axis_over_a_parameter_the_family_lacks_is_refused_at_plan_time() {
    let tmp = tempfile::tempdir().unwrap();
    let net = network(tmp.path(), "net.onnx", 1, 575, 0.0);
    let spec = tmp.path().join("spec.toml");
    std::fs::write(
        &spec,
        format!(
            "datasets = [\"{SAMPLE}\"]\nsettings = [\"no-force\"]\n[[policy]]\npolicy = \"falcon:{}\"\nparameters = {{ stiffness = [40, 200] }}\n",
            net.display()
        ),
    )
    .unwrap();
    let dir = tmp.path().join("sweep");
    let e = error_of(&thorarena(&[
        "sweep",
        "plan",
        spec.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]));
    assert!(e.contains("`falcon` has no parameter `stiffness`"), "{e}");
    assert!(!dir.join("plan.json").exists());
}
