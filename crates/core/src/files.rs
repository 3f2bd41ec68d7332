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
///
/// Only a regular file (or a new one) is replaced so: a symbolic link is
/// followed and its target written (atomically when that is a regular file),
/// and a FIFO, device or socket (`-o /dev/stdout`) is written through, never
/// replaced by a regular file (as root, a rename over `/dev/null` would
/// replace the device node). A directory is refused.
pub fn write_atomic<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<T>,
) -> Result<T> {
    let target = match output_target(path)? {
        OutputTarget::Replace(target) => target,
        OutputTarget::Through(target) => return write_through(&target, write),
    };
    let path = target.as_path();
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

/// Where an output goes: a regular (or new) file, replaced by renaming a
/// temporary over it, or something written through in place.
enum OutputTarget {
    Replace(PathBuf),
    Through(PathBuf),
}

/// The target of an output path: a symbolic link is followed (a dangling
/// one written through, creating its target), a FIFO, device or socket is
/// written through, a directory is refused naming `path`.
fn output_target(path: &Path) -> Result<OutputTarget> {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return Ok(OutputTarget::Replace(path.to_path_buf()));
    };
    let mut target = path.to_path_buf();
    if meta.file_type().is_symlink() {
        match std::fs::canonicalize(path) {
            Ok(t) => target = t,
            Err(_) => return Ok(OutputTarget::Through(target)),
        }
    }
    match std::fs::metadata(&target).map(|m| m.file_type()) {
        Ok(kind) if kind.is_dir() => Err(Error::Format {
            path: path.to_path_buf(),
            message: "is a directory, not a file to write".into(),
        }),
        Ok(kind) if !kind.is_file() => Ok(OutputTarget::Through(target)),
        _ => Ok(OutputTarget::Replace(target)),
    }
}

/// Write into `path` as it is (a FIFO, a device, a dangling link's target):
/// opened for writing, created if missing, never renamed over.
fn write_through<T>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<T>,
) -> Result<T> {
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(path)
        .map_err(|e| io_error(path, e))?;
    let mut w = BufWriter::new(file);
    let v = write(&mut w)?;
    w.flush().map_err(|e| io_error(path, e))?;
    Ok(v)
}

/// Make the output folder `dir` (and its parents). A path that exists but is
/// not a folder is one clear error, not "File exists (os error 17)".
pub fn create_dir(dir: &Path) -> Result<()> {
    if let Ok(meta) = std::fs::metadata(dir) {
        if !meta.is_dir() {
            return Err(Error::Format {
                path: dir.to_path_buf(),
                message: "exists and is not a folder; name a folder for the outputs".into(),
            });
        }
        return Ok(());
    }
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, e))
}

/// Write bytes to `path` atomically.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |w| w.write_all(bytes).map_err(|e| io_error(path, e)))
}

/// Before a long computation: can a file be written at `path`? Its folder
/// must exist (outputs do not make folders for files) and `path` must not be
/// a folder. The write itself may still fail (permissions, a full disk).
pub fn check_output_path(path: &Path) -> Result<()> {
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(folder) = folder {
        if !folder.is_dir() {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "cannot be written: {} is not an existing folder",
                    folder.display()
                ),
            });
        }
    }
    if path.is_dir() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: "is a directory, not a file to write".into(),
        });
    }
    Ok(())
}

/// Several outputs of one command written as a set (issue 36): each file is
/// staged into a temporary file beside it as it is added, and all are
/// renamed into place by [`OutputSet::commit`]. If any staging fails (a
/// full disk, a folder that cannot be written) or the set is dropped
/// uncommitted, the temporaries are removed and none of the set's files is
/// written. Outputs that are not regular files (FIFOs, devices) are written
/// through at commit; links are followed, as in [`write_atomic`].
#[derive(Debug, Default)]
pub struct OutputSet {
    staged: Vec<(PathBuf, PathBuf)>,
    through: Vec<(PathBuf, Vec<u8>)>,
    folders: Vec<PathBuf>,
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Stage `bytes` for `path`; returns `path`.
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<PathBuf> {
        let target = match output_target(path)? {
            OutputTarget::Replace(target) => target,
            OutputTarget::Through(target) => {
                self.through.push((target, bytes.to_vec()));
                return Ok(path.to_path_buf());
            }
        };
        if self.staged.iter().any(|(_, t)| t == &target) {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: "named twice among this command's outputs".into(),
            });
        }
        let tmp = temporary_name(&target);
        let staged = (|| -> std::io::Result<()> {
            let mut file = File::create(&tmp)?;
            file.write_all(bytes)?;
            file.sync_all()
        })();
        if let Err(e) = staged {
            let _ = std::fs::remove_file(&tmp);
            return Err(io_error(path, e));
        }
        self.staged.push((tmp, target));
        Ok(path.to_path_buf())
    }

    /// Make an output folder (and its parents) as [`create_dir`] does; the
    /// folders it made are removed again if the set is not committed.
    pub fn create_dir(&mut self, dir: &Path) -> Result<()> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(p.to_path_buf());
            d = p.parent();
        }
        create_dir(dir)?;
        // innermost first, so that removing them in order empties each parent
        self.folders.extend(missing);
        Ok(())
    }

    /// Rename every staged file into place and write the others through.
    pub fn commit(mut self) -> Result<()> {
        self.folders.clear();
        for (tmp, target) in std::mem::take(&mut self.staged) {
            std::fs::rename(&tmp, &target).map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                io_error(&target, e)
            })?;
        }
        for (path, bytes) in std::mem::take(&mut self.through) {
            write_through(&path, |w| {
                w.write_all(&bytes).map_err(|e| io_error(&path, e))
            })?;
        }
        Ok(())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        for (tmp, _) in &self.staged {
            let _ = std::fs::remove_file(tmp);
        }
        for dir in &self.folders {
            // only if empty: a folder the user filled meanwhile stays
            let _ = std::fs::remove_dir(dir);
        }
    }
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
    fn an_output_set_is_written_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("limpid-set-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // the second file's folder does not exist: the first is not written,
        // and the folder the set made is gone again
        let mut set = OutputSet::new();
        set.create_dir(&dir.join("new/deeper")).unwrap();
        set.add(&dir.join("new/deeper/x.json"), b"x").unwrap();
        set.add(&dir.join("a.json"), b"a").unwrap();
        let e = set.add(&dir.join("missing/b.html"), b"b").unwrap_err();
        assert!(e.to_string().contains("missing/b.html"), "{e}");
        drop(set);
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(left.is_empty(), "{left:?}");
        // committed: both in place, no temporaries
        let mut set = OutputSet::new();
        set.add(&dir.join("a.json"), b"a").unwrap();
        set.add(&dir.join("b.html"), b"b").unwrap();
        assert!(!dir.join("a.json").exists());
        set.commit().unwrap();
        assert_eq!(std::fs::read(dir.join("a.json")).unwrap(), b"a");
        assert_eq!(std::fs::read(dir.join("b.html")).unwrap(), b"b");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
        // a folder as an output, or one path twice, is refused
        let mut set = OutputSet::new();
        assert!(set.add(&dir, b"x").is_err());
        set.add(&dir.join("c"), b"x").unwrap();
        assert!(set.add(&dir.join("c"), b"y").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn special_files_are_refused_before_opening() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let e = read_text(Path::new("/")).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
    }

    /// Outputs that are not regular files are written through, not replaced
    /// (a rename over them would turn a link, FIFO or device into a file).
    #[cfg(unix)]
    #[test]
    fn links_and_devices_are_written_through_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = std::env::temp_dir().join(format!("limpid-through-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // a link to a regular file: the target gets the bytes, the link stays a link
        let target = dir.join("target.csv");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("link.csv");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_file(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // a dangling link: its target is created
        let dangling = dir.join("dangling.csv");
        std::os::unix::fs::symlink(dir.join("made.csv"), &dangling).unwrap();
        write_file(&dangling, b"made").unwrap();
        assert!(std::fs::symlink_metadata(&dangling)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(dir.join("made.csv")).unwrap(), b"made");
        // a device stays a device
        write_file(Path::new("/dev/null"), b"discarded").unwrap();
        assert!(std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());
        // a FIFO: written through to its reader
        let fifo = dir.join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: mkfifo on a fresh path in our own temporary folder.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read(&fifo).unwrap())
        };
        write_file(&fifo, b"through").unwrap();
        assert_eq!(reader.join().unwrap(), b"through");
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        // a directory is refused in one line
        let e = write_file(&dir, b"x").unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
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
