//! Reading the files a user names (specs, section outlines, masks, dye spectra, stacks): every
//! read is bounded before it allocates, and what is not a readable file is named as what it is
//! (a directory, a character device, a socket) instead of "no such file".
//!
//! Pipes and character devices are read as streams, so `baker validate <(generate-spec)` works;
//! the size bound stops a device that never ends (`/dev/zero`) after `max_bytes`.

pub mod csv_rows;

use std::fmt;
use std::io::Read as _;
use std::path::{Path, PathBuf};

/// Spec files: far above any real spec (the thesis database is 3 KB), far below what would
/// strain memory.
pub const MAX_SPEC_BYTES: u64 = 16 << 20;
/// Data files a spec names (polygon CSV, dye CSV, mask image).
pub const MAX_DATA_BYTES: u64 = 64 << 20;

/// Why a file could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FileError {
    #[error("{}: no such file", path.display())]
    Missing { path: PathBuf },
    #[error("{}: is {what}, not a file", path.display())]
    NotAFile { path: PathBuf, what: &'static str },
    #[error("{}: {} is over the limit of {} for {purpose}", path.display(), size_text(*bytes, *regular), bytes_text(*limit))]
    TooLarge {
        path: PathBuf,
        bytes: u64,
        limit: u64,
        purpose: &'static str,
        /// False for a stream (device, pipe): `bytes` is what was read before giving up.
        regular: bool,
    },
    #[error("{}: is not UTF-8 text (byte {offset})", path.display())]
    NotText { path: PathBuf, offset: usize },
    #[error("{}: cannot read: {message}", path.display())]
    Io { path: PathBuf, message: String },
}

fn size_text(bytes: u64, regular: bool) -> String {
    if regular {
        bytes_text(bytes)
    } else {
        format!("a stream that goes on past {}", bytes_text(bytes))
    }
}

/// `12.3 MiB`, `512 bytes`.
pub fn bytes_text(b: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    if b < 1024 {
        return format!("{b} bytes");
    }
    let mut x = b as f64 / 1024.0;
    let mut u = 0;
    while x >= 1024.0 && u + 1 < UNITS.len() {
        x /= 1024.0;
        u += 1;
    }
    format!("{x:.1} {}", UNITS[u])
}

/// What a path is, in words, when it is not a regular file (`None` for a regular file).
pub fn special_kind(ft: &std::fs::FileType) -> Option<&'static str> {
    use std::os::unix::fs::FileTypeExt as _;
    if ft.is_file() {
        None
    } else if ft.is_dir() {
        Some("a directory")
    } else if ft.is_char_device() {
        Some("a character device")
    } else if ft.is_block_device() {
        Some("a block device")
    } else if ft.is_fifo() {
        Some("a FIFO (named pipe)")
    } else if ft.is_socket() {
        Some("a socket")
    } else {
        Some("not a regular file")
    }
}

/// Reads at most `max_bytes` of `path`; `purpose` names the file in the size error ("a spec
/// file").
pub fn read_bytes(
    path: &Path,
    max_bytes: u64,
    purpose: &'static str,
) -> Result<Vec<u8>, FileError> {
    let io = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::NotFound => FileError::Missing {
            path: path.to_path_buf(),
        },
        _ => FileError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        },
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    let ft = meta.file_type();
    let regular = ft.is_file();
    {
        use std::os::unix::fs::FileTypeExt as _;
        if ft.is_dir() || ft.is_socket() || ft.is_block_device() {
            return Err(FileError::NotAFile {
                path: path.to_path_buf(),
                what: special_kind(&ft).unwrap_or("not a regular file"),
            });
        }
    }
    if regular && meta.len() > max_bytes {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            bytes: meta.len(),
            limit: max_bytes,
            purpose,
            regular,
        });
    }
    let f = if ft.is_fifo_like() {
        open_fifo_for_reading(path).map_err(io)?
    } else {
        std::fs::File::open(path).map_err(io)?
    };
    let mut out = Vec::with_capacity(if regular { meta.len() as usize } else { 8192 });
    f.take(max_bytes + 1).read_to_end(&mut out).map_err(io)?;
    if out.len() as u64 > max_bytes {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            bytes: max_bytes,
            limit: max_bytes,
            purpose,
            regular,
        });
    }
    Ok(out)
}

/// `is_fifo` as a method on the file type (for readability above).
trait FifoLike {
    fn is_fifo_like(&self) -> bool;
}

impl FifoLike for std::fs::FileType {
    fn is_fifo_like(&self) -> bool {
        use std::os::unix::fs::FileTypeExt as _;
        self.is_fifo()
    }
}

/// Opens a FIFO without waiting for a writer (a plain `open` blocks until one comes): with a
/// writer (`<(generate-spec)`) reads block for its data as usual; without one they see the end
/// at once.
fn open_fifo_for_reading(path: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt as _;
    use std::os::unix::io::AsRawFd as _;
    let f = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)?;
    set_blocking(f.as_raw_fd())?;
    Ok(f)
}

/// Clears `O_NONBLOCK` on `fd`.
pub fn set_blocking(fd: std::os::unix::io::RawFd) -> std::io::Result<()> {
    // SAFETY: fcntl on a file descriptor this process owns.
    unsafe {
        let flags = libc::fcntl(fd, libc::F_GETFL);
        if flags < 0 || libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK) < 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// [`read_bytes`] as UTF-8 text, without a leading byte-order mark.
pub fn read_text(path: &Path, max_bytes: u64, purpose: &'static str) -> Result<String, FileError> {
    let bytes = read_bytes(path, max_bytes, purpose)?;
    let text = String::from_utf8(bytes).map_err(|e| FileError::NotText {
        path: path.to_path_buf(),
        offset: e.utf8_error().valid_up_to(),
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// A path for messages (`display()` of a path that holds control characters would print them
/// raw to a terminal).
pub struct Shown<'a>(pub &'a Path);

impl fmt::Display for Shown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.0.to_string_lossy();
        if s.chars().any(char::is_control) {
            write!(f, "{s:?}")
        } else {
            f.write_str(&s)
        }
    }
}

/// The SHA-256 of `bytes` in lower-case hex (provenance, manifests, stamps).
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest as _;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_sizes_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_text(dir.path(), 100, "a spec file").unwrap_err();
        assert!(e.to_string().ends_with("is a directory, not a file"), "{e}");
        let e = read_text(&dir.path().join("nope.yaml"), 100, "a spec file").unwrap_err();
        assert!(e.to_string().ends_with("no such file"), "{e}");
        let e = read_text(Path::new("/dev/zero"), 1000, "a spec file").unwrap_err();
        assert!(
            e.to_string()
                .contains("a stream that goes on past 1000 bytes"),
            "{e}"
        );
        let p = dir.path().join("big.yaml");
        std::fs::write(&p, vec![b'a'; 2000]).unwrap();
        let e = read_text(&p, 1000, "a spec file").unwrap_err();
        assert!(e.to_string().contains("2.0 KiB is over the limit"), "{e}");
        std::fs::write(&p, b"\xef\xbb\xbfa: 1\n").unwrap();
        assert_eq!(read_text(&p, 1000, "a spec file").unwrap(), "a: 1\n");
        std::fs::write(&p, b"a: \xff\n").unwrap();
        assert!(matches!(
            read_text(&p, 1000, "a spec file"),
            Err(FileError::NotText { offset: 3, .. })
        ));
        assert_eq!(read_text(Path::new("/dev/null"), 10, "x").unwrap(), "");
        // A FIFO nobody writes to reads as empty instead of blocking.
        let fifo = dir.path().join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        assert_eq!(read_text(&fifo, 10, "x").unwrap(), "");
    }
}
