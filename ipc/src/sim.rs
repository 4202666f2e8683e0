//! The simulator's side of a session: create the services, accept a policy, then each
//! control step publish the observation batch and wait (spin, then block) for the actions
//! under an optional deadline.
//!
//! In iceoryx2 terms the simulator is the *client* of the step service (it sends the
//! request, the observation) and the *server* of the hello service, which it creates last,
//! so a policy that finds `hello` finds the other three. A reply after its deadline is a
//! miss, and the late reply is counted when it arrives (a lower bound: iceoryx2 0.10 puts a
//! client's responses on one channel). `step_prepared` loans the next step's batch while
//! the policy computes, so the caller writes into it what is already known.

mod accept;

use crate::handshake::{joint_names_hash, DeclaredProfile, Hello, Status, Welcome, MAX_JOINTS};
use crate::layout::{ActionBatch, Layout, ObsBatchMut, COMMAND_END, COMMAND_STEP};
use crate::session::{
    create_node, service_names, transport, wait_for, AnswersNoticed, Event, IpcError, Message,
    PeerNode, Port, RecentTurns, ServiceNames, TransportCause, TransportOp, WaitPolicy, Waited,
};
use iceoryx2::node::NodeView;
use iceoryx2::pending_response::PendingResponse;
use iceoryx2::port::client::Client;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::*;
use iceoryx2::request_mut::RequestMut;
use iceoryx2::service::port_factory::request_response::PortFactory as RrFactory;
use std::time::{Duration, Instant};

type StepFactory = RrFactory<ipc::Service, [u64], (), [u64], ()>;
type StepClient = Client<ipc::Service, [u64], (), [u64], ()>;
type StepPending = PendingResponse<ipc::Service, [u64], (), [u64], ()>;
type StepRequest = RequestMut<ipc::Service, [u64], (), [u64], ()>;
type HelloFactory = RrFactory<ipc::Service, Hello, (), Welcome, ()>;

/// What the simulator offers.
#[derive(Debug, Clone)]
pub struct SimConfig {
    /// Session name (services are `thorarena/<session>/…`).
    pub session: String,
    /// Environment slots per batch.
    pub n_envs: usize,
    /// Canonical joint order.
    pub joint_names: Vec<String>,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Action mapping of the dynamics profile: target = offset + scale · action, rad.
    pub action_offset_rad: Vec<f64>,
    /// See `action_offset_rad`.
    pub action_scale: Vec<f64>,
    /// Latency budget per step (`None`: lock-step, wait as long as the policy lives).
    pub budget: Option<Duration>,
    /// How to wait for actions.
    pub wait: WaitPolicy,
    /// The network inputs this simulator builds for a policy that asks for one by name.
    pub inputs: Vec<InputOffer>,
}

/// A network input the simulator can build into the batch's policy-input block.
#[derive(Debug, Clone, PartialEq)]
pub struct InputOffer {
    /// Its name, as a policy asks for it in its hello (`twist2`).
    pub name: String,
    /// `f32` values per environment.
    pub n_inputs: usize,
    /// The reference offsets it is built from, s: a policy asking for it must ask for
    /// exactly these.
    pub reference_offsets_s: Vec<f64>,
}

/// The connected policy.
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyInfo {
    /// Its name.
    pub name: String,
    /// The process id it reported: for logs only, never for liveness (it may name any
    /// process, or one of another pid namespace).
    pub pid: u32,
    /// The reference offsets it asked for, s.
    pub reference_offsets_s: Vec<f64>,
    /// The network input it asked the simulator to build, if any ([`InputOffer::name`]).
    pub input: Option<String>,
    /// The dynamics profile it says it was trained under, if it declared one.
    pub profile: Option<DeclaredProfile>,
}

/// The action mapping and control period of the profile a policy runs under, when the
/// run takes them from the policy's declaration rather than the session's configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionMapping {
    /// Control period, s.
    pub control_dt_s: f64,
    /// Target = offset + scale · action, rad, per joint.
    pub action_offset_rad: Vec<f64>,
    /// See `action_offset_rad`.
    pub action_scale: Vec<f64>,
}

/// Why the run refuses a policy the protocol accepts, as the policy hears it.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// [`Status::Rejected`], or [`Status::Profile`] for its declared profile.
    pub status: Status,
    /// Why, and what to do.
    pub message: String,
}

impl From<String> for Refusal {
    /// A refusal of the run's own ([`Status::Rejected`]).
    fn from(message: String) -> Self {
        Self {
            status: Status::Rejected,
            message,
        }
    }
}

/// How one step's wait ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepOutcome {
    /// The actions arrived in time; the closure read them.
    Answered,
    /// The deadline passed first; the request stays in flight so a late reply is counted.
    Missed,
    /// The policy process died or left the session.
    PolicyGone,
}

struct Connection {
    info: PolicyInfo,
    /// The policy's iceoryx2 node: whether it lives.
    peer: PeerNode,
    layout: Layout,
    client: StepClient,
    seq: u64,
    /// The newest request whose deadline passed, watched for a late reply until the next
    /// step.
    ///
    /// All responses of a client share one channel in iceoryx2 0.10: `has_response` on any
    /// pending request sees them all, and `receive` discards those of other requests. So
    /// a late reply is counted either here (its own pending receives it) or when the
    /// current step's `receive` discards it — a lower bound when several arrive at once.
    overdue: Option<StepPending>,
    /// The next step's batch, loaned and handed to `prepare_next` while the policy
    /// computed the last answer ([`SimSession::step_prepared`]).
    next: Option<StepRequest>,
    /// The last answered steps' round trips: when the next answer is due.
    recent_round_trips: RecentTurns,
}

/// The simulator's end of a session.
pub struct SimSession {
    config: SimConfig,
    joint_hash: u64,
    node: Node<ipc::Service>,
    hello: Server<ipc::Service, Hello, (), Welcome, ()>,
    hello_service: HelloFactory,
    step: StepFactory,
    obs_ready: Notifier<ipc::Service>,
    action_ready: Listener<ipc::Service>,
    connection: Option<Connection>,
    late_replies: u64,
    last_round_trip: Duration,
    answers_noticed: AnswersNoticed,
}

impl SimSession {
    /// Creates the session's services (after removing stale ones of crashed runs).
    pub fn create(config: SimConfig) -> Result<Self, IpcError> {
        let names = service_names(&config.session)?;
        let n = config.joint_names.len();
        if n == 0 || n > MAX_JOINTS {
            return Err(IpcError::Config(format!(
                "{n} joints: the protocol carries 1 to {MAX_JOINTS}"
            )));
        }
        if config.action_offset_rad.len() != n || config.action_scale.len() != n {
            return Err(IpcError::Config(format!(
                "action mapping has {} offsets and {} scales for {n} joints",
                config.action_offset_rad.len(),
                config.action_scale.len()
            )));
        }
        if config.n_envs == 0 {
            return Err(IpcError::Config(
                "a session needs at least one environment slot".into(),
            ));
        }
        let node = create_node(&format!("thorarena-sim-{}", config.session))?;
        // A policy process of the previous run on this session may still hold its ports
        // while it exits (`serve` makes the session again at once): its services are then
        // still there. Only a live simulator makes the session another run's; lingering
        // policy processes are waited for.
        let deadline = Instant::now() + LINGERING_POLICY_GRACE;
        let (step, obs_ready, action_ready, hello_service, hello) = loop {
            match create_services(&node, &names, &config.session) {
                Err(IpcError::SessionInUse(session))
                    if Instant::now() < deadline && !another_simulator_lives(&node, &session) =>
                {
                    std::thread::sleep(Duration::from_millis(20));
                }
                other => break other?,
            }
        };
        Ok(Self {
            joint_hash: joint_names_hash(&config.joint_names),
            config,
            node,
            hello,
            hello_service,
            step,
            obs_ready,
            action_ready,
            connection: None,
            late_replies: 0,
            last_round_trip: Duration::ZERO,
            answers_noticed: AnswersNoticed::default(),
        })
    }

    /// The session's configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// The connected policy, if any.
    pub fn policy(&self) -> Option<&PolicyInfo> {
        self.connection.as_ref().map(|c| &c.info)
    }

    /// The batch layout of the connected policy.
    pub fn layout(&self) -> Option<Layout> {
        self.connection.as_ref().map(|c| c.layout)
    }

    /// Observation published to actions received (or to giving up) in the last `step`.
    pub fn last_round_trip(&self) -> Duration {
        self.last_round_trip
    }

    /// Replies that arrived after their deadline, so far.
    pub fn late_replies(&self) -> u64 {
        self.late_replies
    }

    /// How the answers so far were noticed: while polling, or after blocking.
    pub fn answers_noticed(&self) -> AnswersNoticed {
        self.answers_noticed
    }

    /// One control step: `fill` writes the observation batch into shared memory, the batch
    /// is published, and the actions are awaited for `budget` from the moment of
    /// publishing (`None`: lock-step, as long as the policy lives) and handed to `read`.
    pub fn step(
        &mut self,
        fill: impl FnOnce(&mut ObsBatchMut),
        budget: Option<Duration>,
        read: impl FnOnce(&ActionBatch),
    ) -> Result<StepOutcome, IpcError> {
        self.step_prepared(|batch, _| fill(batch), None, budget, read)
    }

    /// [`Self::step`], with work for the next step done while the policy computes this
    /// one's answer: given `prepare_next`, once the batch is published the next step's
    /// batch is loaned (which zeroes it) and handed to it, and its writes stay there; the
    /// next step's `fill` gets that batch with `prepared` true (false when it had to be
    /// loaned then, as on the first step). What can be written before the step's own
    /// state is known — a network input's history — leaves the step's critical path that
    /// way. The round trip is timed from publishing, so loaning and preparing show in it
    /// when the policy answers faster than they take (an echo policy at 64 slots): only
    /// callers with something to prepare pass `Some`.
    pub fn step_prepared(
        &mut self,
        fill: impl FnOnce(&mut ObsBatchMut, bool),
        prepare_next: Option<&mut dyn FnMut(&mut ObsBatchMut)>,
        budget: Option<Duration>,
        read: impl FnOnce(&ActionBatch),
    ) -> Result<StepOutcome, IpcError> {
        let conn = self
            .connection
            .as_mut()
            .ok_or(IpcError::PeerGone("policy"))?;
        // A late reply to the overdue request that is already here; if it is not, the
        // request stays watched through this step's wait (checked again below), so a
        // reply still on its way when the next batch goes out is counted, not lost.
        if conn
            .overdue
            .as_ref()
            .is_some_and(|old| matches!(old.receive(), Ok(Some(_))))
        {
            self.late_replies += 1;
            conn.overdue = None;
        }
        conn.seq += 1;
        let (mut request, prepared) = match conn.next.take() {
            Some(request) => (request, true),
            None => (
                conn.client
                    .loan_slice(conn.layout.obs_words())
                    .map_err(transport(TransportOp::Loan(Message::Observations)))?,
                false,
            ),
        };
        {
            let bytes: &mut [u8] = bytemuck::cast_slice_mut(request.payload_mut());
            let mut batch = ObsBatchMut::new(conn.layout, bytes, COMMAND_STEP, conn.seq);
            fill(&mut batch, prepared);
            batch.count_active();
        }
        let sent = Instant::now();
        let pending = request
            .send()
            .map_err(transport(TransportOp::Send(Message::Observations)))?;
        self.obs_ready
            .notify()
            .map_err(transport(TransportOp::Notify(Event::ObsReady)))?;
        // Not loanable now (every chunk in flight): the next step loans it, unprepared,
        // and reports the error if there is still none.
        let next = prepare_next.and_then(|prepare| {
            let mut next = conn.client.loan_slice(conn.layout.obs_words()).ok()?;
            let bytes: &mut [u8] = bytemuck::cast_slice_mut(next.payload_mut());
            prepare(&mut ObsBatchMut::new(
                conn.layout,
                bytes,
                COMMAND_STEP,
                conn.seq + 1,
            ));
            Some(next)
        });
        conn.next = next;
        let deadline = budget.map(|b| sent + b);
        let step_service = &self.step;
        let mut response = None;
        let mut receive_error = None;
        let mut discarded = 0;
        let due = conn.recent_round_trips.due_after(sent);
        let waited = wait_for(
            &self.action_ready,
            self.config.wait,
            deadline,
            due,
            &conn.peer,
            // A policy that closed its session but lives on has no step server any more.
            || step_service.dynamic_config().number_of_servers() > 0,
            || {
                if response.is_none() && receive_error.is_none() && pending.has_response() {
                    match pending.receive() {
                        Ok(Some(r)) => response = Some(r),
                        // What was queued answered an earlier step: a late reply.
                        Ok(None) => discarded += 1,
                        Err(e) => receive_error = Some(e),
                    }
                }
                response.is_some() || receive_error.is_some()
            },
        )?;
        self.last_round_trip = sent.elapsed();
        if let Waited::Ready(how) = waited {
            self.answers_noticed.count(how);
            conn.recent_round_trips.record(self.last_round_trip);
        }
        self.late_replies += discarded;
        if let Some(old) = conn.overdue.take() {
            if matches!(old.receive(), Ok(Some(_))) {
                self.late_replies += 1;
            }
        }
        if let Some(e) = receive_error {
            return Err(transport(TransportOp::Receive(Message::Actions))(e));
        }
        match waited {
            Waited::Ready(_) => {
                let response = response.expect("ready means received");
                let bytes: &[u8] = bytemuck::cast_slice(response.payload());
                let batch = ActionBatch::new(conn.layout, bytes)?;
                if batch.header().seq != conn.seq {
                    return Err(IpcError::Transport {
                        op: TransportOp::Receive(Message::Actions),
                        cause: TransportCause::OutOfSequence {
                            answered_seq: batch.header().seq,
                            sent_seq: conn.seq,
                        },
                    });
                }
                read(&batch);
                Ok(StepOutcome::Answered)
            }
            Waited::Deadline => {
                if conn.peer.alive() {
                    conn.overdue = Some(pending);
                    Ok(StepOutcome::Missed)
                } else {
                    self.drop_policy();
                    Ok(StepOutcome::PolicyGone)
                }
            }
            Waited::PeerGone => {
                self.drop_policy();
                Ok(StepOutcome::PolicyGone)
            }
        }
    }

    /// Forgets the connected policy and removes what a crashed one left behind.
    pub fn drop_policy(&mut self) {
        self.connection = None;
        self.node.try_cleanup_dead_nodes();
    }

    /// Tells the policy the run is over (it returns from its loop) and disconnects.
    pub fn end(&mut self) {
        if let Some(conn) = self.connection.as_mut() {
            if let Some(old) = conn.overdue.take() {
                if matches!(old.receive(), Ok(Some(_))) {
                    self.late_replies += 1;
                }
            }
            let request = match conn.next.take() {
                Some(request) => Ok(request),
                None => conn.client.loan_slice(conn.layout.obs_words()),
            };
            if let Ok(mut request) = request {
                let bytes: &mut [u8] = bytemuck::cast_slice_mut(request.payload_mut());
                ObsBatchMut::new(conn.layout, bytes, COMMAND_END, conn.seq + 1);
                if let Ok(pending) = request.send() {
                    let _ = self.obs_ready.notify();
                    // Give the policy a moment to see it before the services go away.
                    let until = Instant::now() + Duration::from_millis(200);
                    while pending.is_connected() && Instant::now() < until && conn.peer.alive() {
                        std::thread::sleep(Duration::from_micros(200));
                    }
                }
            }
        }
        self.connection = None;
    }
}

/// How long a new session waits for the policy processes of an earlier run on the same
/// session name to let go of its services.
const LINGERING_POLICY_GRACE: Duration = Duration::from_secs(10);

/// The session's services and the simulator's ports on them.
type Services = (
    StepFactory,
    Notifier<ipc::Service>,
    Listener<ipc::Service>,
    HelloFactory,
    Server<ipc::Service, Hello, (), Welcome, ()>,
);

/// Creates `names`' four services and this side's ports, or says why not.
fn create_services(
    node: &Node<ipc::Service>,
    names: &ServiceNames,
    session: &str,
) -> Result<Services, IpcError> {
    let step = node
        .service_builder(&names.step)
        .request_response::<[u64], [u64]>()
        .max_servers(1)
        .max_clients(1)
        // The current request, the overdue one, and the end-of-run notice.
        .max_active_requests_per_client(3)
        .max_response_buffer_size(2)
        // The batch being filled, and the next one, prepared while the policy computes.
        .max_loaned_requests(2)
        .max_borrowed_responses_per_pending_response(1)
        .enable_fire_and_forget_requests(true)
        .create()
        .map_err(|e| service_creation_failed(session, e))?;
    let obs_ready = node
        .service_builder(&names.obs_ready)
        .event()
        .max_notifiers(2)
        .max_listeners(4)
        .create()
        .map_err(|e| service_creation_failed(session, e))?
        .notifier_builder()
        .create()
        .map_err(transport(TransportOp::CreatePort(Port::ObsReadyNotifier)))?;
    let action_ready = node
        .service_builder(&names.action_ready)
        .event()
        .max_notifiers(4)
        .max_listeners(2)
        .create()
        .map_err(|e| service_creation_failed(session, e))?
        .listener_builder()
        .create()
        .map_err(transport(TransportOp::CreatePort(
            Port::ActionReadyListener,
        )))?;
    // Last: a policy that finds `hello` finds the other three.
    let hello_service = node
        .service_builder(&names.hello)
        .request_response::<Hello, Welcome>()
        .max_servers(1)
        .max_clients(8)
        .max_active_requests_per_client(1)
        .create()
        .map_err(|e| service_creation_failed(session, e))?;
    let hello = hello_service
        .server_builder()
        .create()
        .map_err(transport(TransportOp::CreatePort(Port::HelloServer)))?;
    Ok((step, obs_ready, action_ready, hello_service, hello))
}

/// Whether a simulator other than this node serves `session` (a live node of its name).
fn another_simulator_lives(node: &Node<ipc::Service>, session: &str) -> bool {
    let name = format!("thorarena-sim-{session}");
    let own = node.id().value();
    let mut found = false;
    let _ = Node::<ipc::Service>::list(node.config(), |state| {
        if let NodeState::Alive(view) = &state {
            if view.id().value() != own
                && view
                    .details()
                    .as_ref()
                    .is_some_and(|d| d.name().as_str() == name)
            {
                found = true;
            }
        }
        CallbackProgression::Continue
    });
    found
}

/// A service-creation error of iceoryx2 that may say "another live node owns this
/// service" (its typed `AlreadyExists`), which is a session in use, not a transport fault.
trait CreateError: std::error::Error + Send + Sync + 'static {
    fn already_exists(&self) -> bool;
}

/// The error of creating one of `session`'s services: in use by another live run, or
/// iceoryx2 failed.
fn service_creation_failed(session: &str, e: impl CreateError) -> IpcError {
    if e.already_exists() {
        IpcError::SessionInUse(session.into())
    } else {
        transport(TransportOp::CreateServices)(e)
    }
}

impl CreateError for iceoryx2::service::builder::request_response::RequestResponseCreateError {
    fn already_exists(&self) -> bool {
        matches!(self, Self::AlreadyExists)
    }
}

impl CreateError for iceoryx2::service::builder::event::EventCreateError {
    fn already_exists(&self) -> bool {
        matches!(self, Self::AlreadyExists)
    }
}
