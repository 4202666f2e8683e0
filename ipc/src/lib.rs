//! `thorarena-ipc`: the zero-copy policy protocol over iceoryx2 — `#[repr(C)]` messages,
//! server and client sides, a C ABI.
//!
//! Not built yet (issue 5). The crate exists so the workspace layout is final and the
//! dependency rule holds from the start: this crate never depends on the simulator core.
#![warn(missing_docs)]

/// Version of the wire protocol; bumped on any layout change.
pub const PROTOCOL_VERSION: u32 = 0;
