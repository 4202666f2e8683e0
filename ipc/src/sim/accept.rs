//! Accepting a policy: each hello is checked against the session and the run's own
//! conditions, answered with a welcome (or the reason for refusing it), and a welcomed
//! policy is connected once its step server is up.

use super::{ActionMapping, Connection, HelloFactory, InputOffer, PolicyInfo, Refusal};
use super::{SimSession, StepFactory};
use crate::handshake::{from_fixed, to_fixed, DeclaredProfile, Hello, Status, Welcome};
use crate::handshake::{MAX_JOINTS, MAX_REFERENCE_OFFSETS};
use crate::layout::Layout;
use crate::session::{
    transport, IpcError, Message, PeerNode, Port, RecentTurns, TransportOp, NODE_CHECK_EVERY,
};
use crate::PROTOCOL_VERSION;
use iceoryx2::active_request::ActiveRequest;
use iceoryx2::identifiers::UniqueNodeId;
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

type HelloRequest = ActiveRequest<ipc::Service, Hello, (), Welcome, ()>;

/// A welcomed policy has this long to create its step server (its client library does so
/// right after the welcome); one that does not is dropped and the next one accepted.
const STEP_SERVER_WITHIN: Duration = Duration::from_secs(10);

impl SimSession {
    /// Waits for a policy to say hello; refuses mismatched ones (each refusal is passed to
    /// `on_refused` and sent back to that policy) and keeps waiting for a good one. A
    /// policy that dies or stalls between its hello and its step server is reported to
    /// `on_refused` too, and the wait goes on.
    pub fn accept(
        &mut self,
        timeout: Option<Duration>,
        on_refused: impl FnMut(&str),
    ) -> Result<PolicyInfo, IpcError> {
        self.accept_vetted(timeout, |_| Ok(None), on_refused)
    }

    /// [`Self::accept`], and a policy the protocol accepts is also put to `vet` (the run's
    /// own conditions: a name it can use, the policy a resumed run was made with, the
    /// profile it declared): a policy it refuses is told so in its welcome (the
    /// refusal's status and reason), rather than welcomed and then sent away as if the
    /// run were over. A mapping `vet` returns (the declared profile's) replaces the
    /// session's from then on, and is the one the welcome carries.
    pub fn accept_vetted(
        &mut self,
        timeout: Option<Duration>,
        vet: impl FnMut(&PolicyInfo) -> Result<Option<ActionMapping>, Refusal>,
        on_refused: impl FnMut(&str),
    ) -> Result<PolicyInfo, IpcError> {
        self.accept_unless_gone(timeout, vet, on_refused, || false)
    }

    /// [`Self::accept_vetted`], giving up with [`IpcError::PeerGone`] as soon as `gone`
    /// says the policy expected cannot come any more (a process the run started for it
    /// exited), rather than waiting out the timeout; `gone` is asked about every 50 ms.
    pub fn accept_unless_gone(
        &mut self,
        timeout: Option<Duration>,
        mut vet: impl FnMut(&PolicyInfo) -> Result<Option<ActionMapping>, Refusal>,
        mut on_refused: impl FnMut(&str),
        mut gone: impl FnMut() -> bool,
    ) -> Result<PolicyInfo, IpcError> {
        self.connection = None;
        self.node.try_cleanup_dead_nodes();
        let start = Instant::now();
        let mut last_asked = start;
        let timed_out = |what| match timeout {
            Some(t) if start.elapsed() > t => Err(IpcError::Timeout(t, what)),
            _ => Ok(()),
        };
        loop {
            while let Some(request) = self
                .hello
                .receive()
                .map_err(transport(TransportOp::Receive(Message::Hello)))?
            {
                if let Some(info) = self.admit(request, &mut vet, &mut on_refused, &timed_out)? {
                    return Ok(info);
                }
            }
            timed_out("a policy to connect")?;
            if last_asked.elapsed() >= Duration::from_millis(50) {
                if gone() {
                    return Err(IpcError::PeerGone("policy"));
                }
                last_asked = Instant::now();
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Answers one hello: a policy the protocol or `vet` refuses is told why; one that is
    /// welcomed is connected once its step server is up. `None`: not connected (the reason
    /// went to `on_refused`), so the caller goes on waiting for the next hello.
    fn admit(
        &mut self,
        request: HelloRequest,
        vet: &mut impl FnMut(&PolicyInfo) -> Result<Option<ActionMapping>, Refusal>,
        on_refused: &mut impl FnMut(&str),
        timed_out: &impl Fn(&'static str) -> Result<(), IpcError>,
    ) -> Result<Option<PolicyInfo>, IpcError> {
        let hello = *request.payload();
        let (status, message) = self.check(&hello);
        let profile = if status == Status::Ok {
            DeclaredProfile::read_from(&hello)
        } else {
            Ok(None)
        };
        let (status, message) = match profile {
            Err(ref why) => (Status::Profile, format!("declared profile: {why}")),
            Ok(_) => (status, message),
        };
        let refuse = |refusal: Refusal, on_refused: &mut dyn FnMut(&str)| {
            on_refused(&refusal.message);
            let _ = request.send_copy(self.welcome(&hello, refusal.status, &refusal.message));
        };
        if status != Status::Ok {
            refuse(Refusal { status, message }, on_refused);
            return Ok(None);
        }
        let n_refs = hello.n_refs as usize;
        let info = PolicyInfo {
            name: from_fixed(&hello.name),
            pid: hello.pid,
            reference_offsets_s: hello.reference_offsets_s[..n_refs].to_vec(),
            input: Some(from_fixed(&hello.input)).filter(|name| !name.is_empty()),
            profile: profile.ok().flatten(),
        };
        match vet(&info) {
            Err(refusal) => {
                refuse(refusal, on_refused);
                return Ok(None);
            }
            Ok(Some(mapping)) => {
                let n = self.config.joint_names.len();
                if mapping.action_offset_rad.len() != n || mapping.action_scale.len() != n {
                    let message = format!(
                        "the run's action mapping for this profile has {} offsets and {} scales for {n} joints",
                        mapping.action_offset_rad.len(),
                        mapping.action_scale.len()
                    );
                    refuse(
                        Refusal {
                            status: Status::Profile,
                            message,
                        },
                        on_refused,
                    );
                    return Ok(None);
                }
                self.config.control_dt_s = mapping.control_dt_s;
                self.config.action_offset_rad = mapping.action_offset_rad;
                self.config.action_scale = mapping.action_scale;
            }
            Ok(None) => {}
        }
        let mut welcome = self.welcome(&hello, Status::Ok, "");
        // The node that sent this hello, as iceoryx2 registered its port.
        let Some(peer_id) = client_node(&self.hello_service, request.origin()) else {
            on_refused(&format!("policy `{}` left before its welcome", info.name));
            return Ok(None);
        };
        let peer = PeerNode::new(peer_id, self.node.config(), NODE_CHECK_EVERY);
        let layout = Layout {
            n_envs: self.config.n_envs,
            n_joints: self.config.joint_names.len(),
            n_refs,
            n_inputs: welcome.n_inputs as usize,
        };
        let client = self
            .step
            .client_builder()
            .initial_max_slice_len(layout.obs_words())
            .allocation_strategy(AllocationStrategy::Static)
            .create()
            .map_err(transport(TransportOp::CreatePort(Port::StepClient)))?;
        welcome.status = Status::Ok as u32;
        if request.send_copy(welcome).is_err() {
            on_refused(&format!("policy `{}` left before its welcome", info.name));
            return Ok(None);
        }
        drop(request);
        if !self.await_step_server(peer_id, &peer, &info.name, on_refused, timed_out)? {
            drop(client);
            self.node.try_cleanup_dead_nodes();
            return Ok(None);
        }
        self.connection = Some(Connection {
            info: info.clone(),
            peer,
            layout,
            client,
            seq: 0,
            overdue: None,
            next: None,
            recent_round_trips: RecentTurns::default(),
        });
        Ok(Some(info))
    }

    /// The welcome answering `hello` with `status` and `message` (the session's shape and
    /// action mapping, whatever the status: a refused policy learns what it should be).
    fn welcome(&self, hello: &Hello, status: Status, message: &str) -> Welcome {
        Welcome {
            protocol_version: PROTOCOL_VERSION,
            status: status as u32,
            n_joints: self.config.joint_names.len() as u32,
            n_envs: self.config.n_envs as u32,
            joint_names_hash: self.joint_hash,
            control_dt_s: self.config.control_dt_s,
            budget_s: self.config.budget.map_or(0.0, |b| b.as_secs_f64()),
            n_refs: hello.n_refs.min(MAX_REFERENCE_OFFSETS as u32),
            pid: std::process::id(),
            n_inputs: self.offer(hello).map_or(0, |o| o.n_inputs as u32),
            reserved: 0,
            action_offset_rad: fixed_joints(&self.config.action_offset_rad),
            action_scale: fixed_joints(&self.config.action_scale),
            message: to_fixed(message),
        }
    }

    /// Waits for the welcomed policy `name` to create its step server. The policy creates
    /// it after the welcome; this waits for that node's server (not any server: a stale
    /// one of another node is not it). False, and the reason sent to `on_refused`, when the
    /// policy died or did not serve within [`STEP_SERVER_WITHIN`].
    fn await_step_server(
        &self,
        peer_id: UniqueNodeId,
        peer: &PeerNode,
        name: &str,
        on_refused: &mut impl FnMut(&str),
        timed_out: &impl Fn(&'static str) -> Result<(), IpcError>,
    ) -> Result<bool, IpcError> {
        let welcomed = Instant::now();
        loop {
            if has_server_of(&self.step, peer_id) {
                return Ok(true);
            }
            if !peer.alive() {
                on_refused(&format!(
                    "policy `{name}` died after its hello, before serving steps"
                ));
                return Ok(false);
            }
            if welcomed.elapsed() > STEP_SERVER_WITHIN {
                on_refused(&format!(
                    "policy `{name}` did not serve steps within {STEP_SERVER_WITHIN:?} of its welcome"
                ));
                return Ok(false);
            }
            timed_out("the policy's step server")?;
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    fn check(&self, hello: &Hello) -> (Status, String) {
        let n = self.config.joint_names.len() as u32;
        let offsets =
            &hello.reference_offsets_s[..(hello.n_refs as usize).min(MAX_REFERENCE_OFFSETS)];
        if self.connection.is_some() {
            (Status::Busy, "another policy is connected".into())
        } else if hello.protocol_version != PROTOCOL_VERSION {
            let msg = format!(
                "protocol version {} but the simulator speaks {PROTOCOL_VERSION}",
                hello.protocol_version
            );
            (Status::ProtocolVersion, msg)
        } else if hello.n_joints != n {
            let msg = format!("{} joints but the robot has {n}", hello.n_joints);
            (Status::JointCount, msg)
        } else if hello.joint_names_hash != self.joint_hash {
            let msg = format!(
                "joint names hash {:#x} but the robot's canonical order hashes to {:#x}",
                hello.joint_names_hash, self.joint_hash
            );
            (Status::JointNames, msg)
        } else if hello.n_refs as usize > MAX_REFERENCE_OFFSETS
            || hello.n_refs == 0
            || offsets.iter().any(|o| !o.is_finite() || *o < 0.0)
        {
            let msg = format!(
                "reference offsets must be 1 to {MAX_REFERENCE_OFFSETS} finite values >= 0 s"
            );
            (Status::ReferenceOffsets, msg)
        } else {
            self.check_input(hello, offsets)
        }
    }

    /// The offer a hello's input name names (`None` for no name or an unknown one).
    fn offer(&self, hello: &Hello) -> Option<&InputOffer> {
        let name = from_fixed(&hello.input);
        self.config.inputs.iter().find(|o| o.name == name)
    }

    /// Whether the simulator builds the input the hello asks for, from its offsets.
    fn check_input(&self, hello: &Hello, offsets: &[f64]) -> (Status, String) {
        let name = from_fixed(&hello.input);
        if name.is_empty() {
            return (Status::Ok, String::new());
        }
        match self.offer(hello) {
            None => {
                let offered: Vec<String> = self
                    .config
                    .inputs
                    .iter()
                    .map(|o| format!("`{}`", o.name))
                    .collect();
                let msg = format!(
                    "this simulator builds no policy input `{name}` (it offers {})",
                    if offered.is_empty() {
                        "none".to_string()
                    } else {
                        offered.join(", ")
                    }
                );
                (Status::Input, msg)
            }
            Some(offer) if offer.reference_offsets_s.as_slice() != offsets => {
                let msg = format!(
                    "policy input `{name}` is built from reference offsets {:?} s, the policy asks for {offsets:?}",
                    offer.reference_offsets_s
                );
                (Status::Input, msg)
            }
            Some(_) => (Status::Ok, String::new()),
        }
    }
}

/// The node that created client port `client` of the hello service.
fn client_node(
    hello: &HelloFactory,
    client: iceoryx2::identifiers::UniqueClientId,
) -> Option<UniqueNodeId> {
    let mut node = None;
    hello.dynamic_config().list_clients(|c| {
        if c.client_id == client {
            node = Some(c.node_id);
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    });
    node
}

/// True when node `node` has created the step service's server.
fn has_server_of(step: &StepFactory, node: UniqueNodeId) -> bool {
    let mut found = false;
    step.dynamic_config().list_servers(|s| {
        found = s.node_id == node;
        if found {
            CallbackProgression::Stop
        } else {
            CallbackProgression::Continue
        }
    });
    found
}

fn fixed_joints(v: &[f64]) -> [f64; MAX_JOINTS] {
    let mut out = [0.0; MAX_JOINTS];
    out[..v.len()].copy_from_slice(v);
    out
}
