//! Files in and out, safely: inputs must be regular files (a FIFO would
//! block for ever, `/dev/zero` would fill memory), settings files are read up
//! to [`MAX_SETTINGS_BYTES`], and outputs are written to a temporary file in
//! the same folder and renamed into place only when complete, so a full disk
//! or an error leaves no truncated file behind (issue 13).

use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Largest settings file (protocol, subject, study manifest, JSON result) read.
pub const MAX_SETTINGS_BYTES: u64 = 64 << 20;

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Open an input file after checking that it is a regular file.
pub fn open_input(path: &Path) -> Result<File> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a pipe, socket or device)"
        };
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!("{what}; expected a regular file"),
        });
    }
    File::open(path).map_err(|e| io_error(path, e))
}

/// Read a whole input file of at most `max_bytes` bytes.
pub fn read_bytes(path: &Path, max_bytes: u64) -> Result<Vec<u8>> {
    let file = open_input(path)?;
    // sized once from the file's length (growing by doubling copied a large file twice)
    let size = file.metadata().map_or(0, |m| m.len().min(max_bytes + 1));
    let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
    file.take(max_bytes + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| io_error(path, e))?;
    if bytes.len() as u64 > max_bytes {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "larger than the {max_bytes} bytes limpid reads for this kind of file"
            ),
        });
    }
    Ok(bytes)
}

/// Read a settings file (UTF-8 text of at most [`MAX_SETTINGS_BYTES`]).
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = read_bytes(path, MAX_SETTINGS_BYTES)?;
    String::from_utf8(bytes).map_err(|e| Error::Format {
        path: path.to_path_buf(),
        message: format!(
            "not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })
}

/// Write `path` through `write`: into a temporary file beside it, renamed
/// into place only when `write` succeeded and the data reached the disk.
pub fn write_atomic<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<T>,
) -> Result<T> {
    let tmp = temporary_name(path);
    let file = File::create(&tmp).map_err(|e| io_error(path, e))?;
    let mut w = BufWriter::new(file);
    let outcome = write(&mut w).and_then(|v| {
        w.flush().map_err(|e| io_error(path, e))?;
        w.get_ref().sync_all().map_err(|e| io_error(path, e))?;
        Ok(v)
    });
    drop(w);
    match outcome {
        Ok(v) => {
            std::fs::rename(&tmp, path).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                io_error(path, e)
            })?;
            Ok(v)
        }
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Write bytes to `path` atomically.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes).map_err(|e| io_error(path, e)))
}

/// `.name.limpid-tmp-PID` beside `path` (hidden, unique per process).
fn temporary_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    path.with_file_name(format!(".{name}.limpid-tmp-{}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_refused_before_opening() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let e = read_text(Path::new("/")).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
    }

    #[test]
    fn a_failed_write_leaves_no_file_and_keeps_the_old_one() {
        let dir = std::env::temp_dir().join(format!("limpid-files-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("out.csv");
        write_file(&path, b"old").unwrap();
        let r: Result<()> = write_atomic(&path, |w| {
            w.write_all(b"partial").unwrap();
            Err(Error::invalid("test", "disk full"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        let leftovers = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(leftovers, 1, "the temporary file was removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
