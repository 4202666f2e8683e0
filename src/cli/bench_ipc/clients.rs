//! The measured clients of `bench ipc`, each started as its own process on its own
//! session: the echo policies (Rust, C++, Python) and the Python TWIST2 adapter.

use super::{Args, Builder, NetworkTiming};
use anyhow::{bail, Context};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;
use thorarena::evaluation::LatencySummary;
use thorarena::perf::{adapter_round_trips, echo_round_trips, AdapterTiming};
use thorarena::policy::inputs::InputBuilder;
use thorarena::robot::RobotModel;
use thorarena_ipc::{Layout, SimConfig, SimSession, WaitPolicy};

/// `--ipc-lib`, or the shared library cargo left beside this binary or in its deps/.
pub(super) fn ipc_library(args: &Args) -> Option<PathBuf> {
    if let Some(lib) = &args.ipc_lib {
        return Some(lib.clone());
    }
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?;
    [dir.to_path_buf(), dir.join("deps")]
        .into_iter()
        .map(|d| d.join("libthorarena_ipc.so"))
        .find(|p| p.is_file())
}

pub(super) fn adapter_round_trip(
    args: &Args,
    robot: &RobotModel,
    envs: usize,
    built_by: Builder,
    ipc_lib: Option<&Path>,
) -> anyhow::Result<Option<(AdapterTiming, NetworkTiming)>> {
    let onnx = args.onnx.as_ref().context("--onnx")?;
    let ok = Command::new(&args.python)
        .args(["-c", "import iceoryx2, numpy, onnxruntime"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        eprintln!(
            "skipping twist2: `{} -c 'import iceoryx2, numpy, onnxruntime'` fails (pip install './adapters/python[policies]')",
            args.python
        );
        return Ok(None);
    }
    let session = format!("bench-twist2-{envs}-{}", std::process::id());
    let config = sim_config(args, robot, &session, envs);
    let mut builder = InputBuilder::new("twist2", envs, &config.action_offset_rad)
        .context("the simulator's TWIST2 input")?;
    let mut sim = SimSession::create(config)?;
    let python = repo_root().join("adapters/python");
    let (observation, transport) = match built_by {
        Builder::Simulator => ("simulator", "python"),
        Builder::SimulatorNative => ("simulator", "native"),
        Builder::Adapter => ("python", "python"),
    };
    let mut command = Command::new(&args.python);
    command
        .arg(python.join("examples/twist2/run_twist2.py"))
        .args(["--session", &session, "--time-network"])
        .args(["--observation", observation, "--transport", transport])
        .args(["--spin-us", &args.spin_us.to_string()])
        .arg("--onnx")
        .arg(onnx)
        .env("PYTHONPATH", python)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit());
    if let Some(lib) = ipc_lib {
        command.env("THORARENA_IPC_LIB", lib);
    }
    let mut child = command
        .spawn()
        .context("starting the Python TWIST2 adapter")?;
    let accepted = sim.accept(Some(Duration::from_secs(60)), |m| eprintln!("refused: {m}"));
    let timed = accepted.map_err(anyhow::Error::from).and_then(|info| {
        let input = info.input.is_some().then_some(&mut builder);
        if input.is_some() == (built_by == Builder::Adapter) {
            bail!("the adapter asked for policy input {:?}", info.input);
        }
        Ok(adapter_round_trips(
            &mut sim,
            args.warmup,
            args.adapter_steps,
            &info.reference_offsets_s,
            input,
        )?)
    });
    sim.end();
    let timed = match timed {
        Ok(t) => t,
        Err(e) => {
            let _ = child.kill();
            let _ = child.wait();
            return Err(e.context("the Python TWIST2 adapter"));
        }
    };
    let out = child.wait_with_output()?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    #[derive(serde::Deserialize)]
    struct Line {
        network_us: NetworkTiming,
    }
    let line = stdout
        .lines()
        .find_map(|l| serde_json::from_str::<Line>(l).ok())
        .with_context(|| format!("the adapter printed no network timing; its output:\n{stdout}"))?;
    if line.network_us.count != args.warmup + args.adapter_steps
        || line.network_us.each.len() != line.network_us.count
    {
        bail!(
            "the adapter timed {} network calls, {} steps were sent",
            line.network_us.count,
            args.warmup + args.adapter_steps
        );
    }
    Ok(Some((timed, line.network_us)))
}

/// A session of `envs` slots for the G1 with the identity action mapping.
fn sim_config(args: &Args, robot: &RobotModel, session: &str, envs: usize) -> SimConfig {
    let n_joints = robot.n_joints();
    SimConfig {
        session: session.to_string(),
        n_envs: envs,
        joint_names: robot.joints.iter().map(|j| j.name.clone()).collect(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; n_joints],
        action_scale: vec![1.0; n_joints],
        budget: None,
        wait: WaitPolicy {
            spin: Duration::from_micros(args.spin_us),
            ..WaitPolicy::default()
        },
        inputs: thorarena::policy::inputs::offers(n_joints),
    }
}

/// The checkout this binary was built from: the C++ and Python echo clients live there.
fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn spawn_client(args: &Args, client: &str, session: &str) -> anyhow::Result<Option<Child>> {
    let spin = args.spin_us.to_string();
    let mut cmd = match client {
        "rust" => {
            let mut c = Command::new(std::env::current_exe()?);
            c.args([
                "client",
                "--policy",
                "echo",
                "--session",
                session,
                "--spin-us",
                &spin,
            ]);
            c
        }
        "cpp" => {
            let exe = args
                .cpp_echo
                .clone()
                .unwrap_or_else(|| repo_root().join("adapters/cpp/build/echo_policy"));
            if !exe.is_file() {
                eprintln!(
                    "skipping cpp: {} not found (build it: cargo build --release -p thorarena-ipc && make -C adapters/cpp)",
                    exe.display()
                );
                return Ok(None);
            }
            let mut c = Command::new(&exe);
            c.args(["--session", session, "--spin-us", &spin]);
            c
        }
        "python" => {
            let ok = Command::new(&args.python)
                .args(["-c", "import iceoryx2, numpy"])
                .output()
                .is_ok_and(|o| o.status.success());
            if !ok {
                eprintln!("skipping python: `{} -c 'import iceoryx2, numpy'` fails (pip install ./adapters/python)", args.python);
                return Ok(None);
            }
            let python = repo_root().join("adapters/python");
            let mut c = Command::new(&args.python);
            c.arg(python.join("examples/echo/echo_policy.py"))
                .args(["--session", session, "--spin-us", &spin])
                .env("PYTHONPATH", python);
            c
        }
        other => bail!("unknown client `{other}` (rust, cpp, python)"),
    };
    Ok(Some(
        cmd.stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .with_context(|| format!("starting the {client} echo policy"))?,
    ))
}

pub(super) fn shm_round_trips(
    args: &Args,
    robot: &RobotModel,
    client: &str,
    layout: Layout,
) -> anyhow::Result<Option<LatencySummary>> {
    let session = format!("bench-{client}-{}-{}", layout.n_envs, std::process::id());
    let mut sim = SimSession::create(sim_config(args, robot, &session, layout.n_envs))?;
    let Some(mut child) = spawn_client(args, client, &session)? else {
        return Ok(None);
    };
    let info = sim.accept(Some(Duration::from_secs(60)), |m| eprintln!("refused: {m}"))?;
    let shape = sim.layout().expect("connected");
    if shape != layout {
        bail!(
            "the {client} echo asked for {} reference frames; the socket baseline moves {} per environment",
            info.reference_offsets_s.len(),
            layout.n_refs
        );
    }
    let summary = echo_round_trips(&mut sim, args.warmup, args.steps)
        .with_context(|| format!("the {client} echo"))?;
    sim.end();
    let _ = child.wait();
    Ok(Some(summary))
}
