//! A launched process's output written to its log up to a size, the rest read away.
//!
//! Why: a policy process prints what it likes, and a chatty one wrote 254 MB in the 2 s of
//! one episode; an hour-long sweep of such tasks fills the disk, and then the runs' own
//! writes fail. Its stdout and stderr are one pipe instead of the file itself: a thread
//! copies the pipe into the log until [`PROCESS_LOG_MAX_BYTES`], then writes a note
//! saying the output was cut (and warns once, naming the log), and keeps reading — never
//! closing the pipe, which would kill a process that writes on — until every writer is
//! gone, when it notes how much was cut.

use std::fs::File;
use std::io::{Read, Write};
use std::path::Path;
use std::process::Stdio;

/// The most bytes of a launched process's output its log keeps: 16 MiB, tens of
/// thousands of lines of a policy's own diagnostics, and a sweep of a thousand tasks
/// stays under 20 GB of logs however chatty its policy.
pub const PROCESS_LOG_MAX_BYTES: u64 = 16 * crate::files::bounded_read::MIB;

/// The process's stdout and stderr, both the writing end of one pipe whose output goes
/// into `log` (at `path`, named in the note) up to `max_bytes`.
pub fn capped_output(log: File, path: &Path, max_bytes: u64) -> std::io::Result<(Stdio, Stdio)> {
    let (reader, writer) = std::io::pipe()?;
    let stderr = writer.try_clone()?;
    let path = path.to_path_buf();
    std::thread::Builder::new()
        .name("process-log".into())
        .spawn(move || pump(reader, log, &path, max_bytes))?;
    Ok((writer.into(), stderr.into()))
}

/// Copies `from` into `log` up to `max_bytes`, then reads the rest away.
fn pump(mut from: impl Read, mut log: File, path: &Path, max_bytes: u64) {
    let mut buf = vec![0u8; 64 * 1024];
    let (mut kept, mut cut) = (0u64, 0u64);
    loop {
        let n = match from.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => break,
        };
        let room = (max_bytes - kept).min(n as u64) as usize;
        if room > 0 && log.write_all(&buf[..room]).is_err() {
            // The disk is full or the file gone: nothing more is kept, the pipe drains.
            kept = max_bytes;
        } else {
            kept += room as u64;
        }
        if room < n {
            if cut == 0 {
                let _ = writeln!(
                    log,
                    "\n[thorarena: this log keeps the first {max_bytes} bytes of the process's output; the rest is not written]"
                );
                log::warn!(
                    "{}: the policy process's output passed {} MiB; the rest is cut (not written)",
                    path.display(),
                    max_bytes >> 20
                );
            }
            cut += (n - room) as u64;
        }
    }
    if cut > 0 {
        let _ = writeln!(log, "[thorarena: {cut} bytes of output were cut]");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_past_the_cap_is_cut_with_a_note_and_read_to_its_end() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.log");
        let log = File::create(&path).unwrap();
        let text = b"0123456789".repeat(1000);
        pump(&text[..], log, &path, 100);
        let written = std::fs::read_to_string(&path).unwrap();
        assert!(written.starts_with(&"0123456789".repeat(10)), "{written}");
        assert!(written.contains("keeps the first 100 bytes"), "{written}");
        assert!(
            written.ends_with("[thorarena: 9900 bytes of output were cut]\n"),
            "{written}"
        );
        let small = dir.path().join("q.log");
        pump(&b"short\n"[..], File::create(&small).unwrap(), &small, 100);
        assert_eq!(std::fs::read(&small).unwrap(), b"short\n");
    }
}
