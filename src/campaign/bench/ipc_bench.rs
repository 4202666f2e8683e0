//! `thorarena bench ipc` as one call: the echo policies' round trips at each environment
//! count against the Unix-socket baselines moving the same bytes in the same run (once
//! with blocking reads, once with the shared-memory path's own wait), then the Python
//! TWIST2 adapter against its network's own time. Each row is handed over as soon as it is
//! measured; a client that cannot run here is skipped with a note saying why.

use super::ipc_clients::{adapter_round_trip, ipc_library, shm_round_trips};
use super::ipc_tables::{
    adapter_heading, adapter_row, echo_heading, echo_row, ADAPTER_NOTES, ECHO_GOALS,
};
use super::{socket_round_trips, BenchLine, Builder, IpcClients, Measured, PerfError};
use crate::eval::LatencySummary;
use crate::sim::robot::RobotModel;
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;
use thorarena_ipc::Layout;

/// The clients `bench ipc` knows: three echo policies (action = q) and the adapter.
const CLIENTS: [&str; 4] = ["rust", "cpp", "python", "twist2"];

/// The client that is TWIST2's Python adapter with its network, not an echo.
const ADAPTER: &str = "twist2";

/// `bench ipc` as asked for.
#[derive(Debug, Clone)]
pub struct IpcBench {
    /// How the clients run and how long they are timed.
    pub setup: IpcClients,
    /// Clients to time, in order: `rust`, `cpp`, `python` (echo policies), `twist2` (the
    /// adapter, which needs `setup.onnx`).
    pub clients: Vec<String>,
    /// Environment counts, one row per client each.
    pub envs: Vec<usize>,
    /// The C ABI library the adapter's extra row loads (`None`: the one cargo left beside
    /// `setup.exe`; without one the row is skipped with a note).
    pub ipc_lib: Option<PathBuf>,
}

impl IpcBench {
    /// Checks the request, then times the echo table and the adapter table on the G1,
    /// handing each line to `say` as it is measured.
    pub fn run(&self, say: &mut dyn FnMut(BenchLine)) -> Result<(), PerfError> {
        self.check()?;
        let robot = crate::policy::registry::robot("g1_29dof")?;
        let echoes: Vec<&str> = self
            .clients
            .iter()
            .map(String::as_str)
            .filter(|c| *c != ADAPTER)
            .collect();
        if !echoes.is_empty() {
            self.echo_table(&robot, &echoes, say)?;
        }
        if self.clients.iter().any(|c| c == ADAPTER) {
            self.adapter_table(&robot, say)?;
        }
        Ok(())
    }

    /// Counts at least one, every client known, the adapter's network given.
    fn check(&self) -> Result<(), PerfError> {
        let c = &self.setup;
        if c.steps == 0 || c.adapter_steps == 0 || self.envs.contains(&0) {
            return Err(PerfError::Precondition(
                "`option.steps`, `option.adapter_steps` and every `option.envs` value must be at least 1".into(),
            ));
        }
        if let Some(other) = self.clients.iter().find(|c| !CLIENTS.contains(&c.as_str())) {
            return Err(PerfError::Precondition(format!(
                "unknown client `{other}` (rust, cpp, python, twist2)"
            )));
        }
        if self.clients.iter().any(|c| c == ADAPTER) && c.onnx.is_none() {
            return Err(PerfError::Precondition(
                "the twist2 client needs `option.onnx` FILE: TWIST2's released network (twist2_1017_25k.onnx)".into(),
            ));
        }
        Ok(())
    }

    /// The echo policies' round trips against the socket baselines, one row per client
    /// and environment count.
    fn echo_table(
        &self,
        robot: &RobotModel,
        clients: &[&str],
        say: &mut dyn FnMut(BenchLine),
    ) -> Result<(), PerfError> {
        for line in echo_heading(&self.setup) {
            say(BenchLine::Figure(line));
        }
        let spin = Duration::from_micros(self.setup.spin_us);
        for &envs in &self.envs {
            // The echo policies ask for one reference frame (the current one).
            let layout = Layout {
                n_envs: envs,
                n_joints: robot.n_joints(),
                n_refs: 1,
                n_inputs: 0,
            };
            let blocking = self
                .socket_baseline(layout, Duration::ZERO)
                .map_err(PerfError::other("the Unix-socket baseline"))?;
            let spinning = self
                .socket_baseline(layout, spin)
                .map_err(PerfError::other("the spinning Unix-socket baseline"))?;
            for &client in clients {
                let refused = &mut |m: &str| say(BenchLine::Note(format!("refused: {m}")));
                match shm_round_trips(&self.setup, robot, client, layout, refused)
                    .map_err(PerfError::other(format!("the {client} echo")))?
                {
                    Measured::Taken(shm) => say(BenchLine::Figure(echo_row(
                        client, layout, &shm, &blocking, &spinning,
                    ))),
                    Measured::Skipped(why) => say(BenchLine::Note(format!("skipping {why}"))),
                }
            }
        }
        say(BenchLine::Figure(ECHO_GOALS.into()));
        Ok(())
    }

    /// The socket baseline: this binary's `bench socket-peer` answering, waiting `spin`
    /// before blocking (zero: blocking reads).
    fn socket_baseline(&self, layout: Layout, spin: Duration) -> Result<LatencySummary, PerfError> {
        let mut peer = Command::new(&self.setup.exe);
        peer.args(crate::campaign::own_command::socket_peer(
            layout.n_envs,
            layout.n_joints,
            layout.n_refs,
            spin.as_micros(),
        ));
        socket_round_trips(peer, layout, self.setup.warmup, self.setup.steps, spin)
    }

    /// The Python TWIST2 adapter's round trips against its network's time in the same
    /// run, with the observation built by the simulator (over iceoryx2's Python binding,
    /// and over the C ABI when its library is found) and by the adapter in numpy, one row
    /// each per environment count. A skipped adapter ends the table where it is.
    fn adapter_table(
        &self,
        robot: &RobotModel,
        say: &mut dyn FnMut(BenchLine),
    ) -> Result<(), PerfError> {
        for line in adapter_heading(&self.setup) {
            say(BenchLine::Figure(line));
        }
        let ipc_lib = ipc_library(self.ipc_lib.as_deref(), &self.setup.exe);
        if ipc_lib.is_none() {
            say(BenchLine::Note("skipping the C ABI client's rows: no libthorarena_ipc.so beside this binary (cargo build --release -p thorarena-ipc, or `option.ipc_lib`)".into()));
        }
        let builders: Vec<Builder> = [
            Builder::Simulator,
            Builder::SimulatorNative,
            Builder::Adapter,
        ]
        .into_iter()
        .filter(|b| *b != Builder::SimulatorNative || ipc_lib.is_some())
        .collect();
        for &envs in &self.envs {
            for &built_by in &builders {
                let lib = ipc_lib.as_deref();
                let refused = &mut |m: &str| say(BenchLine::Note(format!("refused: {m}")));
                match adapter_round_trip(&self.setup, robot, envs, built_by, lib, refused)
                    .map_err(PerfError::other("the Python TWIST2 adapter"))?
                {
                    Measured::Taken(row) => {
                        say(BenchLine::Figure(adapter_row(envs, built_by, &row)))
                    }
                    Measured::Skipped(why) => {
                        say(BenchLine::Note(format!("skipping {why}")));
                        return Ok(());
                    }
                }
            }
        }
        for line in ADAPTER_NOTES {
            say(BenchLine::Figure(line.into()));
        }
        Ok(())
    }
}
