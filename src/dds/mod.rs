//! The G1's own DDS interface (Unitree's `unitree_hg` messages on `rt/lowcmd` and
//! `rt/lowstate`), so deployment code written for the robot can drive the simulator.
//!
//! The message types (`unitree_hg`, and `unitree_go`'s wireless remote), their CDR encoding (`cdr`) and the checksum the robot
//! and Unitree's SDKs put in every message (`crc`, computed over the messages' C struct
//! layout) are ours; DDS itself is `rustdds` (`transport`: the robot's topics).

pub mod bridge;
pub mod cdr;
pub mod crc;
pub mod interface;
pub mod motion_switcher;
pub mod scheduling;
pub mod session;
pub mod transport;
pub mod unitree_go;
pub mod unitree_hg;
pub mod wireless_remote;
pub mod zmq_clock;

pub use transport::{DdsError, RobotEndpoints, MAX_DOMAIN};
pub use unitree_go::WirelessController;
pub use unitree_hg::{ImuState, LowCmd, LowState, MotorCmd, MotorState};

/// A DDS message that could not be decoded.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum DecodeError {
    /// The serialized payload ends before the message does.
    #[error("{message}: {got} bytes of payload, the message needs {need}")]
    Truncated {
        /// The message type.
        message: &'static str,
        /// Bytes available.
        got: usize,
        /// Bytes needed.
        need: usize,
    },
    /// The encapsulation header names an encoding this codec does not read.
    #[error("{message}: encapsulation {kind:#06x} is not plain CDR (XCDR1 or XCDR2)")]
    Encapsulation {
        /// The message type.
        message: &'static str,
        /// The representation identifier.
        kind: u16,
    },
}
