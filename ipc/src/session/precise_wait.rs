//! Blocking on an event listener with a timeout that holds to the microsecond.
//!
//! `Listener::timed_wait` sets the timeout as a socket receive timeout (`SO_RCVTIMEO` on
//! the listener's datagram socket), which the kernel counts in scheduler ticks, rounded
//! up: on a `CONFIG_HZ=250` kernel every wait from 0.2 to 3 ms lasted 8 ms. A wait that
//! must end at a budget's deadline, or shortly before the other side is due, cannot use
//! it: a notification arriving in the overshoot wakes the waiter long after the moment
//! it asked for, so a late answer looked on time and the wake-before-due window was
//! slept through. `ppoll` on the same socket takes a nanosecond timeout on a
//! high-resolution timer (late by the thread's timer slack, 50 µs by default); the
//! events it reports are then taken off the listener without blocking.

use super::{transport, IpcError, TransportOp};
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use std::time::Duration;

/// Blocks until `listener` has a notification or `timeout` has passed; returns how many
/// events it took (0: the timeout passed, or a signal interrupted the wait — the caller
/// checks its condition and waits again).
pub(crate) fn wait_for_event(
    listener: &Listener<ipc::Service>,
    timeout: Duration,
) -> Result<usize, IpcError> {
    // SAFETY: the descriptor stays open while `listener` lives (iceoryx2's
    // `FileDescriptorBased`), which outlives this call; it is only polled, never closed.
    let fd = unsafe { listener.file_descriptor().native_handle() };
    let mut poll = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    let timeout = libc::timespec {
        tv_sec: timeout.as_secs().min(libc::time_t::MAX as u64) as libc::time_t,
        tv_nsec: timeout.subsec_nanos() as libc::c_long,
    };
    // SAFETY: one valid `pollfd`, a valid timespec, no signal mask.
    let ready = unsafe { libc::ppoll(&mut poll, 1, &timeout, std::ptr::null()) };
    if ready < 0 {
        let error = std::io::Error::last_os_error();
        // A signal (Ctrl-Z then `fg`: SIGSTOP, SIGCONT) interrupted the wait: nothing
        // happened to the session.
        if error.kind() == std::io::ErrorKind::Interrupted {
            return Ok(0);
        }
        return Err(transport(TransportOp::WaitForEvent)(error));
    }
    if ready == 0 {
        return Ok(0);
    }
    let mut events = 0;
    listener
        .try_wait(|_| events += 1)
        .map_err(transport(TransportOp::WaitForEvent))?;
    Ok(events)
}
