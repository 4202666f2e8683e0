//! Reading a file whose size and kind are checked first: a regular file only, of at most
//! the bytes its kind may hold.
//!
//! Why: a path a user gives can name anything. `/dev/zero` (or a dataset's symbolic link
//! to it) read with `std::fs::read` grows memory by gigabytes in seconds, and a FIFO
//! without a writer blocks the open forever. Here a FIFO is opened non-blocking, anything
//! but a regular file is refused before a byte is read, and a file larger than its kind's
//! limit is refused rather than read into memory. The errors are `std::io::Error`s whose
//! text says what was found, so every caller keeps its own error type and its "reading
//! PATH: …" wording.

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// One MiB, for the limits.
pub const MIB: u64 = 1 << 20;

/// Opens `path` for reading as a regular file of at most `max_bytes`, `kind` naming what
/// it should be in the error ("request file", "sequence file"). The reader stops at the
/// limit even if the file grows after the check.
pub fn open(path: &Path, kind: &str, max_bytes: u64) -> std::io::Result<std::io::Take<File>> {
    // O_NONBLOCK: opening a FIFO without a writer must not wait; the check below refuses
    // it. Reads of a regular file ignore the flag.
    let file = {
        use std::os::unix::fs::OpenOptionsExt;
        std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(path)?
    };
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("it is {}, not a file", file_kind(&meta)),
        ));
    }
    if meta.len() > max_bytes {
        return Err(too_large(kind, meta.len(), max_bytes));
    }
    Ok(file.take(max_bytes + 1))
}

/// `path` whole, as [`open`] checks it.
pub fn read(path: &Path, kind: &str, max_bytes: u64) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    open(path, kind, max_bytes)?.read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large(kind, bytes.len() as u64, max_bytes));
    }
    Ok(bytes)
}

/// `path` whole as UTF-8 text, as [`open`] checks it.
pub fn read_to_string(path: &Path, kind: &str, max_bytes: u64) -> std::io::Result<String> {
    String::from_utf8(read(path, kind, max_bytes)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "it is not UTF-8 text"))
}

fn too_large(kind: &str, bytes: u64, max_bytes: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "it holds {bytes} bytes or more, over the {} MiB a {kind} may hold",
            max_bytes / MIB
        ),
    )
}

/// What a path that is no regular file is, in words.
pub fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_regular_file_within_its_limit_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let e = read(dir.path(), "request file", MIB)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a directory, not a file"), "{e}");
        let e = read(Path::new("/dev/zero"), "request file", MIB)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a device, not a file"), "{e}");
        let fifo = dir.path().join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo does not retain it.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = read(&fifo, "request file", MIB).unwrap_err().to_string();
        assert!(e.contains("is a FIFO"), "{e}");
        let big = dir.path().join("big.json");
        std::fs::write(&big, vec![b' '; 2 * MIB as usize]).unwrap();
        let e = read(&big, "request file", MIB).unwrap_err().to_string();
        assert!(e.contains("over the 1 MiB a request file may hold"), "{e}");
        let small = dir.path().join("small.json");
        std::fs::write(&small, b"{}").unwrap();
        assert_eq!(read_to_string(&small, "request file", MIB).unwrap(), "{}");
    }
}
