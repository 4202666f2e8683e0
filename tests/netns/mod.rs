//! A private network namespace for the tests that speak DDS: a namespace of its own with
//! only a loopback, so unchanged deployment code (which joins DDS domain 0) and the bridge
//! meet there and nowhere else — no traffic on the host's interfaces, no cross-talk with
//! another test or a developer's robot on domain 0.
//!
//! Made with `unshare -n` (a holder process keeps the namespace alive; programs join it
//! with `nsenter -n`), or for a test whose own thread speaks DDS, by moving that thread
//! into a new namespace ([`enter_private_network`]); both need root. Where that is not
//! allowed, everything runs on the host's loopback (both ends are told to use `lo` /
//! 127.0.0.1 only) and this is said on stderr.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::process::{Child, Command, Stdio};

/// The namespace; dropping it stops the holder (by its pid), and the namespace goes with
/// the last process in it.
pub struct PrivateNetwork {
    holder: Option<Child>,
}

impl PrivateNetwork {
    /// A new namespace with its loopback up, or the host's loopback (said on stderr).
    pub fn new(test: &str) -> Self {
        let holder = Command::new("unshare")
            .args([
                "-n",
                "sh",
                "-c",
                "ip link set lo up && echo up && exec sleep 3600",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn();
        let mut holder = match holder {
            Ok(child) => child,
            Err(e) => return Self::host(test, &format!("unshare: {e}")),
        };
        let mut line = String::new();
        {
            use std::io::BufRead;
            let stdout = holder.stdout.take().expect("piped");
            let _ = std::io::BufReader::new(stdout).read_line(&mut line);
        }
        if line.trim() != "up" {
            let _ = holder.kill();
            let _ = holder.wait();
            return Self::host(test, "`unshare -n` not allowed here (it needs root)");
        }
        Self {
            holder: Some(holder),
        }
    }

    fn host(test: &str, why: &str) -> Self {
        eprintln!("{test}: no private network namespace ({why}): on the host's loopback");
        Self { holder: None }
    }

    /// Whether programs run in a namespace of their own.
    pub fn is_private(&self) -> bool {
        self.holder.is_some()
    }

    /// A command running `program` in the namespace (`nsenter` execs it: the child's pid
    /// is the program's).
    pub fn command(&self, program: impl AsRef<OsStr>) -> Command {
        match &self.holder {
            Some(holder) => {
                let mut command = Command::new("nsenter");
                command
                    .args(["-t", &holder.id().to_string(), "-n", "--"])
                    .arg(program);
                command
            }
            None => Command::new(program),
        }
    }
}

/// Moves the calling thread into a new network namespace with its loopback up; threads
/// and processes it starts afterwards (rustdds' event loop, a Python peer) are in it too.
/// Returns whether it did (it says on stderr why not).
pub fn enter_private_network(test: &str) -> bool {
    let say = |why: &str| {
        eprintln!("{test}: no private network namespace ({why}): on the host's loopback");
    };
    // To come back to if the new namespace's loopback cannot be brought up.
    let host = match std::fs::File::open("/proc/thread-self/ns/net") {
        Ok(file) => file,
        Err(e) => {
            say(&format!("/proc/thread-self/ns/net: {e}"));
            return false;
        }
    };
    // SAFETY: unshare(2) with CLONE_NEWNET changes only this thread's network namespace.
    if unsafe { libc::unshare(libc::CLONE_NEWNET) } != 0 {
        say(&format!("unshare: {}", std::io::Error::last_os_error()));
        return false;
    }
    // `ip` runs in this thread's new namespace, whose loopback starts down.
    let up = Command::new("ip")
        .args(["link", "set", "lo", "up"])
        .status()
        .is_ok_and(|s| s.success());
    if !up {
        use std::os::fd::AsRawFd;
        // SAFETY: setns(2) back into the namespace this thread came from, by an open fd.
        let back = unsafe { libc::setns(host.as_raw_fd(), libc::CLONE_NEWNET) } == 0;
        assert!(
            back,
            "{test}: could not return to the host's network namespace"
        );
        say("`ip link set lo up` failed");
        return false;
    }
    true
}

impl Drop for PrivateNetwork {
    fn drop(&mut self) {
        if let Some(holder) = &mut self.holder {
            let _ = holder.kill();
            let _ = holder.wait();
        }
    }
}
