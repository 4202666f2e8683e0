//! The baseline of `bench ipc`: the same observation and action batches through a Unix
//! stream socket to a peer process that answers action = q, with either blocking reads or
//! the shared-memory path's wait (busy-poll a non-blocking socket, then `poll(2)`).

use super::bench_ipc::{fill, Row};
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use thorarena::evaluation::LatencyRecorder;
use thorarena_ipc::{ActionBatchMut, Layout, ObsBatch, ObsBatchMut};

/// Hidden subcommand: the socket baseline's echo peer.
#[derive(Debug, clap::Args)]
pub struct PeerArgs {
    /// Socket path to connect to.
    #[arg(long)]
    pub socket: PathBuf,
    /// Environments per batch.
    #[arg(long)]
    pub envs: usize,
    /// Joints per environment.
    #[arg(long)]
    pub joints: usize,
    /// Reference frames per environment.
    #[arg(long)]
    pub refs: usize,
    /// Busy-poll this many µs before blocking (0: blocking reads).
    #[arg(long, default_value_t = 0)]
    pub spin_us: u64,
}

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

/// Round trips of `steps` batches (after `warmup`) through a socket peer process.
pub(super) fn socket_baseline(
    warmup: usize,
    steps: usize,
    layout: Layout,
    spin: Duration,
) -> anyhow::Result<Row> {
    let path = std::env::temp_dir().join(format!(
        "thorarena-bench-{}-{}-{}.sock",
        std::process::id(),
        layout.n_envs,
        spin.as_micros()
    ));
    let _ = std::fs::remove_file(&path);
    let listener = UnixListener::bind(&path)?;
    let mut peer = Command::new(std::env::current_exe()?)
        .args(["bench", "socket-peer", "--socket"])
        .arg(&path)
        .args(["--envs", &layout.n_envs.to_string()])
        .args(["--joints", &layout.n_joints.to_string()])
        .args(["--refs", &layout.n_refs.to_string()])
        .args(["--spin-us", &spin.as_micros().to_string()])
        .stdout(Stdio::piped())
        .spawn()?;
    let (stream, _) = listener.accept()?;
    let mut stream = Stream::new(stream, spin)?;
    let mut ready = String::new();
    BufReader::new(peer.stdout.take().expect("piped")).read_line(&mut ready)?;
    let mut obs = vec![0u64; layout.obs_words()];
    let mut actions = vec![0u64; layout.action_words()];
    let mut rec = LatencyRecorder::default();
    for step in 0..(warmup + steps) as u64 {
        {
            let mut b = ObsBatchMut::new(layout, bytemuck::cast_slice_mut(&mut obs), 0, step);
            fill(&mut b, layout, step);
        }
        let started = Instant::now();
        stream.write_all(bytemuck::cast_slice(&obs))?;
        stream.read_exact(bytemuck::cast_slice_mut(&mut actions))?;
        let took = started.elapsed();
        if step >= warmup as u64 {
            rec.record(took);
        }
    }
    drop(stream);
    let _ = peer.wait();
    let _ = std::fs::remove_file(&path);
    Ok(Row::of(&rec))
}

/// `bench socket-peer`: answers each batch read from the socket with action = q.
pub(super) fn run_peer(args: &PeerArgs) -> anyhow::Result<()> {
    use anyhow::Context;
    let layout = Layout {
        n_envs: args.envs,
        n_joints: args.joints,
        n_refs: args.refs,
    };
    let stream = UnixStream::connect(&args.socket)
        .with_context(|| format!("connecting to {}", args.socket.display()))?;
    let mut stream = Stream::new(stream, Duration::from_micros(args.spin_us))?;
    println!("ready");
    std::io::stdout().flush()?;
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
        stream.write_all(bytemuck::cast_slice(&actions))?;
    }
}
