//! The baseline of the IPC round trip: the same observation and action batches through a
//! Unix stream socket to a peer process that answers action = q, with either blocking
//! reads or the shared-memory path's own wait (busy-poll a non-blocking socket, then
//! `poll(2)`), so a comparison separates what waiting costs from what copying costs.

use super::round_trip::fill_echo_observations;
use super::PerfError;
use crate::eval::{LatencyRecorder, LatencySummary};
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use thorarena_ipc::{ActionBatchMut, Layout, ObsBatch, ObsBatchMut};

/// The line a peer prints once connected.
const READY: &str = "ready";

/// A stream socket read and written either blocking or spin-then-block.
struct Stream {
    inner: UnixStream,
    spin: Duration,
}

impl Stream {
    fn new(inner: UnixStream, spin: Duration) -> std::io::Result<Self> {
        inner.set_nonblocking(!spin.is_zero())?;
        Ok(Self { inner, spin })
    }

    /// Waits for the socket to be readable (or writable) once the spin is over.
    fn block(&self, events: libc::c_short) {
        let mut fd = libc::pollfd {
            fd: self.inner.as_raw_fd(),
            events,
            revents: 0,
        };
        // SAFETY: one valid pollfd for a socket we own, for the duration of the call.
        unsafe {
            libc::poll(&mut fd, 1, -1);
        }
    }

    fn read_exact(&mut self, buf: &mut [u8]) -> std::io::Result<()> {
        if self.spin.is_zero() {
            return self.inner.read_exact(buf);
        }
        let (mut filled, started) = (0, Instant::now());
        while filled < buf.len() {
            match self.inner.read(&mut buf[filled..]) {
                Ok(0) => return Err(ErrorKind::UnexpectedEof.into()),
                Ok(n) => filled += n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    if started.elapsed() < self.spin {
                        std::hint::spin_loop();
                    } else {
                        self.block(libc::POLLIN);
                    }
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        if self.spin.is_zero() {
            return self.inner.write_all(buf);
        }
        let mut sent = 0;
        while sent < buf.len() {
            match self.inner.write(&buf[sent..]) {
                Ok(n) => sent += n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => self.block(libc::POLLOUT),
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}

/// `warmup` untimed and `steps` timed round trips through a socket peer: `peer` is the
/// command of a process that connects to the socket path given as its last argument and
/// calls [`answer_socket_echo`] (for `thorarena`, `bench socket-peer … --socket`).
pub fn socket_round_trips(
    mut peer: Command,
    layout: Layout,
    warmup: usize,
    steps: usize,
    spin: Duration,
) -> Result<LatencySummary, PerfError> {
    let path = std::env::temp_dir().join(format!(
        "thorarena-bench-{}-{}-{}.sock",
        std::process::id(),
        layout.n_envs,
        spin.as_micros()
    ));
    let _ = std::fs::remove_file(&path);
    let listener = UnixListener::bind(&path).map_err(PerfError::io("binding the socket"))?;
    let mut peer = peer
        .arg(&path)
        .stdout(Stdio::piped())
        .spawn()
        .map_err(PerfError::io("starting the socket peer"))?;
    let io = |what: &'static str| PerfError::io(what);
    let (stream, _) = listener.accept().map_err(io("accepting the peer"))?;
    let mut stream = Stream::new(stream, spin).map_err(io("configuring the socket"))?;
    let mut ready = String::new();
    BufReader::new(peer.stdout.take().expect("piped"))
        .read_line(&mut ready)
        .map_err(io("reading the peer's ready line"))?;
    let mut obs = vec![0u64; layout.obs_words()];
    let mut actions = vec![0u64; layout.action_words()];
    let mut rec = LatencyRecorder::default();
    for step in 0..(warmup + steps) as u64 {
        {
            let mut b = ObsBatchMut::new(layout, bytemuck::cast_slice_mut(&mut obs), 0, step);
            fill_echo_observations(&mut b, layout, step);
        }
        let started = Instant::now();
        stream
            .write_all(bytemuck::cast_slice(&obs))
            .map_err(io("sending a batch"))?;
        stream
            .read_exact(bytemuck::cast_slice_mut(&mut actions))
            .map_err(io("receiving the actions"))?;
        let took = started.elapsed();
        if step >= warmup as u64 {
            rec.record(took);
        }
    }
    drop(stream);
    let _ = peer.wait();
    let _ = std::fs::remove_file(&path);
    Ok(rec.summary())
}

/// The peer side: connects to `socket`, prints a ready line on standard output, and
/// answers each batch with action = q until the other side closes the socket.
pub fn answer_socket_echo(socket: &Path, layout: Layout, spin: Duration) -> Result<(), PerfError> {
    let stream = UnixStream::connect(socket)
        .map_err(PerfError::io(format!("connecting to {}", socket.display())))?;
    let mut stream = Stream::new(stream, spin).map_err(PerfError::io("configuring the socket"))?;
    let mut stdout = std::io::stdout();
    writeln!(stdout, "{READY}")
        .and_then(|()| stdout.flush())
        .map_err(PerfError::io("writing the ready line"))?;
    let mut obs = vec![0u64; layout.obs_words()];
    let mut actions = vec![0u64; layout.action_words()];
    loop {
        if stream
            .read_exact(bytemuck::cast_slice_mut(&mut obs))
            .is_err()
        {
            return Ok(()); // the benchmark closed the socket
        }
        let batch = ObsBatch::new(layout, bytemuck::cast_slice(&obs))?;
        let mut out = ActionBatchMut::new(
            layout,
            bytemuck::cast_slice_mut(&mut actions),
            batch.header().seq,
        );
        for i in 0..layout.n_envs {
            let env = batch.env(i);
            if env.is_active() {
                out.env(i).copy_from_slice(env.array("q"));
            }
        }
        stream
            .write_all(bytemuck::cast_slice(&actions))
            .map_err(PerfError::io("sending the actions"))?;
    }
}
