//! holosoma's simulator clock: the simulated time in whole milliseconds, as decimal text,
//! published over ZeroMQ (a PUB socket on tcp 127.0.0.1:PORT, 5555 by holosoma's
//! default). holosoma's inference package reads it under `--task.use-sim-time`
//! (`holosoma_inference/utils/clock.py`, `ClockSub`) and then steps its motion clip by the
//! simulator's time instead of counting its own control cycles, which slip behind the
//! wall clock whenever a cycle overruns.
//!
//! A minimal ZMTP 3.0 publisher on std's TCP, no ZeroMQ library: per subscriber the
//! 64-byte greeting (NULL mechanism), a READY command naming the socket type `PUB`, then
//! one single-frame message per publish. What a subscriber sends after its own READY
//! (its subscriptions) is not read: every subscriber gets every message, which is what
//! holosoma's subscription to everything asks for. A subscriber that cannot keep up is
//! dropped, as a PUB socket drops messages for a slow one.

use std::io::{Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Why the clock could not be served.
#[derive(Debug, thiserror::Error)]
#[error("the ZeroMQ clock on 127.0.0.1:{port}: {source}")]
pub struct ZmqClockError {
    /// The port.
    pub port: u16,
    /// The socket error.
    #[source]
    pub source: std::io::Error,
}

/// The publisher; dropping it stops accepting subscribers and closes their connections.
pub struct ZmqClock {
    subscribers: Arc<Mutex<Vec<TcpStream>>>,
    stop: Arc<AtomicBool>,
    acceptor: Option<std::thread::JoinHandle<()>>,
    port: u16,
}

impl ZmqClock {
    /// Listens on 127.0.0.1:`port` (0: any free port, see [`ZmqClock::port`]); a thread
    /// accepts subscribers and does their handshakes.
    pub fn bind(port: u16) -> Result<Self, ZmqClockError> {
        let error = |source| ZmqClockError { port, source };
        let listener =
            TcpListener::bind(SocketAddr::from((Ipv4Addr::LOCALHOST, port))).map_err(error)?;
        listener.set_nonblocking(true).map_err(error)?;
        let port = listener.local_addr().map_err(error)?.port();
        let subscribers = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let acceptor = {
            let (subscribers, stop) = (subscribers.clone(), stop.clone());
            std::thread::spawn(move || accept_until_stopped(&listener, &subscribers, &stop))
        };
        Ok(Self {
            subscribers,
            stop,
            acceptor: Some(acceptor),
            port,
        })
    }

    /// The port it listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Sends `time_ms` to every subscriber whose handshake is done.
    pub fn publish(&self, time_ms: u64) {
        let frame = message_frame(time_ms.to_string().as_bytes());
        let mut subscribers = self.subscribers.lock().unwrap_or_else(|e| e.into_inner());
        subscribers.retain_mut(|stream| stream.write_all(&frame).is_ok());
    }

    /// Subscribers connected and past their handshake.
    pub fn subscribers(&self) -> usize {
        self.subscribers.lock().map_or(0, |s| s.len())
    }
}

impl Drop for ZmqClock {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(acceptor) = self.acceptor.take() {
            let _ = acceptor.join();
        }
    }
}

fn accept_until_stopped(
    listener: &TcpListener,
    subscribers: &Mutex<Vec<TcpStream>>,
    stop: &AtomicBool,
) {
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => {
                // A peer that does not complete the handshake is let go.
                if let Ok(stream) = handshake(stream) {
                    if let Ok(mut s) = subscribers.lock() {
                        s.push(stream);
                    }
                }
            }
            Err(_) => std::thread::sleep(Duration::from_millis(10)),
        }
    }
}

/// ZMTP 3.0 with the NULL mechanism: greetings both ways, our READY, the peer's READY
/// read and checked to be a command; then the stream is left non-blocking for publishing.
fn handshake(mut stream: TcpStream) -> std::io::Result<TcpStream> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(Duration::from_secs(2)))?;
    stream.set_nodelay(true)?;
    stream.write_all(&GREETING)?;
    let mut greeting = [0u8; 64];
    stream.read_exact(&mut greeting)?;
    if greeting[0] != 0xFF || greeting[9] != 0x7F || greeting[10] < 3 {
        return Err(std::io::Error::other("not a ZMTP 3 peer"));
    }
    stream.write_all(&ready_command())?;
    // The peer's READY: a command frame (flags bit 2), short or long.
    let mut flags = [0u8; 1];
    stream.read_exact(&mut flags)?;
    if flags[0] & 0x04 == 0 {
        return Err(std::io::Error::other(
            "the peer's first frame is not a command",
        ));
    }
    let size = if flags[0] & 0x02 != 0 {
        let mut size = [0u8; 8];
        stream.read_exact(&mut size)?;
        u64::from_be_bytes(size)
    } else {
        let mut size = [0u8; 1];
        stream.read_exact(&mut size)?;
        u64::from(size[0])
    };
    std::io::copy(&mut (&mut stream).take(size), &mut std::io::sink())?;
    stream.set_nonblocking(true)?;
    Ok(stream)
}

/// Signature, version 3.0, mechanism "NULL", not a server, filler.
const GREETING: [u8; 64] = {
    let mut g = [0u8; 64];
    g[0] = 0xFF;
    g[9] = 0x7F;
    g[10] = 3;
    g[11] = 0;
    g[12] = b'N';
    g[13] = b'U';
    g[14] = b'L';
    g[15] = b'L';
    g
};

/// READY with the one property `Socket-Type: PUB`.
fn ready_command() -> Vec<u8> {
    ready_command_of(b"PUB")
}

/// READY with the one property `Socket-Type: socket_type` (a short command frame).
fn ready_command_of(socket_type: &[u8]) -> Vec<u8> {
    let mut body = vec![5];
    body.extend(b"READY");
    body.push(11);
    body.extend(b"Socket-Type");
    body.extend((socket_type.len() as u32).to_be_bytes());
    body.extend(socket_type);
    let mut frame = vec![0x04, body.len() as u8];
    frame.extend(body);
    frame
}

/// A single-frame message (short form: the clock's text is under 256 bytes).
fn message_frame(body: &[u8]) -> Vec<u8> {
    debug_assert!(body.len() < 256);
    let mut frame = vec![0x00, body.len() as u8];
    frame.extend(body);
    frame
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frames_are_zmtp_3() {
        assert_eq!(GREETING.len(), 64);
        assert_eq!(&GREETING[..12], &[0xFF, 0, 0, 0, 0, 0, 0, 0, 0, 0x7F, 3, 0]);
        assert_eq!(&GREETING[12..17], b"NULL\0");
        let ready = ready_command();
        assert_eq!(ready[0], 0x04);
        assert_eq!(usize::from(ready[1]), ready.len() - 2);
        assert_eq!(&ready[2..8], b"\x05READY");
        assert_eq!(message_frame(b"1234"), b"\x00\x041234");
    }

    #[test]
    fn a_subscriber_that_speaks_zmtp_gets_the_time() {
        let clock = ZmqClock::bind(0).unwrap();
        // A hand-made ZMTP 3.0 subscriber: greeting, READY(Socket-Type SUB), subscribe all.
        let mut sub = TcpStream::connect(("127.0.0.1", clock.port())).unwrap();
        sub.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        sub.write_all(&GREETING).unwrap();
        sub.write_all(&ready_command_of(b"SUB")).unwrap();
        sub.write_all(&[0x00, 0x01, 0x01]).unwrap();
        let mut greeting = [0u8; 64];
        sub.read_exact(&mut greeting).unwrap();
        let ready = ready_command();
        let mut theirs = vec![0u8; ready.len()];
        sub.read_exact(&mut theirs).unwrap();
        assert_eq!(theirs, ready);
        let start = std::time::Instant::now();
        while clock.subscribers() == 0 && start.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(5));
        }
        clock.publish(40_020);
        let mut message = [0u8; 7];
        sub.read_exact(&mut message).unwrap();
        assert_eq!(&message, b"\x00\x0540020");
    }
}
