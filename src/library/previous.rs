//! An entry's previous build, kept while a new one is compared with it:
//! `OUTPUT/.cache/previous/NAME/` holds the old record and a copy of every file it lists.
//! Accepting the new build drops the copy; discarding it puts the old files and record
//! back and removes the files only the new build wrote. Only files the records list (files
//! solidtex wrote) are ever copied, replaced or removed.

use super::cache::{self, Record};
use super::files::CACHE;
use crate::error::{Error, Result};
use crate::io;
use std::path::{Component, Path, PathBuf};

/// The folder holding exemplar `name`'s previous build. A name the manifest does not
/// allow (a broken entry's, say `../x`) gets a folder no build ever fills.
pub fn folder(output: &Path, name: &str) -> PathBuf {
    let allowed = !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    let previous = output.join(CACHE).join("previous");
    if allowed { previous.join(name) } else { previous.join("-") }
}

const RECORD: &str = "record.json";

/// The previous build's record, when one is kept.
pub fn record(output: &Path, name: &str) -> Option<Record> {
    serde_json::from_slice(&io::atomic::read_bytes(&folder(output, name).join(RECORD)).ok()?).ok()
}

/// The previous build's volume file, when one is kept.
pub fn volume(output: &Path, name: &str) -> Option<PathBuf> {
    record(output, name).map(|_| folder(output, name).join(format!("{name}.exr")))
}

/// Keep a copy of exemplar `name`'s current build, unless one is kept already (the copy is
/// the last accepted build) or there is no build. Returns whether it copied.
pub fn keep(output: &Path, name: &str) -> Result<bool> {
    if record(output, name).is_some() {
        return Ok(false);
    }
    let Some(current) = cache::read_record(output, name) else { return Ok(false) };
    if !current.files.iter().all(|f| output.join(&f.path).is_file()) {
        return Ok(false);
    }
    let kept = folder(output, name);
    for file in current.files.iter().filter(|f| listed(&f.path)) {
        copy(&output.join(&file.path), &kept.join(&file.path))?;
    }
    let json = serde_json::to_string_pretty(&current).expect("a record always serializes");
    io::write_bytes(&kept.join(RECORD), json.as_bytes())?;
    Ok(true)
}

/// Accept the new build: the kept copy goes — only the files its record lists and the
/// record, then the folders they leave empty; anything else in the folder stays.
pub fn drop_kept(output: &Path, name: &str) -> Result<()> {
    let Some(old) = record(output, name) else { return Ok(()) };
    let kept = folder(output, name);
    if !real_folders(output, kept.strip_prefix(output).unwrap_or(&kept)) {
        return Ok(());
    }
    for file in old.files.iter().filter(|f| listed(&f.path)) {
        remove_written(&kept, Path::new(&file.path))?;
        // the folders the file was in, if it leaves them empty (a mask folder)
        for parent in Path::new(&file.path).ancestors().skip(1).filter(|p| !p.as_os_str().is_empty()) {
            if real_folders(&kept, parent) {
                let _ = std::fs::remove_dir(kept.join(parent));
            }
        }
    }
    remove_written(&kept, Path::new(RECORD))?;
    let _ = std::fs::remove_dir(&kept);
    Ok(())
}

/// Whether `path` (from a record) names a file below the folder it is relative to: no
/// root, no `..`.
fn listed(path: &str) -> bool {
    Path::new(path).components().all(|c| matches!(c, Component::Normal(_)))
}

/// Whether every step of `relative` below `base` is a folder, not a link (a link in the
/// cache could lead a removal into a user's folder).
fn real_folders(base: &Path, relative: &Path) -> bool {
    let mut at = base.to_path_buf();
    relative.components().all(|c| {
        at.push(c);
        std::fs::symlink_metadata(&at).is_ok_and(|m| m.is_dir())
    })
}

/// Removes the regular file `relative` below `base` when it is one and no folder on the way
/// is a link (a link or a folder there is left alone); a file already gone is fine.
fn remove_written(base: &Path, relative: &Path) -> Result<()> {
    if !relative.parent().is_none_or(|parent| real_folders(base, parent)) {
        return Ok(());
    }
    let path = base.join(relative);
    match std::fs::symlink_metadata(&path) {
        Ok(meta) if meta.is_file() => std::fs::remove_file(&path).map_err(|e| Error::io(&path, e)),
        _ => Ok(()),
    }
}

/// Discard the new build: the kept files and record go back, the files only the new build
/// wrote are removed, and the copy goes. A file of the new build that is not as solidtex
/// wrote it (a person edited it, or put their own file at its name) stops the discard
/// before anything changes.
pub fn restore(output: &Path, name: &str) -> Result<()> {
    let old = record(output, name)
        .ok_or_else(|| Error::invalid(format!("no previous build of {name} is kept in {}", output.display())))?;
    let kept = folder(output, name);
    let back: Vec<String> = old.files.iter().filter(|f| listed(&f.path)).map(|f| f.path.clone()).collect();
    let only_new: Vec<String> = cache::read_record(output, name)
        .map(|new| new.files.into_iter().map(|f| f.path).filter(|p| listed(p) && !back.contains(p)).collect())
        .unwrap_or_default();
    let ledger = super::build::open_ledger(output)?;
    let touched: Vec<String> = back.iter().chain(&only_new).cloned().collect();
    ledger.claim(&touched)?;
    for path in &back {
        copy(&kept.join(path), &output.join(path))?;
    }
    for path in &only_new {
        remove_written(output, Path::new(path))?;
    }
    cache::write_record(output, &old)?;
    ledger.record(&touched)?;
    drop_kept(output, name)
}

fn copy(from: &Path, to: &Path) -> Result<()> {
    if let Some(parent) = to.parent() {
        std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
    }
    io::write_bytes(to, &io::atomic::read_bytes(from)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::build::{self, Request};

    fn build_with(manifest: &Path, output: &Path, text: &str) {
        std::fs::write(manifest, text).unwrap();
        let request = Request {
            manifest: manifest.to_path_buf(),
            output: output.to_path_buf(),
            force: false,
            only: Vec::new(),
            shard: None,
        };
        let entries = build::select(&request).unwrap();
        build::build(&request, &entries, &build::Quiet).unwrap();
    }

    /// A kept build survives a rebuild; discarding the rebuild gives back the old files
    /// byte for byte (and removes the mask only the rebuild made); accepting drops the copy.
    #[test]
    fn a_discarded_build_gives_the_previous_files_back() {
        let dir = tempfile::tempdir().unwrap();
        let (manifest, out) = (dir.path().join("lib.toml"), dir.path().join("out"));
        let first = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = 1\n";
        build_with(&manifest, &out, first);
        let volume = std::fs::read(out.join("m.exr")).unwrap();
        let json = std::fs::read(out.join(".cache/m.json")).unwrap();
        assert!(!keep(&out, "x").unwrap(), "nothing built, nothing kept");
        assert!(keep(&out, "m").unwrap());
        let second = first.replace("seed = 1", "seed = 2\nmasks = [\"splotch\"]");
        build_with(&manifest, &out, &second);
        assert!(!keep(&out, "m").unwrap(), "the first copy stays the one kept");
        assert_ne!(std::fs::read(out.join("m.exr")).unwrap(), volume);
        assert!(out.join("m.mask.exr").exists() && volume_is_kept(&out));
        restore(&out, "m").unwrap();
        assert_eq!(std::fs::read(out.join("m.exr")).unwrap(), volume);
        assert_eq!(std::fs::read(out.join(".cache/m.json")).unwrap(), json);
        assert!(!out.join("m.mask.exr").exists() && !folder(&out, "m").exists());
        assert!(restore(&out, "m").unwrap_err().to_string().contains("no previous build of m"));
        // a file of the new build a person changed stops the discard before anything changes
        keep(&out, "m").unwrap();
        build_with(&manifest, &out, &second);
        let rebuilt = std::fs::read(out.join("m.exr")).unwrap();
        std::fs::write(out.join("m.mask.exr"), b"my own mask").unwrap();
        let error = restore(&out, "m").unwrap_err().to_string();
        assert!(error.contains("m.mask.exr") && error.contains("changed since"), "{error}");
        assert_eq!(std::fs::read(out.join("m.mask.exr")).unwrap(), b"my own mask");
        assert_eq!(std::fs::read(out.join("m.exr")).unwrap(), rebuilt, "the new build stays as it was");
        std::fs::remove_file(out.join("m.mask.exr")).unwrap();
        restore(&out, "m").unwrap();
        assert_eq!(std::fs::read(out.join("m.exr")).unwrap(), volume);
        keep(&out, "m").unwrap();
        std::fs::write(folder(&out, "m").join("notes.txt"), b"mine").unwrap();
        drop_kept(&out, "m").unwrap();
        assert!(record(&out, "m").is_none() && std::fs::read(out.join("m.exr")).unwrap() == volume);
        assert!(folder(&out, "m").join("notes.txt").exists() && !folder(&out, "m").join("m.exr").exists());
        // a name no entry may have never reaches outside the cache
        let outside = dir.path().join("x");
        std::fs::create_dir(&outside).unwrap();
        drop_kept(&out, "../../x").unwrap();
        assert!(!keep(&out, "../../x").unwrap() && outside.exists());
    }

    /// A link planted in the kept copy (to a user's folder holding a file of a listed name)
    /// leads no removal there.
    #[cfg(unix)]
    #[test]
    fn a_link_in_the_kept_copy_leads_no_removal_outside() {
        let dir = tempfile::tempdir().unwrap();
        let (manifest, out) = (dir.path().join("lib.toml"), dir.path().join("out"));
        let text =
            "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = 1\nmasks = [\"splotch\"]\n";
        build_with(&manifest, &out, text);
        assert!(keep(&out, "m").unwrap());
        let kept = folder(&out, "m");
        let listed: Vec<String> = record(&out, "m").unwrap().files.iter().map(|f| f.path.clone()).collect();
        let user = dir.path().join("user");
        std::fs::create_dir(&user).unwrap();
        for path in &listed {
            std::fs::write(user.join(Path::new(path).file_name().unwrap()), b"mine").unwrap();
        }
        // the kept copy moved aside and a link to the user's folder, holding the record so the
        // copy seems kept there, in its place
        std::fs::copy(kept.join(RECORD), user.join(RECORD)).unwrap();
        let aside = dir.path().join("aside");
        std::fs::rename(&kept, &aside).unwrap();
        std::os::unix::fs::symlink(&user, &kept).unwrap();
        assert!(record(&out, "m").is_some(), "the record reads through the link");
        drop_kept(&out, "m").unwrap();
        for path in listed.iter().map(String::as_str).chain([RECORD]) {
            assert!(user.join(Path::new(path).file_name().unwrap()).exists(), "{path} removed through the link");
        }
    }

    fn volume_is_kept(out: &Path) -> bool {
        volume(out, "m").is_some_and(|p| p.is_file())
    }
}
