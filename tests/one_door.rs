//! Every command opens its run through one door (`eval::pipeline::Evaluation`), so a run
//! directory one command wrote is the same run to the others: `eval --resume` continues a
//! leaderboard's run and a `data check` rollout with nothing left to run, and a data
//! check run again continues its own. A run of another policy is refused by both, naming
//! what differs, and the board runs it again from the start when `--rerun` asks.

use std::path::Path;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");
const SAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sample");

fn thorarena(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn stderr_of(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `eval --resume` of `policy` on the sample without force into `run`.
fn eval_resume(run: &Path, policy: &str) -> Output {
    thorarena(&[
        "eval",
        "--policy",
        policy,
        "--dataset",
        SAMPLE,
        "--settings",
        "no-force",
        "--resume",
        "--out",
        run.to_str().unwrap(),
    ])
}

/// The sample's sequences: every one of them is an episode of a no-force run.
fn sample_sequences() -> usize {
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(Path::new(SAMPLE).join("manifest.json")).unwrap(),
    )
    .unwrap();
    manifest["sequences"].as_array().unwrap().len()
}

#[test]
fn eval_leaderboard_and_data_check_resume_one_anothers_runs_by_one_rule() {
    let tmp = tempfile::tempdir().unwrap();
    let n = sample_sequences();
    let done = format!("0 episodes to run ({n} already done)");

    // A data check's rollouts, continued by the check run again and by `eval --resume`.
    let check = tmp.path().join("check");
    let args = [
        "data",
        "check",
        SAMPLE,
        "--rollout",
        "hold",
        "--out",
        check.to_str().unwrap(),
    ];
    let first = thorarena(&args);
    assert!(first.status.success(), "{}", stderr_of(&first));
    let again = thorarena(&args);
    assert!(again.status.success(), "{}", stderr_of(&again));
    assert!(stderr_of(&again).contains(&done), "{}", stderr_of(&again));
    let resumed = eval_resume(&check.join("rollout-hold"), "hold");
    assert!(resumed.status.success(), "{}", stderr_of(&resumed));
    assert!(
        stderr_of(&resumed).contains(&done),
        "{}",
        stderr_of(&resumed)
    );

    // A leaderboard's run, continued by `eval --resume`.
    let board = tmp.path().join("board");
    let board_args = [
        "leaderboard",
        "--policy",
        "hold",
        "--dataset",
        SAMPLE,
        "--settings",
        "no-force",
        "--engines",
        "rapier",
        "--out",
        board.to_str().unwrap(),
    ];
    let o = thorarena(&board_args);
    assert!(o.status.success(), "{}", stderr_of(&o));
    let run = board.join("runs").join("hold-rapier");
    assert!(
        run.join("run.json").is_file(),
        "no run in {}",
        run.display()
    );
    let resumed = eval_resume(&run, "hold");
    assert!(resumed.status.success(), "{}", stderr_of(&resumed));
    assert!(
        stderr_of(&resumed).contains(&done),
        "{}",
        stderr_of(&resumed)
    );

    // Another policy's run there: `eval --resume` refuses it, naming what differs; so does
    // the board, saying how to run it again, and with `--rerun` runs it from the start.
    let other = eval_resume(&tmp.path().join("balance-run"), "balance");
    assert!(other.status.success(), "{}", stderr_of(&other));
    let refused = eval_resume(&tmp.path().join("balance-run"), "hold");
    assert!(!refused.status.success());
    assert!(
        stderr_of(&refused).contains("policy"),
        "{}",
        stderr_of(&refused)
    );
    std::fs::remove_dir_all(&run).unwrap();
    std::fs::rename(tmp.path().join("balance-run"), &run).unwrap();
    let o = thorarena(&board_args);
    assert!(!o.status.success());
    let said = stderr_of(&o);
    assert!(
        said.contains("differs in: policy") && said.contains("--rerun hold"),
        "{said}"
    );
    let mut rerun = board_args.to_vec();
    rerun.extend(["--rerun", "hold"]);
    let o = thorarena(&rerun);
    assert!(o.status.success(), "{}", stderr_of(&o));
    let said = stderr_of(&o);
    assert!(
        said.contains("running it again from the start")
            && said.contains(&format!("{n} episodes to run (0 already done)")),
        "{said}"
    );
}
