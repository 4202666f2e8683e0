//! A published deployment stack, unchanged, drives a scored episode through `thorarena dds`:
//! holosoma's inference package (PyPI `holosoma-inference` 0.1.3 on Unitree's SDK binding
//! `far-unitree-sdk` 0.1.6, CycloneDDS inside), started as holosoma's sim-to-sim guide
//! starts it (`run_policy inference:g1-29dof-wbt --task.interface lo --task.use-sim-time`,
//! the robot's remote as its input, the clip stepped by the simulator's clock, which the
//! bridge publishes as holosoma's simulator does with `--zmq-clock 5555`), runs its FastSAC
//! dance policy on the simulated G1 for the whole 135.5 s dance. The scripted remote
//! presses A ("start the policy") and select+A ("start the motion clip"); the reference
//! clock starts at the latter. The same policy is then scored in process (`--policy
//! beyondmimic:`), and both results are printed side by side.
//!
//! 0.1.3 applies a per-joint action scale to any ONNX without `action_scale` metadata,
//! which the FastSAC file lacks (it was trained with 1.0, holosoma at fc600e7); the deploy
//! code's own flag `--task.no-action-scales-by-effort-limit-over-p-gain` restores 1.0, the
//! `holosoma-wbt` profile's scale. Without it the robot falls after about 4 s, through the
//! bridge as in process (docs/deployment.md, "Your deployment code, unchanged").
//!
//! The simulated robot runs on MuJoCo (the generated MJCF), both through the bridge and in
//! process. The bridge must keep real time at holosoma's 2 ms step, and rapier's G1 step
//! (≈ 0.5 ms with the episode's bookkeeping) leaves too little slack on a shared
//! 2-vCPU VM whose vCPU slows 10–20× for milliseconds at a time: there 4–8 % of the steps
//! start late, against 1 to 32 on MuJoCo (≈ 0.1 ms a step). docs/deployment.md, "Real time needs slack", has the
//! numbers; `THORARENA_DDS_TEST_ENGINE=rapier` runs this test on rapier. Even MuJoCo's
//! loop is late when the machine stalls for long (this one, during a whole-suite run: 1 548
//! of 18 000 steps, a step taking up to 16 ms): a deployed run the bridge reports as not
//! real-time is not scored but run again, three attempts in all, each printed.
//!
//! Both run in a private network namespace when root allows it. Skipped, saying so, when
//! `../shared/reference`, the deployment environment (`.venv-deploy`) or the `mujoco`
//! feature is absent; never in CI.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
mod netns;
mod prereq;

const BIN: &str = env!("CARGO_BIN_EXE_thorarena");

/// What holosoma logs when it waits for its operator (after its DDS participant is up).
const READY: &str = "Press the appropriate button";

/// `thorarena` with `args`; its stderr on failure.
fn thorarena(args: &[&str]) {
    let out = Command::new(BIN).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "thorarena {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The no-force average of a run's `summary.json`.
fn average(run: &Path) -> serde_json::Value {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    summary["settings"]["no-force"]["average"].clone()
}

#[test]
fn holosomas_inference_package_runs_unchanged_and_its_dance_is_scored() {
    const TEST: &str = "dds_holosoma::holosoma_inference";
    let Some(onnx) = prereq::reference(TEST, "holosoma/fastsac_g1_29dof_dancing.onnx") else {
        return;
    };
    let Some(python) = prereq::deploy_python(TEST) else {
        return;
    };
    let engine = std::env::var("THORARENA_DDS_TEST_ENGINE").unwrap_or_else(|_| "mujoco".into());
    if engine == "mujoco" && !cfg!(feature = "mujoco") {
        prereq::skip(
            TEST,
            "built without the `mujoco` feature (./test.sh builds it; see docs/engines.md, \"MuJoCo backend\")",
        );
        return;
    }
    let onnx = onnx.to_str().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (dataset, in_process) = (path("dance"), path("in-process"));
    thorarena(&[
        "data",
        "import",
        "--format",
        "onnx-motion",
        "--profile",
        "holosoma-wbt",
        onnx,
        "--out",
        &dataset,
        "--task",
        "dance",
    ]);

    // A run the machine did not keep in real time (the bridge says so, and its scores are
    // not a real-time run's) is not scored: it is run again, up to three times in all,
    // each attempt's report printed. Shared VMs stall the loop for milliseconds at a time
    // (docs/deployment.md, "Real time needs slack"). Held to the quiet host the figures
    // were measured near, too: more than one physics step in 200 late (quiet MuJoCo runs
    // have 1 to 32 of 67 730) means the host also stalled the deploy code, whose lag then
    // grows (a run 515 steps late, within the bridge's 1 %, tracked 73.8 mm against 58).
    let quiet = |realtime: &serde_json::Value| {
        let late = realtime["late_steps"].as_f64().unwrap_or(f64::INFINITY);
        let steps = realtime["physics_steps"].as_f64().unwrap_or(0.0);
        realtime["kept_real_time"] == true && late * 200.0 <= steps
    };
    let mut attempts = Vec::new();
    let mut kept = None;
    for attempt in 1..=3 {
        let deployed = path(&format!("deployed-{attempt}"));
        let realtime = deploy_once(&python, onnx, &engine, &dataset, &deployed);
        if quiet(&realtime) {
            kept = Some((deployed, realtime));
            break;
        }
        eprintln!(
            "attempt {attempt}: real time not kept, or more than 1 step in 200 late; not scored: {realtime}"
        );
        attempts.push(realtime);
    }
    let Some((deployed, realtime)) = kept else {
        panic!("no attempt kept real time on a quiet host: {attempts:#?}");
    };
    let offset = realtime["start_offset_s"].as_f64().unwrap();
    assert!((3.5..4.0).contains(&offset), "{realtime}");
    let commands = &realtime["commands"];
    assert_eq!(commands["bad_crc"], 0, "{realtime}");
    // The SDK binding sends the newest command at 500 Hz, one per 2 ms physics step.
    let physics_steps = realtime["physics_steps"].as_f64().unwrap();
    assert!(
        commands["received"].as_f64().unwrap() > 0.9 * physics_steps,
        "{realtime}"
    );

    // In process: the policy as trained, and the same network at the per-joint scale
    // holosoma's 0.1.3 would apply without the flag — a broken deployment's baseline.
    let broken = path("broken");
    for (profile, out) in [("holosoma-wbt", &in_process), ("holosoma-ppo", &broken)] {
        let policy = format!("beyondmimic:{onnx}");
        let mut args = vec!["eval", "--dataset", &dataset, "--profile", profile];
        args.extend(["--policy", &policy, "--settings", "no-force", "--unchecked"]);
        args.extend(["--engine", &engine, "--out", out]);
        thorarena(&args);
    }
    let (deployed, in_process, broken) = (
        average(Path::new(&deployed)),
        average(Path::new(&in_process)),
        average(Path::new(&broken)),
    );
    let number = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap();
    eprintln!(
        "holosoma FastSAC dance, no force, {engine} — deployed through DDS: FATS {:.1}, \
         survival {:.3}, KP {:.1} mm ({} of {} physics steps late; a step took p50 {:.3} ms, \
         at most {:.1} ms); in process: FATS {:.1}, survival {:.3}, KP {:.1} mm; scaled \
         wrong, in process: survival {:.3}",
        number(&deployed, "fats"),
        number(&deployed, "survival"),
        number(&deployed, "kp_mm"),
        realtime["late_steps"],
        realtime["physics_steps"],
        realtime["physics_step_ms"]["p50_ms"].as_f64().unwrap(),
        realtime["physics_step_ms"]["max_ms"].as_f64().unwrap(),
        number(&in_process, "fats"),
        number(&in_process, "survival"),
        number(&in_process, "kp_mm"),
        number(&broken, "survival"),
    );
    // The deploy code danced: a robot held in its stiff start-up pose, or one scaled wrong,
    // falls within seconds, deployed as in process at the same moment (docs/deployment.md). A working
    // deployment dances at least twice as long as the wrong scale does in process. Not
    // always the whole dance: the policy acts on states that reach it through DDS at its
    // own 50 Hz, its clip 3 control steps behind, and on MuJoCo that has cost it a fall
    // (docs/deployment.md: 2 of 6 real-time runs, 29.6 s and 114.5 s in). In process too: the dance
    // has a moment about 30 s in where rounding at the 1e-6 level decides (2 of 24 nudged
    // runs fall there); on AVX-512 kernels the in-process run at eight rows per call fell
    // there, with the pinned kernels it stands (docs/deployment.md).
    // So both are held to the same bar: twice the wrong scale's dance.
    for (run, what) in [(&deployed, "deployed"), (&in_process, "in process")] {
        assert!(
            number(run, "survival") >= 2.0 * number(&broken, "survival"),
            "{what} {run}, scaled wrong {broken}"
        );
    }
    // The BeyondMimic check's tracking bound; and close to the lock-step run: the deploy
    // code's clip runs a constant 3 control steps behind the reference (docs/deployment.md), which
    // cost it 8 to 12 mm on MuJoCo against a whole in-process dance (49.4 mm), 13 to 16
    // against the first 29.6 s (45.1 mm), not 20.
    assert!(number(&deployed, "kp_mm") < 100.0, "{deployed}");
    assert!(
        number(&deployed, "kp_mm") < number(&in_process, "kp_mm") + 20.0,
        "deployed {deployed}, in process {in_process}"
    );
}

/// One deployed dance: holosoma's deploy code and the bridge started as the module doc says,
/// the bridge's run written to `deployed`; its `realtime.json`. Panics when either side
/// fails.
fn deploy_once(
    python: &Path,
    onnx: &str,
    engine: &str,
    dataset: &str,
    deployed: &str,
) -> serde_json::Value {
    const TEST: &str = "dds_holosoma::holosoma_inference";
    let network = netns::PrivateNetwork::new(TEST);
    let log_path = Path::new(deployed).with_extension("holosoma.log");
    let log = std::fs::File::create(&log_path).unwrap();
    let read_log = || std::fs::read_to_string(&log_path).unwrap_or_default();
    let mut deploy = network
        .command(python)
        .args([
            "-m",
            "holosoma_inference.run_policy",
            "inference:g1-29dof-wbt",
        ])
        .args(["--task.model-path", onnx, "--task.interface", "lo"])
        .args(["--task.use-joystick", "--task.rl-rate", "50"])
        .arg("--task.no-action-scales-by-effort-limit-over-p-gain")
        .arg("--task.use-sim-time")
        .env("LOGURU_LEVEL", "INFO")
        .stdin(Stdio::null())
        .stdout(log.try_clone().unwrap())
        .stderr(log)
        .spawn()
        .unwrap();
    let started = Instant::now();
    while !read_log().contains(READY) {
        if deploy.try_wait().unwrap().is_some() || started.elapsed() > Duration::from_secs(120) {
            let _ = deploy.kill();
            let _ = deploy.wait();
            panic!("holosoma did not get ready:\n{}", read_log());
        }
        std::thread::sleep(Duration::from_millis(100));
    }

    let mut bridge = network
        .command(BIN)
        .args(["dds", "--dataset", dataset])
        .args(["--sequence", "dance/fastsac_g1_29dof_dancing"])
        .args(["--setting", "no-force", "--profile", "holosoma-wbt"])
        .args(["--engine", engine])
        .args(["--interface", "lo", "--zmq-clock", "5555"])
        .args(["--remote", "A@3s,select+A@3.5s", "--start-on", "select+A"])
        .args(["--name", "holosoma-deploy", "--out", deployed])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The dance is 135.5 s in real time; the bridge ends with it (or is stopped by its pid
    // after four minutes).
    let started = Instant::now();
    while bridge.try_wait().unwrap().is_none() && started.elapsed() < Duration::from_secs(240) {
        std::thread::sleep(Duration::from_millis(200));
    }
    let _ = bridge.kill();
    let bridge = bridge.wait_with_output().unwrap();
    let _ = deploy.kill(); // its loop never ends on its own
    let _ = deploy.wait();
    drop(network);
    let said = format!(
        "bridge: {}\nholosoma:\n{}",
        String::from_utf8_lossy(&bridge.stderr),
        read_log()
    );
    assert!(bridge.status.success(), "{said}");
    let log_text = read_log();
    assert!(log_text.contains("Using policy actions"), "{said}");
    assert!(log_text.contains("Starting motion clip"), "{said}");

    serde_json::from_str(
        &std::fs::read_to_string(Path::new(deployed).join("realtime.json")).unwrap(),
    )
    .unwrap()
}
