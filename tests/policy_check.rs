//! The sanity check before a score counts (`thorarena policy check`, `thorarena::eval::sanity`):
//! every published network the build runs passes it — TWIST2 and wbc-mjlab on the bundled
//! sample's walk, holosoma's FastSAC and PPO dances on their own clips — and mis-wired
//! variants fail it, naming the check: holosoma's 154 inputs fed in mjlab's order, its PPO
//! under scale 1.0, wbc-mjlab under a profile calling its action absolute. A baseline that
//! cannot walk fails `track` from the command line too. `eval` runs the same check first:
//! its verdict is in `run.json` (`passed`, `exempt` for a baseline, `unchecked` under
//! `--unchecked`), and a network failing it is refused. The published networks are
//! skipped, saying so, when `../shared/reference` is absent; never in CI.

use std::path::{Path, PathBuf};
use std::process::Command;
use thorarena::eval::sanity::{check_policy, walking_sequence, SanityOptions, SanityReport};
use thorarena::policy::registry::{self, PolicyChoice};
use thorarena::sim::motion::import::SourceFormat;
use thorarena::sim::motion::{Dataset, Sequence};

mod common;
#[path = "common/in_process.rs"]
mod in_process;
#[path = "common/onnx_model.rs"]
mod onnx_model;
mod prereq;

/// `policy check POLICY --profile PROFILE` tracking `tracking`, in process.
fn check(policy: &str, profile: &Path, tracking: &Sequence) -> SanityReport {
    let robot = common::g1();
    let profile = thorarena::sim::profile::load_profile(profile, &robot).unwrap();
    let arg = registry::PolicySource::parse(policy).unwrap();
    let PolicyChoice::InProcess(mut p) = arg.load(&robot, &profile).unwrap() else {
        panic!("{policy} does not run in process");
    };
    let report = check_policy(
        p.as_mut(),
        &robot,
        &profile,
        tracking,
        &SanityOptions::default(),
    )
    .unwrap();
    for c in &report.checks {
        eprintln!(
            "{policy} [{}]: {} {}",
            report.profile,
            if c.passed { "pass" } else { "FAIL" },
            c.detail
        );
    }
    report
}

fn bundled(profile: &str) -> PathBuf {
    thorarena::sim::profile::bundled_profile_path(profile)
}

/// The bundled sample's walk: what `policy check` tracks for a general tracker.
fn sample_walk() -> Sequence {
    let robot = common::g1();
    let ds = Dataset::open(&thorarena::data_dir().join("sample"), &robot).unwrap();
    let seqs = ds.load_all().unwrap();
    let i = walking_sequence(&seqs, 10.0).unwrap();
    seqs[i].clone()
}

/// The motion embedded in a holosoma network, imported under `profile`.
fn own_clip(onnx: &Path, profile: &str, dir: &Path) -> Sequence {
    let robot = common::g1();
    let p = registry::profile(profile, &robot).unwrap();
    let out = dir.join(profile);
    in_process::import(
        SourceFormat::OnnxMotion {
            anchor_body: p.beyondmimic.as_ref().unwrap().anchor_body.clone(),
            control_dt_s: p.control_dt_s,
        },
        &[onnx],
        &out,
        false,
        false,
    )
    .unwrap();
    Dataset::open(&out, &robot).unwrap().load(0).unwrap()
}

/// A copy of bundled profile `profile` with `from` replaced by `to`, in `dir`.
fn edited_profile(dir: &Path, profile: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(bundled(profile)).unwrap();
    assert!(text.contains(from), "{profile} has no `{from}`");
    let path = dir.join(format!("{profile}-edited.toml"));
    std::fs::write(&path, text.replace(from, to)).unwrap();
    path
}

#[test]
fn the_published_networks_pass_and_mis_wired_variants_fail_naming_the_check() {
    const TEST: &str = "policy_check::published";
    let (Some(wbc), Some(twist2), Some(fastsac), Some(ppo)) = (
        prereq::reference(TEST, "wbc-mjlab/wbc_g1_policy.onnx"),
        prereq::reference(TEST, "twist2/twist2_1017_25k.onnx"),
        prereq::reference(TEST, "holosoma/fastsac_g1_29dof_dancing.onnx"),
        prereq::reference(TEST, "holosoma/ppo_g1_29dof_dancing.onnx"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let walk = sample_walk();
    let fastsac_clip = own_clip(&fastsac, "holosoma-wbt", dir.path());
    let ppo_clip = own_clip(&ppo, "holosoma-ppo", dir.path());
    let wbc = format!("wbc-mjlab:{}", wbc.display());
    let fastsac = format!("beyondmimic:{}", fastsac.display());
    let ppo = format!("beyondmimic:{}", ppo.display());

    for (policy, profile, clip) in [
        (wbc.clone(), "wbc-mjlab", &walk),
        (format!("twist2:{}", twist2.display()), "twist2", &walk),
        (fastsac.clone(), "holosoma-wbt", &fastsac_clip),
        (ppo.clone(), "holosoma-ppo", &ppo_clip),
    ] {
        let report = check(&policy, &bundled(profile), clip);
        assert!(
            report.passed(),
            "{policy} under {profile}: {:?}",
            report.failed()
        );
        assert_eq!(report.checks.len(), 4);
    }

    // holosoma's 154 inputs in mjlab's order: the network is fed the right numbers in the
    // wrong places, and cannot even stand.
    let mjlab_order = edited_profile(
        dir.path(),
        "holosoma-wbt",
        r#"observation_names = ["actions", "base_ang_vel", "dof_pos", "dof_vel", "motion_command", "motion_ref_ori_b"]"#,
        r#"observation_names = ["command", "motion_anchor_ori_b", "base_ang_vel", "joint_pos", "joint_vel", "actions"]"#,
    );
    let report = check(&fastsac, &mjlab_order, &fastsac_clip);
    assert!(report.failed().contains(&"stand"), "{:?}", report.failed());
    assert!(report.failed().contains(&"track"), "{:?}", report.failed());
    // The PPO file under FastSAC's scale 1.0: it falls on its own dance.
    let report = check(&ppo, &bundled("holosoma-wbt"), &ppo_clip);
    assert!(report.failed().contains(&"track"), "{:?}", report.failed());
    // wbc-mjlab under a profile saying its action is absolute: the file says otherwise,
    // and the contradiction fails the wiring check (the file's mode is still applied).
    let absolute = edited_profile(
        dir.path(),
        "wbc-mjlab",
        r#"action_mode = "reference_residual""#,
        r#"action_mode = "default_relative""#,
    );
    let report = check(&wbc, &absolute, &walk);
    assert_eq!(report.failed(), ["wiring"]);
    assert!(
        report.checks[0].detail.contains("action mode"),
        "{}",
        report.checks[0].detail
    );
}

#[test]
fn a_baseline_that_cannot_walk_fails_track_from_the_command_line() {
    let out = Command::new(env!("CARGO_BIN_EXE_thorarena"))
        .args(["policy", "check", "balance", "--json"])
        .output()
        .unwrap();
    assert!(
        !out.status.success(),
        "balance cannot walk, yet the check passed"
    );
    let report: SanityReport = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report.profile, "default");
    // It stands (a stabiliser), and falls on the walk.
    assert_eq!(report.failed(), ["track"]);
    assert_eq!(report.checks[1].survival, Some(1.0));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("policy check failed (track)"), "{stderr}");
}

/// `eval` of the bundled sample's `push_chair_001` without force, in process: the run's
/// `run.json` `sanity`, or the error's text.
fn sanity_of_eval(policy: &str, unchecked: bool, out: &Path) -> Result<serde_json::Value, String> {
    let request = thorarena::eval::EvalRequest {
        policy: thorarena::policy::registry::PolicySource::parse(policy).unwrap(),
        settings: vec!["no-force".parse().unwrap()],
        selection: thorarena::sim::motion::SequenceSelection {
            tasks: Vec::new(),
            sequences: vec!["push_chair_001".into()],
        },
        unchecked,
        ..Default::default()
    };
    let run = in_process::evaluate(&request, out)?;
    let header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    Ok(header["sanity"].clone())
}

#[test]
fn eval_records_the_check_in_run_json_and_refuses_a_network_failing_it() {
    let dir = tempfile::tempdir().unwrap();
    // A BeyondMimic-shaped network answering zero: it loads, and cannot stand.
    let zero = dir.path().join("zero.onnx");
    let net = onnx_model::Network {
        inputs: vec![("obs", vec![1, 160])],
        outputs: vec![("actions", "obs", 29, 0.0)],
        metadata: Vec::new(),
    };
    std::fs::write(&zero, net.bytes()).unwrap();
    let zero = format!("beyondmimic:{}", zero.display());
    let e = sanity_of_eval(&zero, false, &dir.path().join("refused")).unwrap_err();
    assert!(
        e.contains("failed its sanity check")
            && e.contains("FAIL stand")
            && e.contains("`request.unchecked`"),
        "{e}"
    );
    assert!(
        !dir.path().join("refused/run.json").exists(),
        "a refused run left a run.json"
    );
    // Scored anyway when asked, and the run says so.
    let s = sanity_of_eval(&zero, true, &dir.path().join("unchecked")).unwrap();
    assert_eq!(s["status"], "unchecked");
    // A built-in baseline is a floor, not a tracker: exempt, with the reason.
    let s = sanity_of_eval("balance", false, &dir.path().join("balance")).unwrap();
    assert_eq!(s["status"], "exempt");
    assert!(s["why"].as_str().unwrap().contains("baseline"), "{s}");
    // A published network passes on the walk of the data evaluated.
    let Some(wbc) = prereq::reference("policy_check::eval_records", "wbc-mjlab/wbc_g1_policy.onnx")
    else {
        return;
    };
    let s = sanity_of_eval(
        &format!("wbc-mjlab:{}", wbc.display()),
        false,
        &dir.path().join("wbc"),
    )
    .unwrap();
    assert_eq!(s["status"], "passed");
    assert_eq!(s["tracking_reference"], "push_chair/push_chair_001");
}

#[test]
fn a_published_network_runs_under_its_own_profile_whatever_its_file_is_called() {
    let Some(ppo) = prereq::reference(
        "policy_check::own_profile",
        "holosoma/ppo_g1_29dof_dancing.onnx",
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // Renamed: still holosoma's PPO dance, and its profile is the per-joint scale's.
    let renamed = dir.path().join("my_policy.onnx");
    std::fs::copy(&ppo, &renamed).unwrap();
    let policy = format!("beyondmimic:{}", renamed.display());
    assert_eq!(
        registry::PolicySource::parse(&policy)
            .unwrap()
            .default_profile(),
        "holosoma-ppo"
    );
    let spec = thorarena::eval::EvalSpec::load(&thorarena::eval::EvalRequest {
        policy: thorarena::policy::registry::PolicySource::parse(&policy).unwrap(),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(spec.profile.name, "holosoma-ppo");
    // One byte changed: another network, the family's profile.
    let mut bytes = std::fs::read(&ppo).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    let edited = dir.path().join("edited.onnx");
    std::fs::write(&edited, bytes).unwrap();
    assert_eq!(
        registry::PolicySource::parse(&format!("beyondmimic:{}", edited.display()))
            .unwrap()
            .default_profile(),
        "beyondmimic"
    );
}
