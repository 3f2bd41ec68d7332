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
    let file = open_through(path)?;
    let mut w = BufWriter::new(file);
    let v = write(&mut w)?;
    w.flush().map_err(|e| io_error(path, e))?;
    Ok(v)
}

/// How long an output FIFO may wait for its reader to open it.
const FIFO_READER_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Open `path` for writing in place. A FIFO is opened without blocking: one
/// that nothing reads would block the command for ever (issue 56), so it is
/// refused after [`FIFO_READER_WAIT`].
fn open_through(path: &Path) -> Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create(true).truncate(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
        let is_fifo = std::fs::metadata(path).is_ok_and(|m| m.file_type().is_fifo());
        if is_fifo {
            options.custom_flags(libc::O_NONBLOCK);
            let started = std::time::Instant::now();
            let file = loop {
                match options.open(path) {
                    Ok(file) => break file,
                    // ENXIO: no process has the FIFO open for reading
                    Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
                        if started.elapsed() >= FIFO_READER_WAIT {
                            return Err(Error::Format {
                                path: path.to_path_buf(),
                                message: "is a FIFO that nothing reads: start its reader first, or name a file".into(),
                            });
                        }
                        std::thread::sleep(std::time::Duration::from_millis(20));
                    }
                    Err(e) => return Err(io_error(path, e)),
                }
            };
            // writes block again (as to any pipe) once the reader is there
            use std::os::unix::io::AsRawFd;
            // SAFETY: fcntl on a descriptor this function owns, clearing one flag.
            unsafe {
                let fd = file.as_raw_fd();
                let flags = libc::fcntl(fd, libc::F_GETFL);
                if flags != -1 {
                    libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK);
                }
            }
            return Ok(file);
        }
    }
    options.open(path).map_err(|e| io_error(path, e))
}

/// The same file on disk: one inode (a hard link, a symbolic link, `./x`
/// and `x`), or, for paths not yet created, the same absolute path.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    match (absolute_path(a), absolute_path(b)) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    }
}

/// `path` made absolute through its existing part (links resolved), the
/// missing rest appended as written.
fn absolute_path(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = std::fs::canonicalize(path) {
        return Some(p);
    }
    let name = path.file_name()?;
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    let parent = match parent {
        Some(p) => absolute_path(p)?,
        None => std::env::current_dir().ok()?,
    };
    Some(parent.join(name))
}

/// Refuse, before any work, an output that is one of the command's inputs:
/// writing it would replace the file being read (`convert X -o X`,
/// `--map M --report M`; issue 56). `outputs` and `inputs` pair a path with
/// the flag or role that named it, for the message.
pub fn refuse_overwriting_inputs(
    outputs: &[(&Path, &str)],
    inputs: &[(&Path, &str)],
) -> Result<()> {
    for (out, out_role) in outputs {
        if let Some((_, in_role)) = inputs.iter().find(|(input, _)| same_file(out, input)) {
            return Err(Error::Format {
                path: out.to_path_buf(),
                message: format!(
                    "is both {out_role} and {in_role}; writing it would replace the input: name another output file"
                ),
            });
        }
    }
    for (i, (a, a_role)) in outputs.iter().enumerate() {
        if let Some((_, b_role)) = outputs[i + 1..].iter().find(|(b, _)| same_file(a, b)) {
            return Err(Error::Format {
                path: a.to_path_buf(),
                message: format!(
                    "named both as {a_role} and as {b_role}: name two different paths"
                ),
            });
        }
    }
    Ok(())
}

/// Make the output folder `dir` (and its parents). A path that exists but is
/// not a folder is one clear error, not "File exists (os error 17)".
pub fn create_dir(dir: &Path) -> Result<()> {
    check_output_folder(dir)?;
    if dir.is_dir() {
        return Ok(());
    }
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, e))
}

/// Before a long computation: `dir` is a folder or can be made as one (it,
/// or its nearest existing ancestor, is not a file).
pub fn check_output_folder(dir: &Path) -> Result<()> {
    let mut d = Some(dir);
    while let Some(p) = d.filter(|p| !p.as_os_str().is_empty()) {
        if let Ok(meta) = std::fs::metadata(p) {
            if !meta.is_dir() {
                return Err(Error::Format {
                    path: p.to_path_buf(),
                    message: "exists and is not a folder; name a folder for the outputs".into(),
                });
            }
            return Ok(());
        }
        d = p.parent();
    }
    Ok(())
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
        if self.staged.iter().any(|(_, file)| same_file(file, dir)) {
            return Err(Error::Format {
                path: dir.to_path_buf(),
                message:
                    "named both as an output file and as an output folder: name two different paths"
                        .into(),
            });
        }
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
    /// A failure part-way removes every temporary still staged (issue 56).
    pub fn commit(mut self) -> Result<()> {
        while let Some((tmp, target)) = self.staged.first().cloned() {
            // on an error `self` is dropped, removing this temporary and the rest
            std::fs::rename(&tmp, &target).map_err(|e| io_error(&target, e))?;
            self.staged.remove(0);
        }
        for (path, bytes) in std::mem::take(&mut self.through) {
            write_through(&path, |w| {
                w.write_all(&bytes).map_err(|e| io_error(&path, e))
            })?;
        }
        self.folders.clear();
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

    /// Issue 56: a FIFO nobody reads is refused instead of blocking for ever.
    #[cfg(unix)]
    #[test]
    fn a_fifo_without_a_reader_is_refused_not_waited_on() {
        let dir = std::env::temp_dir().join(format!("limpid-fifo-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: mkfifo on a fresh path in our own temporary folder.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let started = std::time::Instant::now();
        let e = write_file(&fifo, b"x").unwrap_err().to_string();
        assert!(e.contains("FIFO that nothing reads"), "{e}");
        assert!(started.elapsed() < std::time::Duration::from_secs(10));
        // the same through an output set
        let mut set = OutputSet::new();
        set.add(&fifo, b"x").unwrap();
        assert!(set
            .commit()
            .unwrap_err()
            .to_string()
            .contains("nothing reads"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 56: an output that is an input, by any name, is refused; so is
    /// one path named as two outputs, or as a file and a folder of one set.
    #[test]
    fn outputs_never_replace_inputs() {
        let dir = std::env::temp_dir().join(format!("limpid-same-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let input = dir.join("rec.csv");
        std::fs::write(&input, b"t\n0\n").unwrap();
        let dotted = dir.join("sub/../rec.csv");
        assert!(same_file(&input, &dotted));
        #[cfg(unix)]
        {
            let link = dir.join("link.csv");
            std::os::unix::fs::symlink(&input, &link).unwrap();
            assert!(same_file(&link, &input));
            let hard = dir.join("hard.csv");
            std::fs::hard_link(&input, &hard).unwrap();
            assert!(same_file(&hard, &input));
        }
        assert!(!same_file(&input, &dir.join("other.csv")));
        assert!(same_file(&dir.join("new.csv"), &dir.join("sub/../new.csv")));
        let e = refuse_overwriting_inputs(&[(&dotted, "-o")], &[(&input, "the recording")])
            .unwrap_err()
            .to_string();
        assert!(e.contains("is both -o and the recording"), "{e}");
        refuse_overwriting_inputs(
            &[(&dir.join("out.csv"), "-o")],
            &[(&input, "the recording")],
        )
        .unwrap();
        let e = refuse_overwriting_inputs(
            &[
                (&dir.join("r.html"), "-o"),
                (&dir.join("r.html"), "--figures"),
            ],
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("named both as -o and as --figures"), "{e}");
        let mut set = OutputSet::new();
        set.add(&dir.join("r.html"), b"page").unwrap();
        let e = set.create_dir(&dir.join("r.html")).unwrap_err().to_string();
        assert!(e.contains("output file and as an output folder"), "{e}");
        drop(set);
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("limpid-tmp") || n == "r.html")
            .collect();
        assert!(left.is_empty(), "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Issue 56: a commit that fails part-way leaves no temporary behind.
    #[test]
    fn a_failed_commit_removes_its_temporaries() {
        let dir = std::env::temp_dir().join(format!("limpid-commit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let mut set = OutputSet::new();
        set.add(&dir.join("a.html"), b"a").unwrap();
        set.add(&dir.join("b.svg"), b"b").unwrap();
        // a folder appears where the first file goes, after staging
        std::fs::create_dir(dir.join("a.html")).unwrap();
        std::fs::write(dir.join("a.html/keep"), b"k").unwrap();
        assert!(set.commit().is_err());
        let mut left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["a.html"], "temporaries left");
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
