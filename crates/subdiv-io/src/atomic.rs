//! Atomic file writes: a failed write never leaves a half-written file at the target path.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::IoError;

/// Writes `path` through `write`: first to `<path>.tmp` in the same directory (so the rename
/// stays on one file system and is atomic), synced to disk, then renamed over `path`. On any
/// failure the temporary file is removed and `path` is left as it was.
///
/// A plain sibling file rather than a `tempfile` one: the output then gets the permissions a
/// newly created file normally gets (the umask's), not `tempfile`'s private 0600.
pub fn write_file(path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>) -> Result<(), IoError> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let result = (|| {
        let mut writer = BufWriter::new(File::create(&tmp)?);
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
    result.map_err(|source| IoError::Io { path: path.to_owned(), source })
}
