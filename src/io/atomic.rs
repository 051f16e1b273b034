//! Safe writes and bounded reads.
//!
//! A file is written to a fresh temporary file in its own folder (a unique, unpredictable
//! name, created exclusively, so a planted link cannot redirect it) that is then renamed
//! over the target: a crash or an error never leaves half a file under the real name.
//!
//! A folder (a PNG slice stack, a set of masks) is written as a whole the same way, and
//! only where solidtex may write: a new or empty folder, or one holding just the files
//! solidtex listed there before in [`FOLDER_LIST`], each with the blake3 hash of what it
//! wrote, unchanged since. The new folder takes the old one's place in one step, and only
//! the files of that list are removed afterwards: solidtex never deletes a file it did not
//! write, nor one a person changed.
//!
//! Reads take regular files only (a pipe would block, a device never ends) and stop at a
//! size cap that follows from the voxel budget.

use crate::error::{Error, Result};
use std::fs::{self, File};
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The file in a folder solidtex wrote that lists the files it wrote there.
pub const FOLDER_LIST: &str = "solidtex-folder.txt";

/// The largest text file (manifest, fill spec, snapshot) solidtex reads.
pub const TEXT_CAP: u64 = 64 << 20;

/// The folder a path lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The last component of `path` as text, for temporary names.
fn name_of(path: &Path) -> String {
    path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "output".to_string())
}

/// The temporaries this process is writing, removed by [`remove_live_temporaries`] when it
/// is stopped (Ctrl-C, SIGTERM).
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Attempts at a temporary that another run's clean-up keeps taking away.
const ATTEMPTS: usize = 8;

/// A temporary's entry in [`LIVE`] and its advisory lock, held while it is written: other
/// runs' clean-up ([`remove_stale_temporaries`]) leaves a locked temporary alone.
struct Live {
    path: PathBuf,
    _lock: File,
}

impl Live {
    /// Register `path` in `list`, the registry held locked since before the temporary was
    /// made: a stop signal in between waits for it, then removes it too.
    fn new(list: &mut Vec<PathBuf>, path: &Path, lock: File) -> Live {
        list.push(path.to_path_buf());
        Live { path: path.to_path_buf(), _lock: lock }
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        live_paths().retain(|p| *p != self.path);
    }
}

fn live_paths() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Remove the temporaries this process is writing: for a stop signal, just before the
/// process exits. The registry stays locked for good after it, so no temporary made
/// meanwhile is left out (a thread that makes one waits until the exit).
pub fn remove_live_temporaries() {
    let live = live_paths();
    for path in live.iter() {
        let _ = match fs::symlink_metadata(path) {
            Ok(m) if m.is_dir() => fs::remove_dir_all(path),
            Ok(_) => fs::remove_file(path),
            Err(_) => Ok(()),
        };
    }
    std::mem::forget(live);
}

/// Lock the new temporary at `path` through `handle` (an open handle of it) and confirm that
/// `path` still names it: false when another run's clean-up took it before the lock (the
/// caller makes another). A file system without locks leaves it unlocked.
fn claim(path: &Path, handle: &File) -> bool {
    match handle.try_lock() {
        Ok(()) => is_same_file(path, handle),
        Err(std::fs::TryLockError::WouldBlock) => false,
        Err(std::fs::TryLockError::Error(_)) => true,
    }
}

#[cfg(unix)]
fn is_same_file(path: &Path, handle: &File) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (fs::symlink_metadata(path), handle.metadata()) {
        (Ok(named), Ok(held)) => (named.dev(), named.ino()) == (held.dev(), held.ino()),
        _ => false,
    }
}

#[cfg(not(unix))]
fn is_same_file(path: &Path, _handle: &File) -> bool {
    path.exists()
}

/// A temporary file being written: registered and locked until persisted or dropped
/// (dropped, it is deleted).
struct TempFile {
    file: tempfile::NamedTempFile,
    _live: Live,
}

/// A temporary folder being written: registered and locked until kept or dropped
/// (dropped, it is deleted).
struct TempFolder {
    folder: tempfile::TempDir,
    live: Live,
}

impl TempFolder {
    /// Keep the folder (no longer deleted on drop nor on a stop signal).
    fn keep(self) -> PathBuf {
        let TempFolder { folder, live } = self;
        let path = folder.keep();
        drop(live);
        path
    }

    fn path(&self) -> &Path {
        self.folder.path()
    }
}

/// A temporary file for `path`, named `.NAME.solidtex-` + six random letters + `.tmp`, created
/// exclusively in the folder of `path`.
fn temporary_file(path: &Path) -> Result<TempFile> {
    let prefix = format!(".{}.solidtex-", name_of(path));
    for _ in 0..ATTEMPTS {
        let mut list = live_paths();
        let builder = tempfile::Builder::new().prefix(&prefix).suffix(".tmp").tempfile_in(folder_of(path));
        let file = builder.map_err(|e| Error::io(path, e))?;
        let lock = file.as_file().try_clone().map_err(|e| Error::io(path, e))?;
        if claim(file.path(), &lock) {
            let live = Live::new(&mut list, file.path(), lock);
            return Ok(TempFile { file, _live: live });
        }
    }
    Err(taken_away(path))
}

/// A temporary folder beside `path`, named like [`temporary_file`].
fn temporary_folder(path: &Path) -> Result<TempFolder> {
    let prefix = format!(".{}.solidtex-", name_of(path));
    for _ in 0..ATTEMPTS {
        let mut list = live_paths();
        let builder = tempfile::Builder::new().prefix(&prefix).suffix(".tmp").tempdir_in(folder_of(path));
        let folder = builder.map_err(|e| Error::io(path, e))?;
        let lock = File::open(folder.path()).map_err(|e| Error::io(path, e))?;
        if claim(folder.path(), &lock) {
            let live = Live::new(&mut list, folder.path(), lock);
            return Ok(TempFolder { folder, live });
        }
    }
    Err(taken_away(path))
}

fn taken_away(path: &Path) -> Error {
    Error::file(
        path,
        format!(
            "cannot write: each temporary made beside it was removed at once ({ATTEMPTS} attempts); is another program clearing that folder?"
        ),
    )
}

/// Whether a file name is one of solidtex's temporaries (left behind by a killed run).
pub fn is_temporary_name(name: &str) -> bool {
    temporary_stem(name).is_some()
}

/// The output name a temporary's name was made for (`NAME` of `.NAME.solidtex-XXXXXX.tmp`).
fn temporary_stem(name: &str) -> Option<&str> {
    // exactly the shape `temporary_file` and `temporary_folder` give: six random letters or digits
    let rest = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (stem, letters) = rest.rsplit_once(".solidtex-")?;
    let shaped = !stem.is_empty() && letters.len() == 6 && letters.bytes().all(|b| b.is_ascii_alphanumeric());
    shaped.then_some(stem)
}

/// Remove the temporaries in `folder` that stopped runs left (for the output named
/// `output` only, when given): files and folders of [`is_temporary_name`]'s shape whose lock
/// can be taken, so none that a running solidtex is writing. A link of that shape is
/// removed itself (solidtex makes none), never followed.
pub fn remove_stale_temporaries(folder: &Path, output: Option<&str>) {
    let Ok(entries) = fs::read_dir(folder) else { return };
    for entry in entries.filter_map(|e| e.ok()) {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(stem) = temporary_stem(&name) else { continue };
        if output.is_some_and(|o| o != stem) {
            continue;
        }
        let path = entry.path();
        let _ = match fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => fs::remove_file(&path),
            Ok(m) if m.is_dir() => remove_if_unlocked(&path, remove_stale_folder),
            Ok(m) if m.is_file() => remove_if_unlocked(&path, |p| fs::remove_file(p)),
            _ => Ok(()),
        };
    }
}

/// Remove a temporary folder a stopped run left. Without a [`FOLDER_LIST`] it is one
/// solidtex was still filling, all its own. With one it may be a previous folder swapped out
/// by a run stopped before clearing it, where files may have appeared meanwhile: only the
/// files the list vouches for go, and the folder only if nothing else is left.
fn remove_stale_folder(path: &Path) -> std::io::Result<()> {
    if !path.join(FOLDER_LIST).is_file() {
        return fs::remove_dir_all(path);
    }
    let listed = listed_files(path);
    for entry in fs::read_dir(path)?.filter_map(|e| e.ok()) {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name != FOLDER_LIST && why_foreign(path, &name, &listed, true).is_none() {
            fs::remove_file(entry.path())?;
        }
    }
    if fs::read_dir(path)?.count() == 1 {
        fs::remove_file(path.join(FOLDER_LIST))?;
        fs::remove_dir(path)?;
    }
    Ok(())
}

/// `remove` the temporary at `path` while holding its lock: no run is writing it.
fn remove_if_unlocked(path: &Path, remove: fn(&Path) -> std::io::Result<()>) -> std::io::Result<()> {
    let handle = File::open(path)?;
    match handle.try_lock() {
        Ok(()) => remove(path),
        Err(_) => Ok(()),
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

/// Refuse a file output that is a symbolic link: written atomically, the link itself would
/// be replaced by the new file (documents the user edits are written through their links,
/// [`write_document`]).
pub fn not_a_link(path: &Path) -> Result<()> {
    match fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_symlink() => Err(Error::usage(format!(
            "{}: is a symbolic link; solidtex neither replaces a link nor writes where it points (name the file \
             it points to, or another name)",
            path.display()
        ))),
        _ => Ok(()),
    }
}

/// Write `path` atomically with `body` filling a buffered writer.
pub fn write_file(path: &Path, body: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    check_folder(path)?;
    not_a_link(path)?;
    if path.is_dir() {
        return Err(Error::file(
            path,
            "is a folder; name a file to write (solidtex does not replace folders by files)",
        ));
    }
    remove_stale_temporaries(folder_of(path), Some(&name_of(path)));
    let temp = temporary_file(path)?;
    let file = temp.file.as_file().try_clone().map_err(|e| Error::io(path, e))?;
    let mut writer = BufWriter::new(file);
    body(&mut writer)?;
    writer.flush().map_err(|e| Error::io(path, e))?;
    temp.file.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    set_mode(temp.file.path(), path)?;
    temp.file.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// The temporary file gets the permissions of the file it replaces, or those a new file
/// gets from the process's umask (a temporary file is created private, 0600).
#[cfg(unix)]
fn set_mode(temp: &Path, path: &Path) -> Result<()> {
    use std::os::unix::fs::PermissionsExt;
    let mode = match fs::symlink_metadata(path) {
        Ok(meta) if meta.is_file() => meta.permissions().mode() & 0o7777,
        _ => 0o666 & !umask(),
    };
    fs::set_permissions(temp, fs::Permissions::from_mode(mode)).map_err(|e| Error::io(path, e))
}

#[cfg(not(unix))]
fn set_mode(_temp: &Path, _path: &Path) -> Result<()> {
    Ok(())
}

/// The process's umask, read without changing it (Linux: /proc/self/status); 022 when
/// it cannot be read.
#[cfg(unix)]
fn umask() -> u32 {
    let status = fs::read_to_string("/proc/self/status").unwrap_or_default();
    let line = status.lines().find_map(|l| l.strip_prefix("Umask:"));
    line.and_then(|v| u32::from_str_radix(v.trim(), 8).ok()).unwrap_or(0o022)
}

/// Write a document the user edits in place (a manifest) atomically: through a symbolic
/// link to the file it names, keeping that file's permissions. A read-only document (no
/// write permission for anyone) is refused, whoever runs solidtex: its owner protected it.
pub fn write_document(path: &Path, bytes: &[u8]) -> Result<()> {
    let linked = fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
    let target = if linked { fs::canonicalize(path).map_err(|e| Error::io(path, e))? } else { path.to_path_buf() };
    if read_only(&target) {
        return Err(Error::file(
            path,
            "is read-only: solidtex does not replace a file you protected (make it writable, e.g. chmod u+w, \
             or save under another name)",
        ));
    }
    write_bytes(&target, bytes)
}

/// Whether `path` exists with no write permission for anyone.
pub fn read_only(path: &Path) -> bool {
    fs::metadata(path).is_ok_and(|m| m.permissions().readonly())
}

/// Write `bytes` to `path` atomically.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_file(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// Fill the folder `path` as a whole: `body` writes into a new sibling folder, which then
/// takes the place of `path`. Refused unless [`writable_folder`] allows `path`.
pub fn write_folder(path: &Path, body: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let path = &without_trailing_slash(path);
    check_folder(path)?;
    let old = writable_folder(path)?;
    remove_stale_temporaries(folder_of(path), Some(&name_of(path)));
    let temp = temporary_folder(path)?;
    body(temp.path()).map_err(|e| named_in(e, temp.path(), path))?;
    write_list(temp.path()).map_err(|e| named_in(e, temp.path(), path).in_file(path))?;
    let temp = temp.keep();
    let placed = match &old {
        None => fs::rename(&temp, path).map_err(|e| Error::io(path, e)),
        Some(_) => swap_folders(&temp, path),
    };
    match (placed, old) {
        (Err(e), _) => {
            let _ = fs::remove_dir_all(&temp);
            Err(e)
        }
        // `temp` now holds the previous folder.
        (Ok(()), Some(names)) => remove_listed(&temp, &names, path),
        (Ok(()), None) => Ok(()),
    }
}

/// `path` without a trailing `/`: `link/` names the link itself, as `link` does, where the
/// file system would follow it to its folder.
fn without_trailing_slash(path: &Path) -> PathBuf {
    path.components().collect()
}

/// `e` naming, instead of a file in the temporary folder `temp`, that file in `path`: the
/// folder the user named, which the temporary one becomes.
fn named_in(e: Error, temp: &Path, path: &Path) -> Error {
    let moved = |file: PathBuf| match file.strip_prefix(temp) {
        Ok(rest) if rest.as_os_str().is_empty() => path.to_path_buf(),
        Ok(rest) => path.join(rest),
        Err(_) => file,
    };
    match e {
        Error::Io { path: file, source } => Error::Io { path: moved(file), source },
        Error::File { path: file, message } => Error::File { path: moved(file), message },
        other => other,
    }
}

/// The names a folder holds, or `None` when there is no folder at `path`; an error unless
/// solidtex may replace it: a real folder (not a link), not the current folder or one above
/// it, and holding nothing but the files its [`FOLDER_LIST`] names.
pub fn writable_folder(path: &Path) -> Result<Option<Vec<String>>> {
    let path = &without_trailing_slash(path);
    let meta = match fs::symlink_metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(path, e)),
    };
    if meta.file_type().is_symlink() {
        return Err(Error::file(path, "is a symbolic link; solidtex writes a folder output only at a real folder"));
    }
    if !meta.is_dir() {
        return Err(Error::file(path, "exists and is not a folder; solidtex does not replace it by a folder"));
    }
    if holds_current_folder(path) {
        return Err(Error::file(
            path,
            "is the current folder (or holds it); write a folder output into a new folder, e.g. slices/",
        ));
    }
    let names = folder_names(path)?;
    let listed = listed_files(path);
    let foreign: Vec<(&String, &str)> = names
        .iter()
        .filter(|n| *n != FOLDER_LIST)
        .filter_map(|n| why_foreign(path, n, &listed, names.iter().any(|n| n == FOLDER_LIST)).map(|w| (n, w)))
        .collect();
    if let Some((first, why)) = foreign.first() {
        return Err(Error::file(
            path,
            format!(
                "holds {} file(s) solidtex may not replace (e.g. {first:?}, which {why}); solidtex writes a folder \
                 output only where the folder is new, empty, or holds what it wrote before, unchanged (listed with \
                 their hashes in {FOLDER_LIST}); move those files away or choose a new folder",
                foreign.len()
            ),
        ));
    }
    Ok(Some(names))
}

/// Whether the current working folder is `path` or lies inside it.
pub fn holds_current_folder(path: &Path) -> bool {
    match (fs::canonicalize(path), std::env::current_dir().and_then(fs::canonicalize)) {
        (Ok(folder), Ok(current)) => current.starts_with(folder),
        _ => false,
    }
}

/// The entry names of a folder, sorted.
fn folder_names(path: &Path) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for entry in fs::read_dir(path).map_err(|e| Error::io(path, e))? {
        let entry = entry.map_err(|e| Error::io(path, e))?;
        names.push(entry.file_name().to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}

/// Why the file `name` of the folder `path` is not solidtex's to replace, given the list
/// of what it wrote there, if the folder has one (`None`: it is).
fn why_foreign(path: &Path, name: &str, listed: &[(String, Option<String>)], has_list: bool) -> Option<&'static str> {
    match listed.iter().find(|(n, _)| n == name) {
        // a file another command put into solidtex's folder (a fill's model beside the
        // drawn meshes) is solidtex's, but not this folder's
        None if has_list => Some("is not among the files solidtex wrote as this folder"),
        None => Some("solidtex did not write"),
        Some((_, None)) => Some("an older solidtex listed without a content hash, so a change cannot be told"),
        Some((_, Some(hash))) if file_hash(&path.join(name)).as_deref() == Some(hash) => None,
        Some(_) => Some("was changed since solidtex wrote it"),
    }
}

/// The blake3 hash (hex) of a regular file's content; `None` for anything else.
pub fn file_hash(path: &Path) -> Option<String> {
    if !fs::symlink_metadata(path).is_ok_and(|m| m.is_file()) {
        return None;
    }
    let mut hasher = blake3::Hasher::new();
    let file = File::open(path).ok()?;
    hasher.update_reader(file).ok()?;
    Some(hasher.finalize().to_hex().to_string())
}

/// The plain file names the folder's [`FOLDER_LIST`] names, each with the hash recorded
/// for it (`None` in a list written before hashes were recorded).
fn listed_files(path: &Path) -> Vec<(String, Option<String>)> {
    let list = path.join(FOLDER_LIST);
    let is_small_file = fs::symlink_metadata(&list).is_ok_and(|m| m.is_file() && m.len() <= TEXT_CAP);
    let text = if is_small_file { fs::read_to_string(&list).unwrap_or_default() } else { String::new() };
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| match l.split_once("  ") {
            Some((hash, name)) if hash.len() == 64 && hash.bytes().all(|b| b.is_ascii_hexdigit()) => {
                (name.to_string(), Some(hash.to_string()))
            }
            _ => (l.to_string(), None),
        })
        .filter(|(name, _)| !name.contains('/') && name != "." && name != "..")
        .collect()
}

/// Give the [`FOLDER_LIST`] of `folder`, written by a solidtex that recorded names only,
/// the hashes of its files when `known(name, hash)` vouches for every one (a build's
/// records hold them); otherwise leave it as it is.
pub fn upgrade_list(folder: &Path, known: impl Fn(&str, &str) -> bool) -> Result<()> {
    let listed = listed_files(folder);
    if listed.is_empty() || listed.iter().all(|(_, hash)| hash.is_some()) {
        return Ok(());
    }
    let vouched = listed.iter().all(|(name, _)| file_hash(&folder.join(name)).is_none_or(|h| known(name, &h)));
    if vouched && folder_names(folder)?.iter().all(|n| n == FOLDER_LIST || listed.iter().any(|(l, _)| l == n)) {
        write_list(folder)?;
    }
    Ok(())
}

/// Write the [`FOLDER_LIST`] of a freshly written folder: each file's hash and name.
fn write_list(folder: &Path) -> Result<()> {
    let mut text = String::from(
        "# Written by solidtex: the files it wrote here, each after the blake3 hash of its content.\n\
         # It replaces this folder as a whole when it writes it again, and refuses while any other\n\
         # file is present or a listed file was changed.\n",
    );
    for name in folder_names(folder)?.into_iter().filter(|n| n != FOLDER_LIST) {
        let path = folder.join(&name);
        let hash = file_hash(&path).ok_or_else(|| Error::file(&path, "cannot be read back to record its hash"))?;
        text.push_str(&format!("{hash}  {name}\n"));
    }
    fs::write(folder.join(FOLDER_LIST), text).map_err(|e| Error::io(folder.join(FOLDER_LIST), e))
}

/// Put the folder `fresh` at `path` and the folder that was at `path` at `fresh`, in one
/// step where the system allows it; otherwise move the old folder aside first and back on
/// failure.
fn swap_folders(fresh: &Path, path: &Path) -> Result<()> {
    #[cfg(target_os = "linux")]
    {
        use rustix::fs::{CWD, RenameFlags, renameat_with};
        if renameat_with(CWD, fresh, CWD, path, RenameFlags::EXCHANGE).is_ok() {
            return Ok(());
        }
    }
    let aside = temporary_folder(path)?.keep();
    fs::rename(path, &aside).map_err(|e| Error::io(path, e))?;
    if let Err(e) = fs::rename(fresh, path) {
        let _ = fs::rename(&aside, path);
        return Err(Error::io(path, e));
    }
    fs::rename(&aside, fresh).map_err(|e| Error::io(fresh, e))
}

/// Remove the previous folder, now at `old`: only the files it was checked to hold.
fn remove_listed(old: &Path, names: &[String], path: &Path) -> Result<()> {
    for name in names {
        let file = old.join(name);
        if fs::symlink_metadata(&file).is_ok_and(|m| m.is_file()) {
            let _ = fs::remove_file(file);
        }
    }
    if fs::remove_dir(old).is_ok() {
        return Ok(());
    }
    // Files appeared in the old folder while solidtex wrote: keep it under a visible name
    // that no clean-up of temporaries matches.
    let kept = keep_aside(old, path).unwrap_or_else(|| old.to_path_buf());
    Err(Error::file(
        path,
        format!(
            "written; the previous folder was kept as {}, because files appeared in it while solidtex wrote \
             (look there)",
            kept.display()
        ),
    ))
}

/// Move `old` to a new sibling `NAME.kept-<random letters>` of `path`.
fn keep_aside(old: &Path, path: &Path) -> Option<PathBuf> {
    let prefix = format!("{}.kept-", name_of(path));
    let target = tempfile::Builder::new().prefix(&prefix).tempdir_in(folder_of(path)).ok()?.keep();
    if fs::rename(old, &target).is_err() {
        // The empty folder made for it here, and nothing else.
        let _ = fs::remove_dir(&target);
        return None;
    }
    Some(target)
}

/// The size cap for a volume file read within `budget` bytes of samples: the samples,
/// a quarter more for file overheads, and a megabyte for headers.
pub fn file_cap(budget: u64) -> u64 {
    budget.saturating_add(budget / 4).saturating_add(1 << 20)
}

/// Read a whole regular file of at most `cap` bytes, naming it on failure.
pub fn read_bytes_within(path: &Path, cap: u64) -> Result<Vec<u8>> {
    let file = open_regular(path, cap)?;
    let mut bytes = Vec::new();
    file.take(cap.saturating_add(1)).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(too_large(path, cap));
    }
    Ok(bytes)
}

/// Read a whole regular file within the cap of the voxel budget (`SOLIDTEX_MAX_BYTES`).
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    read_bytes_within(path, file_cap(super::budget_from_env()?))
}

/// Read a UTF-8 text file of at most [`TEXT_CAP`] bytes; `what` names the kind of file
/// (e.g. "manifest") in the error. A file that is not text is not quoted.
pub fn read_text(path: &Path, what: &str) -> Result<String> {
    let bytes = read_bytes_within(path, TEXT_CAP)?;
    String::from_utf8(bytes).map_err(|e| {
        Error::file(
            path,
            format!(
                "is not UTF-8 text (invalid byte at offset {}); a {what} is a text file",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// Open `path` for reading if it is a regular file of at most `cap` bytes.
pub fn open_regular(path: &Path, cap: u64) -> Result<File> {
    let meta = fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() { "a folder" } else { "not a regular file (a device, pipe or socket)" };
        return Err(Error::file(path, format!("is {kind}; solidtex reads this input only from a regular file")));
    }
    if meta.len() > cap {
        return Err(too_large(path, cap));
    }
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let opened = file.metadata().map_err(|e| Error::io(path, e))?;
    if !opened.is_file() {
        return Err(Error::file(path, "is not a regular file; solidtex reads this input only from a regular file"));
    }
    Ok(file)
}

fn too_large(path: &Path, cap: u64) -> Error {
    Error::file(
        path,
        format!(
            "is larger than {cap} bytes, the most solidtex reads for this kind of file (for volumes, meshes and \
             models the limit follows the voxel budget, SOLIDTEX_MAX_BYTES)"
        ),
    )
}

/// A path's canonical form when it exists.
pub fn canonical(path: &Path) -> Option<PathBuf> {
    fs::canonicalize(path).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of another's in a folder solidtex wrote is named as not this folder's (it may
    /// be solidtex's own, written by another command); in a folder without solidtex's list,
    /// as a file solidtex did not write. Either way the folder is left as it was.
    #[test]
    fn a_file_added_to_a_written_folder_is_named_as_not_the_folders() {
        let dir = tempfile::tempdir().unwrap();
        let ours = dir.path().join("ours");
        write_folder(&ours, |d| write_bytes(&d.join("a.obj"), b"mesh")).unwrap();
        fs::write(ours.join("a.lst"), b"model").unwrap();
        let error = write_folder(&ours, |d| write_bytes(&d.join("a.obj"), b"mesh 2")).unwrap_err().to_string();
        assert!(error.contains("\"a.lst\", which is not among the files solidtex wrote as this folder"), "{error}");
        assert_eq!(fs::read(ours.join("a.obj")).unwrap(), b"mesh");
        let theirs = dir.path().join("theirs");
        fs::create_dir(&theirs).unwrap();
        fs::write(theirs.join("notes.txt"), b"mine").unwrap();
        let error = write_folder(&theirs, |d| write_bytes(&d.join("a.obj"), b"mesh")).unwrap_err().to_string();
        assert!(error.contains("\"notes.txt\", which solidtex did not write"), "{error}");
    }

    /// The clean-up of an interrupted build matches the names solidtex gives its
    /// temporaries and nothing a user could plausibly name alike.
    #[test]
    fn only_solidtex_temporaries_match() {
        let dir = tempfile::tempdir().unwrap();
        let file = temporary_file(&dir.path().join("kiwi.exr")).unwrap();
        let folder = temporary_folder(&dir.path().join("kiwi_slices")).unwrap();
        for made in [file.file.path(), folder.path()] {
            let name = made.file_name().unwrap().to_string_lossy().into_owned();
            assert!(is_temporary_name(&name), "{name}");
        }
        for user in
            [".notes.solidtex-draft.tmp", ".solidtex-abc123.tmp", "kiwi.solidtex-abc123.tmp", ".a.solidtex-abc12!.tmp"]
        {
            assert!(!is_temporary_name(user), "{user}");
        }
    }

    /// A temporary is listed and locked while written, and listed no more once persisted,
    /// kept or dropped.
    #[test]
    fn temporaries_are_listed_while_written() {
        let dir = tempfile::tempdir().unwrap();
        let listed = |p: &Path| live_paths().iter().any(|l| l == p);
        let file = temporary_file(&dir.path().join("a.exr")).unwrap();
        let folder = temporary_folder(&dir.path().join("b")).unwrap();
        let (file_path, folder_path) = (file.file.path().to_path_buf(), folder.path().to_path_buf());
        assert!(listed(&file_path) && listed(&folder_path));
        let other = File::open(&file_path).unwrap();
        assert!(matches!(other.try_lock(), Err(std::fs::TryLockError::WouldBlock)), "the writer holds the lock");
        file.file.persist(dir.path().join("a.exr")).unwrap();
        drop(file._live);
        let kept = folder.keep();
        assert!(!listed(&file_path) && !listed(&folder_path) && kept.is_dir());
        let dropped = temporary_file(&dir.path().join("c.exr")).unwrap();
        let dropped_path = dropped.file.path().to_path_buf();
        drop(dropped);
        assert!(!listed(&dropped_path) && !dropped_path.exists());
    }

    /// The clean-up of stale temporaries removes those of the output asked for whose lock
    /// is free (files and folders), and keeps one a running writer holds locked, those of
    /// other outputs, and files a user named alike.
    #[test]
    fn only_unlocked_temporaries_of_the_output_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let names = [".kiwi.exr.solidtex-aaaaaa.tmp", ".kiwi.exr.solidtex-bbbbbb.tmp", ".pear.exr.solidtex-cccccc.tmp"];
        for name in names {
            fs::write(d.join(name), "x").unwrap();
        }
        fs::create_dir(d.join(".kiwi.exr.solidtex-dddddd.tmp")).unwrap();
        fs::write(d.join(".kiwi.exr.solidtex-dddddd.tmp/z0000.png"), "x").unwrap();
        fs::write(d.join(".kiwi.exr.solidtex-draft.tmp"), "mine").unwrap();
        let writer = File::open(d.join(names[1])).unwrap();
        writer.lock().unwrap();
        remove_stale_temporaries(d, Some("kiwi.exr"));
        let left = folder_names(d).unwrap();
        assert_eq!(
            left,
            [".kiwi.exr.solidtex-bbbbbb.tmp", ".kiwi.exr.solidtex-draft.tmp", ".pear.exr.solidtex-cccccc.tmp"]
        );
        drop(writer);
        remove_stale_temporaries(d, None);
        assert_eq!(folder_names(d).unwrap(), [".kiwi.exr.solidtex-draft.tmp"]);
    }

    /// A stale temporary folder holding a previous folder (with its list) loses only the
    /// files the list vouches for; a file that appeared in it, and so the folder, stay.
    #[test]
    fn a_stale_swapped_out_folder_keeps_what_its_list_does_not_vouch_for() {
        let dir = tempfile::tempdir().unwrap();
        let stale = dir.path().join(".s.solidtex-eeeeee.tmp");
        fs::create_dir(&stale).unwrap();
        fs::write(stale.join("z0000.png"), "slice").unwrap();
        write_list(&stale).unwrap();
        fs::write(stale.join("notes.txt"), "mine").unwrap();
        remove_stale_temporaries(dir.path(), Some("s"));
        assert_eq!(folder_names(&stale).unwrap(), ["notes.txt", FOLDER_LIST]);
        fs::remove_file(stale.join("notes.txt")).unwrap();
        remove_stale_temporaries(dir.path(), Some("s"));
        assert!(!stale.exists(), "all vouched for: the folder goes");
    }

    /// A replaced file keeps its permissions, a new one gets the umask's; a document behind
    /// a link is written where the link points, the link kept.
    #[cfg(unix)]
    #[test]
    fn writes_keep_permissions_and_documents_follow_links() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
        let new = dir.path().join("new.txt");
        write_bytes(&new, b"a").unwrap();
        assert_eq!(mode(&new), 0o666 & !umask());
        fs::set_permissions(&new, fs::Permissions::from_mode(0o640)).unwrap();
        write_bytes(&new, b"b").unwrap();
        assert_eq!((mode(&new), fs::read(&new).unwrap()), (0o640, b"b".to_vec()));
        let link = dir.path().join("link.toml");
        std::os::unix::fs::symlink(&new, &link).unwrap();
        write_document(&link, b"c").unwrap();
        assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays");
        assert_eq!((fs::read(&new).unwrap(), mode(&new)), (b"c".to_vec(), 0o640));
    }
}
