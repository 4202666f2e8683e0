//! The policy's side of a session (the "client" of a ThorArena run): say hello, then each
//! control step take the observation batch straight from shared memory and write the
//! actions straight into the loaned response.
//!
//! In iceoryx2 terms the policy is the *server* of the step service (it answers the
//! simulator's requests) and a *client* of the hello service.

use crate::handshake::{
    from_fixed, joint_names_hash, to_fixed, DeclaredProfile, Hello, Status, Welcome,
    INPUT_NAME_BYTES, MAX_JOINTS, MAX_REFERENCE_OFFSETS,
};
use crate::layout::{ActionBatchMut, Layout, ObsBatch, COMMAND_END};
use crate::session::{
    create_node, service_names, transport, wait_for, Event, IpcError, Message, PeerNode, Port,
    RecentTurns, ServiceNames, TransportOp, WaitPolicy, Waited, NODE_CHECK_EVERY,
};
use crate::PROTOCOL_VERSION;
use iceoryx2::active_request::ActiveRequest;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::port::client::Client;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::*;
use iceoryx2::response_mut::ResponseMut;
use iceoryx2::service::port_factory::event::PortFactory as EventPortFactory;
use iceoryx2::service::port_factory::request_response::PortFactory as RrFactory;
use std::cell::Cell;
use std::time::{Duration, Instant};

type StepServer = Server<ipc::Service, [u64], (), [u64], ()>;
type StepFactory = RrFactory<ipc::Service, [u64], (), [u64], ()>;
type HelloFactory = RrFactory<ipc::Service, Hello, (), Welcome, ()>;
type HelloClient = Client<ipc::Service, Hello, (), Welcome, ()>;
type EventFactory = EventPortFactory<ipc::Service>;
type StepRequest = ActiveRequest<ipc::Service, [u64], (), [u64], ()>;
type StepResponse = ResponseMut<ipc::Service, [u64], ()>;

/// What the policy declares when it connects.
#[derive(Debug, Clone)]
pub struct PolicyConfig {
    /// Session to join.
    pub session: String,
    /// Name recorded in the results.
    pub name: String,
    /// The joint order the policy assumes (checked against the robot's by hash).
    pub joint_names: Vec<String>,
    /// Times ahead of each step at which the policy wants reference frames, s.
    pub reference_offsets_s: Vec<f64>,
    /// How to wait for observations.
    pub wait: WaitPolicy,
    /// Protocol version to announce (tests set a wrong one on purpose).
    pub protocol_version: u32,
    /// Process id to announce: this process's (tests announce another on purpose; the
    /// simulator logs it and never trusts it).
    pub announced_pid: u32,
    /// A network input for the simulator to build into each batch's policy-input block
    /// (`twist2`), or empty for none ([`crate::Hello::input`]).
    pub input: String,
    /// The dynamics profile the policy was trained under (`None`: the run must name
    /// one, or it refuses the policy).
    pub profile: Option<DeclaredProfile>,
}

impl PolicyConfig {
    /// A configuration with the default wait policy and this build's protocol version.
    pub fn new(
        session: &str,
        name: &str,
        joint_names: Vec<String>,
        reference_offsets_s: Vec<f64>,
    ) -> Self {
        Self {
            session: session.into(),
            name: name.into(),
            joint_names,
            reference_offsets_s,
            wait: WaitPolicy::default(),
            protocol_version: PROTOCOL_VERSION,
            announced_pid: std::process::id(),
            input: String::new(),
            profile: None,
        }
    }
}

/// The session as the simulator described it.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionInfo {
    /// Batch layout (environment slots, joints, reference frames).
    pub layout: Layout,
    /// Control period, s.
    pub control_dt_s: f64,
    /// Latency budget per step (`None`: lock-step).
    pub budget: Option<Duration>,
    /// The process id the simulator reported (for logs; liveness is watched through its
    /// iceoryx2 node).
    pub simulator_pid: u32,
    /// How an action becomes a PD target: target = offset + scale · action, rad.
    pub action_offset_rad: Vec<f64>,
    /// See `action_offset_rad`.
    pub action_scale: Vec<f64>,
}

/// What waiting for the next step gave.
pub enum Next {
    /// A batch to answer.
    Step(Box<PolicyStep>),
    /// The run is over.
    End,
    /// Nothing arrived within the timeout.
    Timeout,
}

/// A connected policy.
pub struct PolicyClient {
    info: SessionInfo,
    server: StepServer,
    obs_ready: Listener<ipc::Service>,
    action_ready: Notifier<ipc::Service>,
    wait: WaitPolicy,
    /// When the last answer went out: the simulator's next batch is due a turn later.
    answered_at: Cell<Option<Instant>>,
    /// The simulator's last turns (from an answer to the next batch): physics, then
    /// building the batch.
    recent_turns: RecentTurns,
    /// The simulator's iceoryx2 node: whether it lives.
    simulator: PeerNode,
    // Declared last: ports above drop before their node.
    _node: Node<ipc::Service>,
}

impl PolicyClient {
    /// Joins `config.session`, waiting up to `timeout` for the simulator to serve it.
    pub fn connect(config: &PolicyConfig, timeout: Duration) -> Result<Self, IpcError> {
        let names = service_names(&config.session)?;
        if config.reference_offsets_s.len() > MAX_REFERENCE_OFFSETS {
            return Err(IpcError::Refused {
                status: Status::ReferenceOffsets,
                message: format!("at most {MAX_REFERENCE_OFFSETS} reference offsets"),
            });
        }
        if config.input.len() >= INPUT_NAME_BYTES {
            return Err(IpcError::Refused {
                status: Status::Input,
                message: format!(
                    "policy input name {:?} is longer than {} bytes",
                    config.input,
                    INPUT_NAME_BYTES - 1
                ),
            });
        }
        let node = create_node(&format!("thorarena-policy-{}", config.session))?;
        let start = Instant::now();
        let services = open_services(&node, &names, &config.session, start, timeout)?;
        refuse_if_served(&services.step, &config.session)?;
        let obs_ready = services
            .obs_ready
            .listener_builder()
            .create()
            .map_err(transport(TransportOp::CreatePort(Port::ObsReadyListener)))?;
        let action_ready = services
            .action_ready
            .notifier_builder()
            .create()
            .map_err(transport(TransportOp::CreatePort(
                Port::ActionReadyNotifier,
            )))?;
        let hello_client = services
            .hello
            .client_builder()
            .create()
            .map_err(transport(TransportOp::CreatePort(Port::HelloClient)))?;
        let welcome = say_hello(&hello_client, &services.step, config, start, timeout)?;
        let layout = Layout {
            n_envs: welcome.n_envs as usize,
            n_joints: welcome.n_joints as usize,
            n_refs: welcome.n_refs as usize,
            n_inputs: welcome.n_inputs as usize,
        };
        let simulator_node = hello_server_node(&services.hello)?;
        let server = services
            .step
            .server_builder()
            .initial_max_slice_len(layout.action_words())
            .allocation_strategy(AllocationStrategy::Static)
            .create()
            .map_err(transport(TransportOp::CreatePort(Port::StepServer)))?;
        Ok(Self {
            info: session_info(&welcome, layout),
            server,
            obs_ready,
            action_ready,
            wait: config.wait,
            answered_at: Cell::new(None),
            recent_turns: RecentTurns::default(),
            simulator: PeerNode::new(simulator_node, node.config(), NODE_CHECK_EVERY),
            _node: node,
        })
    }

    /// The session's shape.
    pub fn info(&self) -> &SessionInfo {
        &self.info
    }

    /// Waits for the next observation batch. Only the newest batch is answered: a batch
    /// that was overtaken (the policy fell behind its deadline) is dropped unanswered.
    pub fn next_step(&mut self, timeout: Option<Duration>) -> Result<Next, IpcError> {
        let deadline = timeout.map(|t| Instant::now() + t);
        let answered_at = self.answered_at.take();
        let due = answered_at.and_then(|at| self.recent_turns.due_after(at));
        let waited = wait_for(
            &self.obs_ready,
            self.wait,
            deadline,
            due,
            &self.simulator,
            || true,
            || self.server.has_requests().unwrap_or(true),
        )?;
        match waited {
            Waited::Deadline => return Ok(Next::Timeout),
            Waited::PeerGone => return Err(IpcError::PeerGone("simulator")),
            Waited::Ready(_) => {}
        }
        if let Some(at) = answered_at {
            self.recent_turns.record(at.elapsed());
        }
        let mut newest = None;
        while let Some(r) = self
            .server
            .receive()
            .map_err(transport(TransportOp::Receive(Message::Observations)))?
        {
            newest = Some(r);
        }
        let Some(request) = newest else {
            return Ok(Next::Timeout);
        };
        let layout = self.info.layout;
        let header = ObsBatch::new(layout, bytemuck::cast_slice(request.payload()))?.header();
        if header.command == COMMAND_END {
            return Ok(Next::End);
        }
        Ok(Next::Step(Box::new(PolicyStep {
            request,
            response: None,
            layout,
            seq: header.seq,
        })))
    }

    /// The common loop: answer every step with `act(observations, actions)` until the run
    /// ends. Returns the number of steps answered.
    pub fn run(
        &mut self,
        mut act: impl FnMut(&ObsBatch, &mut ActionBatchMut),
    ) -> Result<u64, IpcError> {
        let mut steps = 0;
        loop {
            match self.next_step(None)? {
                Next::Step(mut step) => {
                    step.answer(&mut act)?;
                    step.send(self)?;
                    steps += 1;
                }
                Next::End => return Ok(steps),
                Next::Timeout => {
                    if !self.simulator.alive() {
                        return Err(IpcError::PeerGone("simulator"));
                    }
                }
            }
        }
    }
}

/// The four services of a session, opened from the policy's side.
struct Services {
    hello: HelloFactory,
    step: StepFactory,
    obs_ready: EventFactory,
    action_ready: EventFactory,
}

/// Opens the session's four services, retrying until `timeout` (from `start`) passes.
///
/// The simulator creates `hello` last, but a policy may also catch a session that is being
/// torn down: all four must open, or none is used.
fn open_services(
    node: &Node<ipc::Service>,
    names: &ServiceNames,
    session: &str,
    start: Instant,
    timeout: Duration,
) -> Result<Services, IpcError> {
    loop {
        match try_open_services(node, names) {
            Some(services) => return Ok(services),
            None if start.elapsed() < timeout => std::thread::sleep(Duration::from_millis(5)),
            None => return Err(IpcError::NoSession(session.into())),
        }
    }
}

/// One attempt of [`open_services`]: `None` unless all four services open.
fn try_open_services(node: &Node<ipc::Service>, names: &ServiceNames) -> Option<Services> {
    let hello = node
        .service_builder(&names.hello)
        .request_response::<Hello, Welcome>()
        .open()
        .ok()?;
    let step = node
        .service_builder(&names.step)
        .request_response::<[u64], [u64]>()
        .open()
        .ok()?;
    let obs_ready = node.service_builder(&names.obs_ready).event().open().ok()?;
    let action_ready = node
        .service_builder(&names.action_ready)
        .event()
        .open()
        .ok()?;
    Some(Services {
        hello,
        step,
        obs_ready,
        action_ready,
    })
}

/// Refuses at once a session whose steps another policy already serves, rather than wait
/// for a welcome the simulator cannot give in the middle of a run.
fn refuse_if_served(step: &StepFactory, session: &str) -> Result<(), IpcError> {
    if step.dynamic_config().number_of_servers() > 0 {
        return Err(IpcError::Refused {
            status: Status::Busy,
            message: format!(
                "session {session:?} is in use: another policy is connected (a session serves one policy at a time)"
            ),
        });
    }
    Ok(())
}

/// The handshake: sends the policy's hello through `client` and waits until `timeout`
/// (from `start`) for the welcome; a welcome that refuses is an [`IpcError::Refused`].
/// Another policy that starts serving `step` meanwhile won a race for the session: this
/// one is refused as busy at once rather than left waiting for its whole timeout.
fn say_hello(
    client: &HelloClient,
    step: &StepFactory,
    config: &PolicyConfig,
    start: Instant,
    timeout: Duration,
) -> Result<Welcome, IpcError> {
    let mut offsets = [0.0; MAX_REFERENCE_OFFSETS];
    offsets[..config.reference_offsets_s.len()].copy_from_slice(&config.reference_offsets_s);
    let hello = Hello {
        protocol_version: config.protocol_version,
        n_joints: config.joint_names.len() as u32,
        joint_names_hash: joint_names_hash(&config.joint_names),
        pid: config.announced_pid,
        n_refs: config.reference_offsets_s.len() as u32,
        reference_offsets_s: offsets,
        name: to_fixed(&config.name),
        input: to_fixed(&config.input),
        ..Hello::blank()
    };
    let mut hello = hello;
    DeclaredProfile::write_into(config.profile.as_ref(), &mut hello).map_err(|message| {
        IpcError::Refused {
            status: Status::Profile,
            message,
        }
    })?;
    let pending = client
        .send_copy(hello)
        .map_err(transport(TransportOp::Send(Message::Hello)))?;
    let welcome = loop {
        if let Some(r) = pending
            .receive()
            .map_err(transport(TransportOp::Receive(Message::Welcome)))?
        {
            break *r.payload();
        }
        if start.elapsed() > timeout {
            return Err(IpcError::Timeout(timeout, "the simulator's welcome"));
        }
        refuse_if_served(step, &config.session)?;
        std::thread::sleep(Duration::from_micros(200));
    };
    let status = Status::from_u32(welcome.status).unwrap_or(Status::ProtocolVersion);
    if status != Status::Ok {
        return Err(IpcError::Refused {
            status,
            message: from_fixed(&welcome.message),
        });
    }
    Ok(welcome)
}

/// The simulator's node: the one serving `hello` (it welcomed us).
fn hello_server_node(hello: &HelloFactory) -> Result<UniqueNodeId, IpcError> {
    let mut simulator_node = None;
    hello.dynamic_config().list_servers(|s| {
        simulator_node = Some(s.node_id);
        CallbackProgression::Stop
    });
    simulator_node.ok_or(IpcError::PeerGone("simulator"))
}

/// The session as the welcome describes it.
fn session_info(welcome: &Welcome, layout: Layout) -> SessionInfo {
    SessionInfo {
        layout,
        control_dt_s: welcome.control_dt_s,
        budget: (welcome.budget_s > 0.0).then(|| Duration::from_secs_f64(welcome.budget_s)),
        simulator_pid: welcome.pid,
        action_offset_rad: welcome.action_offset_rad[..layout.n_joints.min(MAX_JOINTS)].to_vec(),
        action_scale: welcome.action_scale[..layout.n_joints.min(MAX_JOINTS)].to_vec(),
    }
}

/// One observation batch being answered.
pub struct PolicyStep {
    request: StepRequest,
    response: Option<StepResponse>,
    layout: Layout,
    seq: u64,
}

impl PolicyStep {
    /// The observations, in shared memory.
    pub fn observations(&self) -> ObsBatch<'_> {
        ObsBatch::new(self.layout, bytemuck::cast_slice(self.request.payload()))
            .expect("checked when received")
    }

    /// The action slots, in shared memory (loaned on first use, zeroed).
    pub fn actions(&mut self) -> Result<ActionBatchMut<'_>, IpcError> {
        if self.response.is_none() {
            let response = self
                .request
                .loan_slice(self.layout.action_words())
                .map_err(transport(TransportOp::Loan(Message::Actions)))?;
            self.response = Some(response);
        }
        let response = self.response.as_mut().expect("loaned above");
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(response.payload_mut());
        Ok(ActionBatchMut::new(self.layout, bytes, self.seq))
    }

    /// Calls `act` with the observations and the action slots.
    pub fn answer(
        &mut self,
        act: &mut impl FnMut(&ObsBatch, &mut ActionBatchMut),
    ) -> Result<(), IpcError> {
        if self.response.is_none() {
            self.actions()?;
        }
        let obs = ObsBatch::new(self.layout, bytemuck::cast_slice(self.request.payload()))?;
        let response = self.response.as_mut().expect("loaned above");
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(response.payload_mut());
        let mut actions = ActionBatchMut::new(self.layout, bytes, self.seq);
        act(&obs, &mut actions);
        Ok(())
    }

    /// Sends the actions and wakes the simulator.
    pub fn send(mut self, client: &PolicyClient) -> Result<(), IpcError> {
        if self.response.is_none() {
            self.actions()?;
        }
        let response = self.response.take().expect("loaned above");
        // A simulator that gave up on this step has dropped it: nothing to deliver.
        let _ = response.send();
        client
            .action_ready
            .notify()
            .map_err(transport(TransportOp::Notify(Event::ActionReady)))?;
        client.answered_at.set(Some(Instant::now()));
        Ok(())
    }
}
