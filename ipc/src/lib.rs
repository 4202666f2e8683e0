//! `thorarena-ipc`: ThorArena's zero-copy policy protocol over iceoryx2.
//!
//! A session joins one simulator run and one policy process. Each control step the
//! simulator writes every environment's observation into one shared-memory block (the
//! request of the `step` request–response service), wakes the policy through the
//! `obs_ready` event, and waits — a short spin, then a blocking wait — for the action block
//! (the response) and the `action_ready` event. A handshake on the `hello` service fixes the
//! batch shape first. Services are named `thorarena/<session>/{hello,step,obs_ready,action_ready}`.
//!
//! This crate knows nothing of the simulator core (`thorarena`): it moves bytes with a
//! documented layout ([`layout`]), so C, C++ and Python clients can implement it too.
#![warn(missing_docs)]

pub mod client;
pub mod describe;
pub mod ffi;
pub mod handshake;
pub mod layout;
pub mod session;
pub mod sim;

pub use client::{Next, PolicyClient, PolicyConfig, PolicyStep, SessionInfo};
pub use handshake::{
    joint_names_hash, DeclaredProfile, Hello, ProfileContent, ProfileKind, Status, Welcome,
    INPUT_NAME_BYTES, MAX_REFERENCE_OFFSETS, PROFILE_NAME_BYTES,
};
pub use layout::{
    ActionBatch, ActionBatchMut, BatchHeader, EnvHeader, EnvObs, EnvObsMut, Layout, LayoutError,
    ObsBatch, ObsBatchMut, FLAG_ACTIVE, FLAG_PREVIOUS_TERMINATED, FLAG_RESET,
};
pub use session::{
    check_session_name, process_alive, AnswersNoticed, Event, IpcError, Message, Port,
    TransportCause, TransportOp, WaitPolicy,
};
pub use sim::{ActionMapping, InputOffer, PolicyInfo, Refusal, SimConfig, SimSession, StepOutcome};

/// Version of the wire protocol; bumped on any change of the messages or the layout.
pub const PROTOCOL_VERSION: u32 = 4;
