//! Atomic file writes: a failed or interrupted write never leaves a half-written file at the
//! target path, and never writes through a file planted at the temporary path.

use std::collections::HashSet;
use std::collections::hash_map::RandomState;
use std::fs::{self, File, OpenOptions};
use std::hash::{BuildHasher, Hasher};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::IoError;

/// The temporary files being written now, for [`remove_temporary_files`].
static LIVE: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

/// Deletes every temporary file a writer of this crate is writing now. For signal handlers: a
/// program that exits on SIGINT or SIGTERM calls this first, so that no `<name>.<hex>.tmp` is
/// left beside its output. Safe to call from any thread at any time; a writer whose file was
/// removed fails (or renames nothing) and leaves its target as it was.
pub fn remove_temporary_files() {
    let live = LIVE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    for path in live.iter().flatten() {
        let _ = fs::remove_file(path);
    }
}

fn register(path: &Path) {
    let mut live = LIVE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    live.get_or_insert_with(HashSet::new).insert(path.to_owned());
}

fn unregister(path: &Path) {
    let mut live = LIVE.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some(live) = live.as_mut() {
        live.remove(path);
    }
}

/// 64 unpredictable bits: std's per-process random hash keys, mixed with a counter so that two
/// calls never repeat. (Uniqueness itself comes from `create_new`; randomness makes the name
/// hard to plant ahead.)
fn random_u64() -> u64 {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut hasher = RandomState::new().build_hasher();
    hasher.write_u64(COUNTER.fetch_add(1, Ordering::Relaxed));
    hasher.write_u32(std::process::id());
    hasher.finish()
}

/// Creates `<name>.<16 hex digits>.tmp` beside `path` with `create_new` (`O_EXCL`: an existing
/// file or symlink there is never opened or followed), registered for
/// [`remove_temporary_files`].
fn create_temporary(path: &Path) -> io::Result<(PathBuf, File)> {
    let name = path.file_name().ok_or_else(|| io::Error::other("the output path names no file"))?;
    loop {
        let mut tmp_name = name.to_owned();
        tmp_name.push(format!(".{:016x}.tmp", random_u64()));
        let tmp = path.with_file_name(tmp_name);
        // Registered before it exists, so a signal between creation and registration still
        // finds it.
        register(&tmp);
        match OpenOptions::new().read(true).write(true).create_new(true).open(&tmp) {
            Ok(file) => return Ok((tmp, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => unregister(&tmp),
            Err(e) => {
                unregister(&tmp);
                return Err(e);
            }
        }
    }
}

/// Writes `path` through `write`: first to a fresh `<name>.<16 hex>.tmp` in the same directory
/// (so the rename stays on one file system and is atomic), synced to disk, then renamed over
/// `path`. On any failure the temporary file is removed and `path` is left as it was.
///
/// Not a `tempfile` file: the output then gets the permissions a newly created file normally
/// gets (the umask's), not `tempfile`'s private 0600.
pub(crate) fn write_file(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), IoError> {
    let result = create_temporary(path).and_then(|(tmp, file)| {
        let result = (|| {
            let mut writer = BufWriter::new(file);
            write(&mut writer)?;
            writer.flush()?;
            writer.get_ref().sync_all()?;
            drop(writer);
            fs::rename(&tmp, path)
        })();
        if result.is_err() {
            // The write already failed; a leftover temporary file is the lesser problem.
            let _ = fs::remove_file(&tmp);
        }
        unregister(&tmp);
        result
    });
    result.map_err(|source| IoError::Io { path: path.to_owned(), source })
}

/// A scratch file beside an output (`<name>.<16 hex>.tmp`, as [`write_file`]'s, so that
/// [`remove_temporary_files`] removes it too): written through a buffer, then copied into the
/// output; removed when dropped.
pub(crate) struct Scratch {
    path: PathBuf,
    writer: BufWriter<File>,
}

impl Scratch {
    /// A fresh scratch file beside `path`.
    pub(crate) fn beside(path: &Path) -> io::Result<Self> {
        let (tmp, file) = create_temporary(path)?;
        Ok(Self { path: tmp, writer: BufWriter::with_capacity(1 << 16, file) })
    }

    pub(crate) fn writer(&mut self) -> &mut BufWriter<File> {
        &mut self.writer
    }

    /// Everything written so far, appended to `w` (by the kernel where it can: `io::copy`
    /// between files takes `copy_file_range` on Linux).
    pub(crate) fn copy_into(&mut self, w: &mut BufWriter<File>) -> io::Result<()> {
        use std::io::Seek;
        self.writer.flush()?;
        let file = self.writer.get_mut();
        file.rewind()?;
        io::copy(file, w)?;
        Ok(())
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.path);
        unregister(&self.path);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Held by every test that writes a file, as `remove_temporary_files` removes every writer's.
    pub(crate) static WRITING: Mutex<()> = Mutex::new(());

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[cfg(unix)]
    #[test]
    fn a_symlink_planted_at_the_old_temporary_name_is_not_followed() {
        let _writing = WRITING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim");
        fs::write(&victim, "keep").unwrap();
        let out = dir.path().join("out.obj");
        std::os::unix::fs::symlink(&victim, dir.path().join("out.obj.tmp")).unwrap();
        write_file(&out, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read_to_string(&victim).unwrap(), "keep");
        assert_eq!(fs::read_to_string(&out).unwrap(), "new");
    }

    #[test]
    fn the_temporary_file_is_unique_registered_and_removed_on_error() {
        let _writing = WRITING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.glb");
        let failed = write_file(&out, |w| {
            let live = LIVE.lock().unwrap().clone().unwrap_or_default();
            let tmp = live.iter().find(|p| p.parent() == Some(dir.path())).expect("registered").clone();
            let name = tmp.file_name().unwrap().to_str().unwrap().to_owned();
            let hex = name.strip_prefix("out.glb.").and_then(|n| n.strip_suffix(".tmp")).unwrap();
            assert!(hex.len() == 16 && hex.bytes().all(|b| b.is_ascii_hexdigit()), "{name}");
            w.write_all(b"partial")?;
            Err(io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(entries(dir.path()), Vec::<String>::new());
    }

    #[test]
    fn remove_temporary_files_deletes_a_file_being_written() {
        let _writing = WRITING.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.csv");
        let result = write_file(&out, |w| {
            w.write_all(b"partial")?;
            w.flush()?;
            remove_temporary_files();
            Ok(())
        });
        // The rename finds no file: the write fails, and nothing is left.
        assert!(result.is_err());
        assert_eq!(entries(dir.path()), Vec::<String>::new());
    }
}
