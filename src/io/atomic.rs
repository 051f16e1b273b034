//! Atomic writes: write a temporary file in the target folder, then rename it over
//! the target. A crash or an error never leaves half a file under the real name.

use crate::error::{Error, Result};
use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The folder a path lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Fail with a clear message unless the folder of `path` exists.
pub fn check_folder(path: &Path) -> Result<()> {
    let folder = folder_of(path);
    if folder.is_dir() {
        Ok(())
    } else {
        Err(Error::file(
            path,
            format!("cannot write: the folder {} does not exist (create it first)", folder.display()),
        ))
    }
}

/// A temporary sibling name for `path`.
fn temp_name(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    folder_of(path).join(format!(".{name}.{}.tmp", std::process::id()))
}

/// Write `path` atomically with `body` filling a buffered writer.
pub fn write_file(path: &Path, body: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    check_folder(path)?;
    let temp = temp_name(path);
    let result = (|| {
        let file = File::create(&temp).map_err(|e| Error::io(path, e))?;
        let mut writer = BufWriter::new(file);
        body(&mut writer)?;
        writer.flush().map_err(|e| Error::io(path, e))?;
        let file = writer.into_inner().map_err(|e| Error::io(path, e.into_error()))?;
        file.sync_all().map_err(|e| Error::io(path, e))?;
        fs::rename(&temp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&temp);
    }
    result
}

/// Write `bytes` to `path` atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_file(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// Fill a folder atomically: `body` writes into a temporary sibling folder, which then
/// replaces `path` (an existing folder at `path` is removed only after success).
pub fn write_folder(path: &Path, body: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    check_folder(path)?;
    if path.exists() && !path.is_dir() {
        return Err(Error::file(path, "exists and is not a folder"));
    }
    let temp = temp_name(path);
    let _ = fs::remove_dir_all(&temp);
    let result = (|| {
        fs::create_dir(&temp).map_err(|e| Error::io(&temp, e))?;
        body(&temp)?;
        if path.exists() {
            fs::remove_dir_all(path).map_err(|e| Error::io(path, e))?;
        }
        fs::rename(&temp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        let _ = fs::remove_dir_all(&temp);
    }
    result
}

/// Read a whole file, naming it on failure.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    fs::read(path).map_err(|e| Error::io(path, e))
}
