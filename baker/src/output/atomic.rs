//! Writing one output file: atomically where that is possible, as a stream where the target is
//! a device, and never by replacing something that is not a regular file.
//!
//! | the path is | what happens |
//! |---|---|
//! | new, or a regular file | a temporary file in the same directory, synced, renamed over it: readers see the old file or the whole new one |
//! | `-` | written to standard output |
//! | a character device (`/dev/null`), a FIFO, a socket | written to directly, as a stream (no temporary file, no rename: the device stays a device) |
//! | a directory, a block device | an error that says so; nothing is written |
//!
//! Symbolic links are followed to decide, so a link to `/dev/null` is written to as a stream;
//! a link to a regular file is replaced by the new file (the file it pointed to is untouched).

use std::fs::{self, File};
use std::io::{self, Write};
use std::path::Path;

/// Where the bytes of an output go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sink {
    /// A regular file or a new path: temp-and-rename.
    File,
    /// `-`.
    Stdout,
    /// A character device or a FIFO: opened for writing.
    Stream,
    /// A Unix socket: connected to.
    Socket,
}

/// What writing to `path` will do; an error for a directory or a block device.
pub fn target(path: &Path) -> io::Result<Sink> {
    use std::os::unix::fs::FileTypeExt as _;
    if path.as_os_str() == "-" {
        return Ok(Sink::Stdout);
    }
    let meta = match fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Sink::File),
        Err(e) => return Err(e),
    };
    let ft = meta.file_type();
    if ft.is_file() {
        Ok(Sink::File)
    } else if ft.is_char_device() || ft.is_fifo() {
        Ok(Sink::Stream)
    } else if ft.is_socket() {
        Ok(Sink::Socket)
    } else {
        let what = crate::files::special_kind(&ft).unwrap_or("not a regular file");
        Err(io::Error::other(format!(
            "{} is {what}; expected a file name (or a character device, a FIFO, or `-` for \
             standard output)",
            crate::files::Shown(path)
        )))
    }
}

/// How long a write to a FIFO waits for a process to read it.
const FIFO_READER_WAIT: std::time::Duration = std::time::Duration::from_secs(5);

/// Opens a stream target for writing. A FIFO nobody reads is an error after
/// [`FIFO_READER_WAIT`] (a plain `open` would wait forever).
fn open_stream(path: &Path, t: Sink) -> io::Result<Box<dyn Write>> {
    use std::os::unix::fs::OpenOptionsExt as _;
    use std::os::unix::io::AsRawFd as _;
    Ok(match t {
        Sink::Stdout => Box::new(io::stdout().lock()),
        Sink::Socket => Box::new(std::os::unix::net::UnixStream::connect(path)?),
        _ => {
            let t0 = std::time::Instant::now();
            let f = loop {
                match fs::OpenOptions::new()
                    .write(true)
                    .custom_flags(libc::O_NONBLOCK)
                    .open(path)
                {
                    Ok(f) => break f,
                    Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
                        if t0.elapsed() > FIFO_READER_WAIT {
                            return Err(io::Error::other(format!(
                                "{} is a FIFO that no process reads",
                                crate::files::Shown(path)
                            )));
                        }
                        std::thread::sleep(std::time::Duration::from_millis(10));
                    }
                    Err(e) => return Err(e),
                }
            };
            crate::files::set_blocking(f.as_raw_fd())?;
            Box::new(f)
        }
    })
}

/// Writes `bytes` to `path` ([module docs](self)): atomically for files.
pub fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    match target(path)? {
        Sink::File => write_with(path, |tmp| {
            let mut f = File::create(tmp)?;
            f.write_all(bytes)
        }),
        t => {
            let mut w = open_stream(path, t)?;
            w.write_all(bytes)?;
            w.flush()
        }
    }
}

/// Lets `fill` create and write a temporary file (for writers that open files themselves,
/// such as HDF5), then puts it at `path`: renamed over a regular file (synced first; the
/// temporary file, next to `path`, is removed if anything fails), or copied into a stream
/// target (the temporary file then lives in the system's temporary directory).
pub fn write_with<E: From<io::Error>>(
    path: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let t = target(path)?;
    if t != Sink::File {
        let tmp = tempfile::Builder::new().prefix(".baker-").tempfile()?;
        fill(tmp.path())?;
        let mut w = open_stream(path, t)?;
        io::copy(&mut File::open(tmp.path())?, &mut w)?;
        w.flush()?;
        return Ok(());
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    fs::create_dir_all(dir)?;
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "path has no file name"))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = fill(&tmp).and_then(|()| {
        File::open(&tmp)?.sync_all()?;
        // The target may have become something else while `fill` ran.
        if target(path)? != Sink::File {
            return Err(io::Error::other(format!(
                "{} changed into a special file while it was being written",
                crate::files::Shown(path)
            ))
            .into());
        }
        fs::rename(&tmp, path)?;
        Ok(())
    });
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_whole_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/a.txt");
        write(&p, b"one").unwrap();
        write(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(p.parent().unwrap()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn directories_are_refused_and_devices_stay_devices() {
        use std::os::unix::fs::FileTypeExt as _;
        let dir = tempfile::tempdir().unwrap();
        let e = write(dir.path(), b"x").unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        write(Path::new("/dev/null"), b"discarded").unwrap();
        write_with(Path::new("/dev/null"), |tmp| {
            std::fs::write(tmp, b"discarded")
        })
        .unwrap();
        assert!(std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());
    }
}
