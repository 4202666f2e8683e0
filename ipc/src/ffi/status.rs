//! The C ABI's status codes: one per outcome of a call, the handshake's refusals under
//! their wire numbers.

use crate::handshake::Status;
use crate::session::IpcError;
use std::ffi::CStr;

/// What a call gave: success, the two non-error outcomes of waiting (`End`, `Timeout`),
/// or why it failed. Refusals carry the simulator's handshake status with the same number
/// (`Welcome::status`); every other failure is one `IpcError` variant.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThorarenaStatus {
    /// Success.
    Ok = 0,
    /// Refused: the simulator speaks another protocol version.
    RefusedProtocolVersion = 1,
    /// Refused: the robot has another number of joints.
    RefusedJointCount = 2,
    /// Refused: same joint count, different joint names or order.
    RefusedJointNames = 3,
    /// Refused: too many reference offsets, none, or one negative or not finite.
    RefusedReferenceOffsets = 4,
    /// Refused: another policy is connected.
    RefusedBusy = 5,
    /// Refused: the run refused this policy (its name, or a resumed run that was another
    /// policy's); the message says why.
    RefusedByRun = 6,
    /// Refused: the simulator builds no policy input of the name asked for (or not from
    /// the reference offsets asked for).
    RefusedInput = 7,
    /// Refused: the profile the policy declared is unknown, malformed or not the run's,
    /// or it declared none and the run names none (the message says what to do).
    RefusedProfile = 8,
    /// The run is over: leave the loop and close the client.
    End = 10,
    /// Nothing arrived within the timeout (waiting for a step, or for the welcome).
    Timeout = 11,
    /// No simulator serves this session.
    NoSession = 20,
    /// The session name cannot name iceoryx2 services (`[A-Za-z0-9_.-]{1,64}`).
    SessionName = 21,
    /// Another live run owns the session (simulator side).
    SessionInUse = 22,
    /// The simulator was configured with something the protocol cannot carry.
    Config = 23,
    /// The simulator process died or left.
    SimulatorGone = 24,
    /// A received batch does not match the session's layout.
    Layout = 25,
    /// iceoryx2 failed (see the message).
    Transport = 26,
    /// A NULL pointer, a string that is not UTF-8, an unknown field name, a count out of range.
    InvalidArgument = 30,
    /// Calls out of order: `thorarena_next_step` while a step is held (call
    /// `thorarena_send` first), or `thorarena_send` with no step held.
    CallOrder = 31,
    /// The client was used on another thread than the one that connected it (its
    /// iceoryx2 ports are bound to that thread).
    WrongThread = 32,
    /// A bug in this library (a Rust panic, caught at the boundary).
    Panic = 40,
}

impl ThorarenaStatus {
    /// The status of a refused handshake (the same number as on the wire).
    pub fn from_refusal(status: Status) -> Self {
        match status {
            Status::Ok => Self::Ok,
            Status::ProtocolVersion => Self::RefusedProtocolVersion,
            Status::JointCount => Self::RefusedJointCount,
            Status::JointNames => Self::RefusedJointNames,
            Status::ReferenceOffsets => Self::RefusedReferenceOffsets,
            Status::Busy => Self::RefusedBusy,
            Status::Rejected => Self::RefusedByRun,
            Status::Input => Self::RefusedInput,
            Status::Profile => Self::RefusedProfile,
        }
    }

    /// The status of a transport error.
    pub fn from_error(error: &IpcError) -> Self {
        match error {
            IpcError::Config(_) => Self::Config,
            IpcError::SessionName(_) => Self::SessionName,
            IpcError::SessionInUse(_) => Self::SessionInUse,
            IpcError::NoSession(_) => Self::NoSession,
            IpcError::Refused { status, .. } => Self::from_refusal(*status),
            IpcError::Timeout(..) => Self::Timeout,
            IpcError::PeerGone(_) => Self::SimulatorGone,
            IpcError::Layout(_) => Self::Layout,
            // The message names the directory or file and what to do about it.
            IpcError::Transport { .. } | IpcError::PrivateRoot { .. } => Self::Transport,
        }
    }

    /// Every status, in declaration order.
    pub const ALL: [Self; 22] = [
        Self::Ok,
        Self::RefusedProtocolVersion,
        Self::RefusedJointCount,
        Self::RefusedJointNames,
        Self::RefusedReferenceOffsets,
        Self::RefusedBusy,
        Self::RefusedByRun,
        Self::RefusedInput,
        Self::RefusedProfile,
        Self::End,
        Self::Timeout,
        Self::NoSession,
        Self::SessionName,
        Self::SessionInUse,
        Self::Config,
        Self::SimulatorGone,
        Self::Layout,
        Self::Transport,
        Self::InvalidArgument,
        Self::CallOrder,
        Self::WrongThread,
        Self::Panic,
    ];

    /// The C name of the status (`THORARENA_STATUS_REFUSED_JOINT_COUNT`).
    pub fn name(self) -> &'static CStr {
        match self {
            Self::Ok => c"THORARENA_STATUS_OK",
            Self::RefusedProtocolVersion => c"THORARENA_STATUS_REFUSED_PROTOCOL_VERSION",
            Self::RefusedJointCount => c"THORARENA_STATUS_REFUSED_JOINT_COUNT",
            Self::RefusedJointNames => c"THORARENA_STATUS_REFUSED_JOINT_NAMES",
            Self::RefusedReferenceOffsets => c"THORARENA_STATUS_REFUSED_REFERENCE_OFFSETS",
            Self::RefusedBusy => c"THORARENA_STATUS_REFUSED_BUSY",
            Self::RefusedByRun => c"THORARENA_STATUS_REFUSED_BY_RUN",
            Self::RefusedInput => c"THORARENA_STATUS_REFUSED_INPUT",
            Self::RefusedProfile => c"THORARENA_STATUS_REFUSED_PROFILE",
            Self::End => c"THORARENA_STATUS_END",
            Self::Timeout => c"THORARENA_STATUS_TIMEOUT",
            Self::NoSession => c"THORARENA_STATUS_NO_SESSION",
            Self::SessionName => c"THORARENA_STATUS_SESSION_NAME",
            Self::SessionInUse => c"THORARENA_STATUS_SESSION_IN_USE",
            Self::Config => c"THORARENA_STATUS_CONFIG",
            Self::SimulatorGone => c"THORARENA_STATUS_SIMULATOR_GONE",
            Self::Layout => c"THORARENA_STATUS_LAYOUT",
            Self::Transport => c"THORARENA_STATUS_TRANSPORT",
            Self::InvalidArgument => c"THORARENA_STATUS_INVALID_ARGUMENT",
            Self::CallOrder => c"THORARENA_STATUS_CALL_ORDER",
            Self::WrongThread => c"THORARENA_STATUS_WRONG_THREAD",
            Self::Panic => c"THORARENA_STATUS_PANIC",
        }
    }
}
