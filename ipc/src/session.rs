//! What both sides share: service names per session, node creation, errors, and the
//! spin-then-block wait.

use iceoryx2::config::Config;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::node::NodeState;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::prelude::*;
use std::cell::Cell;
use std::time::{Duration, Instant};

/// Every way the transport can fail, for both sides.
#[derive(Debug, thiserror::Error)]
pub enum IpcError {
    /// The simulator's side was configured with something the protocol cannot carry.
    #[error("session configuration: {0}")]
    Config(String),
    /// The session name cannot name iceoryx2 services.
    #[error("bad session name {0:?}: use 1 to 64 characters from [A-Za-z0-9_.-]")]
    SessionName(String),
    /// Another live run already owns this session.
    #[error("session {0:?} is in use by another live run (stale shared memory of crashed runs is removed at start; this one is alive)")]
    SessionInUse(String),
    /// No simulator serves this session.
    #[error("no ThorArena run serves session {0:?} (start `thorarena eval --policy ipc:{0}` or `thorarena serve --session {0}` first)")]
    NoSession(String),
    /// The simulator refused the handshake.
    #[error("session refused ({status:?}): {message}")]
    Refused {
        /// Why, as a typed code.
        status: crate::Status,
        /// Why, in words.
        message: String,
    },
    /// Nothing connected or answered in time.
    #[error("timed out after {0:?} waiting for {1}")]
    Timeout(Duration, &'static str),
    /// The other process died or left.
    #[error("the {0} process is gone")]
    PeerGone(&'static str),
    /// A received block does not match the session's layout.
    #[error(transparent)]
    Layout(#[from] crate::LayoutError),
    /// iceoryx2 failed (the message carries its error).
    #[error("iceoryx2: {0}")]
    Transport(String),
}

pub(crate) fn transport<E: std::fmt::Debug>(what: &str) -> impl FnOnce(E) -> IpcError + '_ {
    move |e| IpcError::Transport(format!("{what}: {e:?}"))
}

/// The four services of a session, named `thorarena/<session>/…` so concurrent runs never
/// cross.
pub(crate) struct ServiceNames {
    pub hello: ServiceName,
    pub step: ServiceName,
    pub obs_ready: ServiceName,
    pub action_ready: ServiceName,
}

pub(crate) fn service_names(session: &str) -> Result<ServiceNames, IpcError> {
    let ok = !session.is_empty()
        && session.len() <= 64
        && session
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-".contains(c));
    if !ok {
        return Err(IpcError::SessionName(session.into()));
    }
    let name = |leaf: &str| {
        ServiceName::new(&format!("thorarena/{session}/{leaf}"))
            .map_err(|_| IpcError::SessionName(session.into()))
    };
    Ok(ServiceNames {
        hello: name("hello")?,
        step: name("step")?,
        obs_ready: name("obs_ready")?,
        action_ready: name("action_ready")?,
    })
}

/// A node that leaves signals to the host program and first removes what crashed
/// processes left behind in `/dev/shm` and `/tmp/iceoryx2`.
pub(crate) fn create_node(name: &str) -> Result<Node<ipc::Service>, IpcError> {
    set_log_level_from_env_or(LogLevel::Error);
    let node_name = NodeName::new(name).map_err(transport("node name"))?;
    let node = NodeBuilder::new()
        .name(&node_name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(transport("creating the node"))?;
    node.try_cleanup_dead_nodes();
    Ok(node)
}

/// True while process `pid` exists and is not a zombie. `0` means unknown (always alive).
///
/// For a process this one started (its own pid, not one it was told): a pid a peer reports
/// about itself proves nothing — it may name any live process, and inside a container it
/// names a process of another pid namespace. Peers are watched through [`PeerNode`].
pub fn process_alive(pid: u32) -> bool {
    if pid == 0 {
        return true;
    }
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        // The state is the first field after the parenthesised command name.
        Ok(stat) => stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .is_none_or(|state| state != "Z" && state != "X"),
        Err(_) => false,
    }
}

/// The other side's iceoryx2 node, watched for liveness.
///
/// iceoryx2 keeps a lock for each node that the kernel releases when the node's process
/// dies, however it dies, and removes the node's files when it closes cleanly; a peer can
/// neither hold that lock for a process that is gone nor choose which node the service's
/// ports say it created. So this, not a pid the peer reports about itself, decides whether
/// the peer lives — the same in a container that shares the iceoryx2 directories, where a
/// reported pid names a process of another pid namespace.
pub(crate) struct PeerNode {
    id: UniqueNodeId,
    config: Config,
    /// Looking a node up lists the node directory: do it at most this often.
    every: Duration,
    last: Cell<Option<(Instant, bool)>>,
}

impl PeerNode {
    /// Looks the node up at most every `every` (cached in between).
    pub(crate) fn new(id: UniqueNodeId, config: &Config, every: Duration) -> Self {
        Self {
            id,
            config: config.clone(),
            every,
            last: Cell::new(None),
        }
    }

    /// True while the node's process lives (or its state cannot be read: another user's
    /// node, or one being created, is not declared dead).
    pub(crate) fn alive(&self) -> bool {
        let now = Instant::now();
        if let Some((at, alive)) = self.last.get() {
            if !alive || now.duration_since(at) < self.every {
                return alive;
            }
        }
        let alive = match Node::<ipc::Service>::state_of(&self.config, self.id) {
            Ok(Some(NodeState::Alive(_))) => true,
            // Dead: its process is gone. None: it closed and removed itself.
            Ok(Some(NodeState::Dead(_))) | Ok(None) => false,
            Ok(Some(NodeState::Inaccessible(_) | NodeState::Undefined(_))) | Err(_) => true,
        };
        self.last.set(Some((now, alive)));
        alive
    }
}

/// How often a blocked side looks up its peer's node at most (a directory listing; the
/// cheaper "did it leave the session" check runs every `WaitPolicy::liveness_every`).
pub(crate) const NODE_CHECK_EVERY: Duration = Duration::from_millis(10);

/// How a side waits for the other: busy-poll for `spin`, then block on the event
/// listener; check the peer's liveness every `liveness_every` of blocking.
#[derive(Debug, Clone, Copy)]
pub struct WaitPolicy {
    /// Busy-poll this long before blocking (the low-latency path).
    pub spin: Duration,
    /// While blocked, check that the peer process lives this often.
    pub liveness_every: Duration,
}

impl Default for WaitPolicy {
    fn default() -> Self {
        Self {
            spin: Duration::from_micros(50),
            liveness_every: Duration::from_millis(2),
        }
    }
}

/// What a wait ended with.
pub(crate) enum Waited {
    Ready,
    Deadline,
    PeerGone,
}

/// Waits until `ready()` holds, the deadline passes, or the peer is gone: its node died
/// (`peer`), or it left the session while alive (`peer_present()` false). Drains the
/// listener after each wake-up (a WaitSet-free loop cannot spin on stale events).
pub(crate) fn wait_for(
    listener: &Listener<ipc::Service>,
    policy: WaitPolicy,
    deadline: Option<Instant>,
    peer: &PeerNode,
    peer_present: impl Fn() -> bool,
    mut ready: impl FnMut() -> bool,
) -> Result<Waited, IpcError> {
    let start = Instant::now();
    while start.elapsed() < policy.spin {
        if ready() {
            return Ok(Waited::Ready);
        }
        std::hint::spin_loop();
    }
    loop {
        if ready() {
            return Ok(Waited::Ready);
        }
        let now = Instant::now();
        let mut slice = policy.liveness_every;
        if let Some(d) = deadline {
            if now >= d {
                return Ok(Waited::Deadline);
            }
            slice = slice.min(d - now);
        }
        let n = match listener.timed_wait(|_| {}, slice) {
            Ok(n) => n,
            // A signal interrupted the wait (Ctrl-Z then `fg`: SIGSTOP, SIGCONT): nothing
            // happened to the session, so wait again after the liveness check below.
            Err(ListenerWaitError::InterruptSignal) => 0,
            Err(e) => return Err(transport("waiting on the event listener")(e)),
        };
        if n == 0 && !ready() && (!peer_present() || !peer.alive()) {
            return Ok(Waited::PeerGone);
        }
    }
}
