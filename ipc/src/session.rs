//! What both sides share: service names per session, node creation, errors, and the
//! spin-then-block wait.
//!
//! The wait busy-polls, then blocks to the microsecond (`precise_wait.rs`: iceoryx2's own
//! timed wait rounds up to scheduler ticks). A side that knows when the other is due
//! (`RecentTurns`: its last few turns) polls again through that window
//! (`WaitPolicy::wake_early`). While blocked it checks that the peer lives by the peer's
//! iceoryx2 node (`PeerNode`), whose lock the kernel releases when its process dies —
//! never by the pid the peer reports. A session's files live in this user's own root
//! (`private_root.rs`).

use iceoryx2::config::Config;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::node::NodeState;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use std::cell::Cell;
use std::time::{Duration, Instant};

mod precise_wait;
pub mod private_root;
use precise_wait::wait_for_event;

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
    /// This user's iceoryx2 directory, or a file in `/dev/shm` carrying this user's
    /// prefix, cannot be trusted or used ([`private_root`]).
    #[error("iceoryx2 files: {}: {problem}", .path.display())]
    PrivateRoot {
        /// The directory or file.
        path: std::path::PathBuf,
        /// What is wrong with it, and what to do.
        problem: String,
    },
    /// The other process died or left.
    #[error("the {0} process is gone")]
    PeerGone(&'static str),
    /// A received block does not match the session's layout.
    #[error(transparent)]
    Layout(#[from] crate::LayoutError),
    /// The transport failed while doing `op`: iceoryx2 returned an error, or the peer
    /// answered out of sequence (`cause` says which).
    #[error("iceoryx2: {op}: {cause}")]
    Transport {
        /// What this side was doing.
        op: TransportOp,
        /// Why it failed.
        cause: TransportCause,
    },
}

/// What a side was doing when the transport failed: callers match on it (a failed
/// [`TransportOp::Send`] is not a failed [`TransportOp::CreateNode`]), and the error's
/// text names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TransportOp {
    /// Making an iceoryx2 node name of the session's.
    NameNode,
    /// Creating this side's iceoryx2 node.
    CreateNode,
    /// Creating the session's services (the simulator's side).
    CreateServices,
    /// Creating a port of one of the session's services.
    CreatePort(Port),
    /// Loaning a batch in shared memory to write it.
    Loan(Message),
    /// Sending a message.
    Send(Message),
    /// Receiving a message.
    Receive(Message),
    /// Waking the peer through an event service.
    Notify(Event),
    /// Blocking on this side's event listener.
    WaitForEvent,
}

/// A port of a session's services, named as the error text names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Port {
    /// The simulator's server of the `hello` service.
    HelloServer,
    /// The policy's client of the `hello` service.
    HelloClient,
    /// The policy's server of the `step` service.
    StepServer,
    /// The simulator's client of the `step` service.
    StepClient,
    /// The simulator's notifier of the `obs_ready` event.
    ObsReadyNotifier,
    /// The policy's listener of the `obs_ready` event.
    ObsReadyListener,
    /// The policy's notifier of the `action_ready` event.
    ActionReadyNotifier,
    /// The simulator's listener of the `action_ready` event.
    ActionReadyListener,
}

/// A message of the protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Message {
    /// The policy's handshake request.
    Hello,
    /// The simulator's handshake answer.
    Welcome,
    /// An observation batch (a `step` request).
    Observations,
    /// An action batch (a `step` response).
    Actions,
}

/// An event service of a session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// The simulator published observations.
    ObsReady,
    /// The policy sent actions.
    ActionReady,
}

/// Why a transport operation failed.
#[derive(Debug)]
pub enum TransportCause {
    /// iceoryx2's own error (downcast it to the type the operation returns, e.g.
    /// `iceoryx2::port::ReceiveError`). Not an error `source`: the text already shows it.
    Iceoryx2(Box<dyn std::error::Error + Send + Sync>),
    /// The action batch received answers another step than the one sent.
    OutOfSequence {
        /// The step the batch answers.
        answered_seq: u64,
        /// The step that was sent.
        sent_seq: u64,
    },
}

impl std::fmt::Display for TransportOp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NameNode => f.write_str("node name"),
            Self::CreateNode => f.write_str("creating the node"),
            Self::CreateServices => f.write_str("creating the session services"),
            Self::CreatePort(port) => write!(f, "{port}"),
            Self::Loan(Message::Observations) => f.write_str("loaning the observation batch"),
            Self::Loan(Message::Actions) => f.write_str("loaning the action batch"),
            Self::Loan(message) => write!(f, "loaning the {message}"),
            Self::Send(message) => write!(f, "sending {message}"),
            Self::Receive(message) => write!(f, "receiving {message}"),
            Self::Notify(event) => write!(f, "notifying {event}"),
            Self::WaitForEvent => f.write_str("waiting on the event listener"),
        }
    }
}

impl std::fmt::Display for Port {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::HelloServer => "hello server",
            Self::HelloClient => "hello client",
            Self::StepServer => "step server",
            Self::StepClient => "step client",
            Self::ObsReadyNotifier => "obs_ready notifier",
            Self::ObsReadyListener => "obs_ready listener",
            Self::ActionReadyNotifier => "action_ready notifier",
            Self::ActionReadyListener => "action_ready listener",
        })
    }
}

impl std::fmt::Display for Message {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Hello => "hello",
            Self::Welcome => "welcome",
            Self::Observations => "observations",
            Self::Actions => "actions",
        })
    }
}

impl std::fmt::Display for Event {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::ObsReady => "obs_ready",
            Self::ActionReady => "action_ready",
        })
    }
}

impl std::fmt::Display for TransportCause {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            // iceoryx2's Debug text names the variant (`NodeCreationFailure::…`), its Display
            // often does not.
            Self::Iceoryx2(e) => write!(f, "{e:?}"),
            Self::OutOfSequence {
                answered_seq,
                sent_seq,
            } => write!(
                f,
                "action batch answers step {answered_seq} but step {sent_seq} was sent"
            ),
        }
    }
}

/// Maps an iceoryx2 error of `op` to [`IpcError::Transport`].
pub(crate) fn transport<E>(op: TransportOp) -> impl FnOnce(E) -> IpcError
where
    E: std::error::Error + Send + Sync + 'static,
{
    move |e| IpcError::Transport {
        op,
        cause: TransportCause::Iceoryx2(Box::new(e)),
    }
}

/// The four services of a session, named `thorarena/<session>/…` so concurrent runs never
/// cross.
pub(crate) struct ServiceNames {
    pub hello: ServiceName,
    pub step: ServiceName,
    pub obs_ready: ServiceName,
    pub action_ready: ServiceName,
}

/// Refuses a session name that cannot name a session's services: 1 to 64 characters
/// from `[A-Za-z0-9_.-]`. Both sides hold a name to it before anything is served.
pub fn check_session_name(session: &str) -> Result<(), IpcError> {
    let ok = !session.is_empty()
        && session.len() <= 64
        && session
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-".contains(c));
    if ok {
        Ok(())
    } else {
        Err(IpcError::SessionName(session.into()))
    }
}

pub(crate) fn service_names(session: &str) -> Result<ServiceNames, IpcError> {
    check_session_name(session)?;
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

/// A node in this user's private iceoryx2 root ([`private_root`]) that leaves signals to
/// the host program and first removes what crashed processes left behind.
pub(crate) fn create_node(name: &str) -> Result<Node<ipc::Service>, IpcError> {
    set_log_level_from_env_or(LogLevel::Error);
    let node_name = NodeName::new(name).map_err(transport(TransportOp::NameNode))?;
    let config = private_root::config()?;
    let node = NodeBuilder::new()
        .name(&node_name)
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| IpcError::PrivateRoot {
            path: std::path::PathBuf::from(format!(
                "/dev/shm/{}*",
                private_root::file_prefix()
            )),
            problem: format!(
                "iceoryx2 could not create a node ({e:?}); if no session of yours is running, remove these files and try again"
            ),
        })?;
    private_root::make_shm_files_private();
    node.try_cleanup_dead_nodes();
    Ok(node)
}

/// True while process `pid` exists and is not a zombie. `0` means unknown (always alive).
///
/// For a process this one started (its own pid, not one it was told): a pid a peer reports
/// about itself proves nothing — it may name any live process, and inside a container it
/// names a process of another pid namespace. Peers are watched through `PeerNode`.
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
/// listener; check the peer's liveness every `liveness_every` of blocking. When the side
/// knows when the other is due (its recent turns), it stops blocking
/// `wake_early` before that moment and busy-polls until `wake_early` after it: waking a
/// blocked process costs tens of µs, polling through a short window costs nothing on the
/// critical path.
#[derive(Debug, Clone, Copy)]
pub struct WaitPolicy {
    /// Busy-poll this long before blocking (the low-latency path).
    pub spin: Duration,
    /// While blocked, check that the peer process lives this often.
    pub liveness_every: Duration,
    /// Busy-poll from this long before the other side's earliest expected moment until
    /// as long after its latest (zero: never; only waits that know when the other side
    /// is due use it).
    pub wake_early: Duration,
}

impl Default for WaitPolicy {
    fn default() -> Self {
        Self {
            spin: Duration::from_micros(50),
            liveness_every: Duration::from_millis(2),
            wake_early: Duration::from_micros(150),
        }
    }
}

/// The other side's last few turns (from this side's send to the other's answer), which
/// say when its next answer is due: between the quickest and the slowest
/// ([`WaitPolicy::wake_early`]).
#[derive(Debug, Default)]
pub(crate) struct RecentTurns(Vec<Duration>);

impl RecentTurns {
    /// Turns remembered.
    const KEPT: usize = 8;

    /// Remembers one turn, forgetting the oldest beyond [`Self::KEPT`].
    pub(crate) fn record(&mut self, turn: Duration) {
        if self.0.len() == Self::KEPT {
            self.0.remove(0);
        }
        self.0.push(turn);
    }

    /// When the answer to what was sent at `sent` is due: the earliest and the latest
    /// moment, or `None` before any turn was seen.
    pub(crate) fn due_after(&self, sent: Instant) -> Option<(Instant, Instant)> {
        let first = self.0.iter().min()?;
        let last = self.0.iter().max()?;
        Some((sent + *first, sent + *last))
    }
}

/// What a wait ended with.
pub(crate) enum Waited {
    Ready(Noticed),
    Deadline,
    PeerGone,
}

/// How a wait noticed that the other side had answered: what noticing cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Noticed {
    /// In the busy-poll that starts every wait ([`WaitPolicy::spin`]).
    Spinning,
    /// Busy-polling the window where the answer was due ([`WaitPolicy::wake_early`]).
    InWindow,
    /// After blocking: a kernel wake-up, tens of µs.
    AfterBlocking,
}

/// How the answers seen so far were noticed ([`crate::SimSession::answers_noticed`]):
/// the share noticed by polling says whether the [`WaitPolicy`] suits the policy's
/// timing, since each one noticed after blocking cost a kernel wake-up.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct AnswersNoticed {
    /// In the busy-poll right after the batch went out.
    pub spinning: u64,
    /// Busy-polling the window where the answer was due.
    pub in_window: u64,
    /// After blocking.
    pub after_blocking: u64,
}

impl AnswersNoticed {
    pub(crate) fn count(&mut self, how: Noticed) {
        match how {
            Noticed::Spinning => self.spinning += 1,
            Noticed::InWindow => self.in_window += 1,
            Noticed::AfterBlocking => self.after_blocking += 1,
        }
    }

    /// Every answer counted.
    pub fn total(&self) -> u64 {
        self.spinning + self.in_window + self.after_blocking
    }

    /// The answers counted since `earlier`, a former value of the same session's counts.
    pub fn since(&self, earlier: &Self) -> Self {
        Self {
            spinning: self.spinning - earlier.spinning,
            in_window: self.in_window - earlier.in_window,
            after_blocking: self.after_blocking - earlier.after_blocking,
        }
    }
}

/// Waits until `ready()` holds, the deadline passes, or the peer is gone: its node died
/// (`peer`), or it left the session while alive (`peer_present()` false). Drains the
/// listener after each wake-up (a WaitSet-free loop cannot spin on stale events). `due`:
/// the earliest and latest moment `ready()` is expected to start holding, if known
/// ([`WaitPolicy::wake_early`]).
pub(crate) fn wait_for(
    listener: &Listener<ipc::Service>,
    policy: WaitPolicy,
    deadline: Option<Instant>,
    due: Option<(Instant, Instant)>,
    peer: &PeerNode,
    peer_present: impl Fn() -> bool,
    mut ready: impl FnMut() -> bool,
) -> Result<Waited, IpcError> {
    let start = Instant::now();
    while start.elapsed() < policy.spin {
        if ready() {
            return Ok(Waited::Ready(Noticed::Spinning));
        }
        std::hint::spin_loop();
    }
    // The window around `due` to poll through, if there is one still ahead.
    let early = policy.wake_early;
    let window = due
        .filter(|_| !early.is_zero())
        .map(|(first, last)| (first.checked_sub(early).unwrap_or(first), last + early))
        .filter(|(_, end)| *end > Instant::now());
    let mut blocked = false;
    loop {
        if ready() {
            let how = if blocked {
                Noticed::AfterBlocking
            } else {
                Noticed::Spinning
            };
            return Ok(Waited::Ready(how));
        }
        let now = Instant::now();
        let mut slice = policy.liveness_every;
        if let Some(d) = deadline {
            if now >= d {
                return Ok(Waited::Deadline);
            }
            slice = slice.min(d - now);
        }
        if let Some((from, until)) = window {
            if now >= from && now < until {
                let until = deadline.map_or(until, |d| until.min(d));
                while Instant::now() < until {
                    if ready() {
                        return Ok(Waited::Ready(Noticed::InWindow));
                    }
                    std::hint::spin_loop();
                }
                continue;
            }
            if now < from {
                slice = slice.min(from - now);
            }
        }
        let n = wait_for_event(listener, slice)?;
        blocked = true;
        if n == 0 && !ready() && (!peer_present() || !peer.alive()) {
            return Ok(Waited::PeerGone);
        }
    }
}
