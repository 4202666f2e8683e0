//! A policy process says what it was trained under: at connect it declares its dynamics
//! profile — a bundled one by name or the numbers — and the run takes it when it names
//! none, records it by content (`run.json`: the profile's name, `declared_profile`, and
//! the identity's profile fingerprint), refuses a `--profile` that contradicts it (or runs
//! it with `--profile-mismatch-ok`, recorded), and refuses a process that declares none
//! when the run names none either, telling both sides both ways to fix it. Python clients,
//! over iceoryx2's binding and over the C ABI. A process under any profile but the
//! baselines' `default` passes the sanity check first, as a network in process does, and
//! `run.json` records the verdict: TWIST2's published network in a Python process passes.
//! (The replay script here is open loop — no tracker — so its runs under other profiles
//! are `--unchecked`, which is recorded too.)

mod policy_session;
mod prereq;

use policy_session::*;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;
use thorarena::policy::registry;

/// `eval` serving `session` on one short sequence without force.
fn serve(session: &str, out: &Path, extra: &[&str]) -> Child {
    Command::new(BIN)
        .args(["eval", "--dataset", &format!("{ROOT}/data/sample")])
        .args(["--policy", &format!("ipc:{session}")])
        .args(["--sequences", "clean_table_000", "--settings", "no-force"])
        .args(["--workers", "1", "--out", out.to_str().unwrap()])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// A Python replay policy joining `session`, declaring `profile` (a Python expression:
/// `None`, `"wbc-mjlab"`, `ta.Profile(...)`), over `transport`.
fn python_client(session: &str, profile: &str, transport: &str) -> Child {
    let script = format!(
        r#"
import sys, numpy as np, thorarena as ta
try:
    s = ta.connect({session:?}, name="declares", joint_names=ta.G1_JOINT_NAMES,
                   timeout_s=60, profile={profile}, transport={transport:?})
except ta.SessionRefused as e:
    print(f"refused: {{e}}", file=sys.stderr)
    sys.exit(7)
for obs, actions in s.steps():
    active = (obs["flags"] & ta.FLAG_ACTIVE) != 0
    target = obs["reference"][:, 0]["joint_pos"]
    actions[:] = np.where(active[:, None], (target - s.action_offset_rad) / s.action_scale, 0.0)
"#
    );
    Command::new("python3")
        .args(["-c", &script])
        .env("PYTHONPATH", format!("{ROOT}/adapters/python"))
        .env("THORARENA_IPC_LIB", ipc_library())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// The C ABI library cargo built for this test binary: `libthorarena_ipc.so` beside it
/// in `<target>/<profile>/deps` (a test build does not copy it up to `<profile>`, and a
/// separate `cargo build -p thorarena-ipc` would replace the workspace's own build of the
/// crate there).
fn ipc_library() -> std::path::PathBuf {
    let exe = std::env::current_exe().unwrap();
    exe.parent().unwrap().join("libthorarena_ipc.so")
}

fn run_json(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `profile` as the Python expression of its numbers, named `name`.
fn python_profile(profile: &thorarena::sim::profile::Profile, name: &str) -> String {
    let list = |v: &[f64]| format!("{v:?}");
    format!(
        "ta.Profile(name={name:?}, control_dt_s={:?}, physics_dt_s={:?}, kp={}, kd={}, action_scale={}, action_offset_rad={}, action_delay_steps={}, action_clip={})",
        profile.control_dt_s,
        profile.physics_dt_s,
        list(&profile.gains.kp),
        list(&profile.gains.kd),
        list(&profile.action_scale),
        list(&profile.action_offset_rad),
        profile.action_delay_steps,
        profile.action_clip.map_or("None".to_string(), |c| format!("{c:?}")),
    )
}

/// Runs a client declaring `profile` against a run with `extra` flags: both outputs.
fn pair(
    name: &str,
    profile: &str,
    transport: &str,
    extra: &[&str],
) -> (Output, Output, std::path::PathBuf, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let s = session(name);
    let out = dir.path().join("run");
    let run = serve(&s, &out, extra);
    let client = python_client(&s, profile, transport);
    let client = wait_at_most(client, Duration::from_secs(120), "the policy client");
    let run = wait_at_most(run, Duration::from_secs(120), "eval");
    (run, client, out, dir)
}

#[test]
fn a_profile_declared_by_name_or_by_numbers_is_the_runs_and_is_recorded() {
    if !python_ready(
        "declared_profile::a_profile_declared_by_name_or_by_numbers_is_the_runs_and_is_recorded",
    ) {
        return;
    }
    let robot = registry::robot("g1_29dof").unwrap();
    let wbc = registry::profile("wbc-mjlab", &robot).unwrap();
    let default = registry::profile("default", &robot).unwrap();
    assert_ne!(wbc.fingerprint(), default.fingerprint());
    // By name: the run takes wbc-mjlab's gains, not the default profile's.
    let (run, client, out, _dir) = pair("named", "\"wbc-mjlab\"", "python", &["--unchecked"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    let header = run_json(&out);
    assert_eq!(header["profile"], "wbc-mjlab", "{header}");
    assert_eq!(header["declared_profile"], "wbc-mjlab");
    assert_eq!(header["identity"]["profile_sha256"], wbc.fingerprint());
    assert!(
        stderr(&run).contains("profile `wbc-mjlab`"),
        "{}",
        stderr(&run)
    );

    // By numbers: the same gains under a name of the user's, resolved as a file's would
    // be (its torque limits the robot's).
    let numbers = python_profile(&wbc, "my-mjlab-run");
    let (run, client, out, _dir) = pair("numbers", &numbers, "python", &["--unchecked"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    let header = run_json(&out);
    assert_eq!(header["profile"], "my-mjlab-run", "{header}");
    assert_eq!(header["declared_profile"], "my-mjlab-run");
    let declared = thorarena::policy::declared_profile::resolve(
        &thorarena_ipc::DeclaredProfile::Content(thorarena_ipc::ProfileContent {
            name: "my-mjlab-run".into(),
            control_dt_s: wbc.control_dt_s,
            physics_dt_s: wbc.physics_dt_s,
            action_delay_steps: wbc.action_delay_steps as u32,
            action_clip: wbc.action_clip,
            kp: wbc.gains.kp.clone(),
            kd: wbc.gains.kd.clone(),
            action_scale: wbc.action_scale.clone(),
            action_offset_rad: wbc.action_offset_rad.clone(),
        }),
        &robot,
    )
    .unwrap();
    assert_eq!(header["identity"]["profile_sha256"], declared.fingerprint());
    assert_eq!(
        (&declared.gains.kp, &declared.gains.kd),
        (&wbc.gains.kp, &wbc.gains.kd)
    );
    assert_eq!(
        declared.gains.effort_limit_nm,
        robot.joints.iter().map(|j| j.effort_nm).collect::<Vec<_>>()
    );
}

#[test]
fn over_the_c_abi_a_declared_profile_is_the_runs_too() {
    if !python_ready("declared_profile::over_the_c_abi_a_declared_profile_is_the_runs_too") {
        return;
    }
    if !ipc_library().exists() {
        return prereq::skip(
            "declared_profile::over_the_c_abi_a_declared_profile_is_the_runs_too",
            &format!(
                "no {} (is `cdylib` still in ipc/Cargo.toml's crate-type?)",
                ipc_library().display()
            ),
        );
    }
    let robot = registry::robot("g1_29dof").unwrap();
    let wbc = registry::profile("wbc-mjlab", &robot).unwrap();
    let (run, client, out, _dir) = pair("native", "\"wbc-mjlab\"", "native", &["--unchecked"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    assert_eq!(
        run_json(&out)["identity"]["profile_sha256"],
        wbc.fingerprint()
    );
    let numbers = python_profile(&wbc, "native-numbers");
    let (run, client, out, _dir) = pair("native-n", &numbers, "native", &["--unchecked"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    assert_eq!(run_json(&out)["profile"], "native-numbers");
}

#[test]
fn a_process_that_declares_none_needs_the_runs_profile_and_is_told_both_ways() {
    if !python_ready("declared_profile::a_process_that_declares_none_needs_the_runs_profile_and_is_told_both_ways") {
        return;
    }
    // With --profile, a process that declares none runs under it.
    let (run, client, out, _dir) = pair("none-given", "None", "python", &["--profile", "default"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    let header = run_json(&out);
    assert_eq!(header["profile"], "default");
    assert!(header.get("declared_profile").is_none(), "{header}");
    // Under the baselines' profile a process is judged as a baseline is.
    assert_eq!(header["sanity"]["status"], "exempt", "{header}");
    // Without, it is refused in its handshake (it hears why and exits), and the run,
    // which had no other policy, ends at its connect timeout saying why it refused it.
    let (run, client, out, _dir) = pair("none", "None", "python", &["--connect-timeout", "8"]);
    assert_eq!(client.status.code(), Some(7), "{}", stderr(&client));
    for (who, text) in [("client", stderr(&client)), ("eval", stderr(&run))] {
        assert!(
            text.contains("declared no profile")
                && text.contains("--profile NAME")
                && text.contains("connect(profile=")
                && text.contains("options.profile_name"),
            "{who}: {text}"
        );
    }
    assert!(!run.status.success());
    assert!(!out.join("episodes.jsonl").exists());
}

#[test]
fn a_profile_that_contradicts_the_declared_one_is_refused_unless_allowed() {
    if !python_ready(
        "declared_profile::a_profile_that_contradicts_the_declared_one_is_refused_unless_allowed",
    ) {
        return;
    }
    let extra = ["--profile", "default", "--connect-timeout", "8"];
    let (run, client, _out, _dir) = pair("contra", "\"wbc-mjlab\"", "python", &extra);
    assert_eq!(client.status.code(), Some(7), "{}", stderr(&client));
    let text = stderr(&client);
    assert!(
        text.contains("contradicts") && text.contains("--profile-mismatch-ok"),
        "{text}"
    );
    assert!(!run.status.success());
    // Allowed: the run's profile stands, and run.json says it ran against the declaration.
    let extra = ["--profile", "default", "--profile-mismatch-ok"];
    let (run, client, out, _dir) = pair("contra-ok", "\"wbc-mjlab\"", "python", &extra);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    let header = run_json(&out);
    assert_eq!(header["profile"], "default");
    assert_eq!(header["declared_profile"], "wbc-mjlab");
    assert_eq!(header["profile_mismatch_ok"], true);
    // The same numbers under --profile are no contradiction.
    let (run, client, out, _dir) = pair("same", "\"default\"", "python", &["--profile", "default"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    assert!(run_json(&out).get("profile_mismatch_ok").is_none());
}

#[test]
fn a_network_in_a_process_passes_the_sanity_check_first_and_the_verdict_is_recorded() {
    let test = "declared_profile::a_network_in_a_process_passes_the_sanity_check_first_and_the_verdict_is_recorded";
    if !prereq::python_modules(
        test,
        &["iceoryx2", "numpy", "onnxruntime"],
        "pip install './adapters/python[policies]'",
    ) {
        return;
    }
    let Some(onnx) = prereq::reference(test, "twist2/twist2_1017_25k.onnx") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let s = session("twist2-check");
    let out = dir.path().join("run");
    // One walk, so the check and the run are short.
    let run = Command::new(BIN)
        .args(["eval", "--dataset", &format!("{ROOT}/data/sample")])
        .args(["--policy", &format!("ipc:{s}")])
        .args(["--sequences", "syn_carry_001", "--settings", "no-force"])
        .args(["--workers", "1", "--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = Command::new("python3")
        .arg(format!(
            "{ROOT}/adapters/python/examples/twist2/run_twist2.py"
        ))
        .args([
            "--session",
            &s,
            "--onnx",
            onnx.to_str().unwrap(),
            "--timeout",
            "60",
        ])
        .args(["--transport", "python"])
        .env("PYTHONPATH", format!("{ROOT}/adapters/python"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let client = wait_at_most(client, Duration::from_secs(300), "the TWIST2 process");
    let run = wait_at_most(run, Duration::from_secs(300), "eval");
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(client.status.success(), "{}", stderr(&client));
    let header = run_json(&out);
    assert_eq!(header["profile"], "twist2", "{header}");
    assert_eq!(header["sanity"]["status"], "passed", "{header}");
}
