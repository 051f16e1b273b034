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
    for file in old.files.iter().filter(|f| listed(&f.path)) {
        remove_written(&kept.join(&file.path))?;
        // the folders the file was in, if it leaves them empty (a mask folder)
        for parent in Path::new(&file.path).ancestors().skip(1).filter(|p| !p.as_os_str().is_empty()) {
            let _ = std::fs::remove_dir(kept.join(parent));
        }
    }
    remove_written(&kept.join(RECORD))?;
    let _ = std::fs::remove_dir(&kept);
    Ok(())
}

/// Whether `path` (from a record) names a file below the folder it is relative to: no
/// root, no `..`.
fn listed(path: &str) -> bool {
    Path::new(path).components().all(|c| matches!(c, Component::Normal(_)))
}

/// Removes the regular file at `path` (a link or a folder there is left alone); a file
/// already gone is fine.
fn remove_written(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.is_file() => std::fs::remove_file(path).map_err(|e| Error::io(path, e)),
        _ => Ok(()),
    }
}

/// Discard the new build: the kept files and record go back, the files only the new build
/// wrote are removed, and the copy goes.
pub fn restore(output: &Path, name: &str) -> Result<()> {
    let old = record(output, name)
        .ok_or_else(|| Error::invalid(format!("no previous build of {name} is kept in {}", output.display())))?;
    let kept = folder(output, name);
    for file in old.files.iter().filter(|f| listed(&f.path)) {
        copy(&kept.join(&file.path), &output.join(&file.path))?;
    }
    if let Some(new) = cache::read_record(output, name) {
        let only_new = new.files.iter().filter(|f| listed(&f.path) && !old.files.iter().any(|o| o.path == f.path));
        for file in only_new {
            remove_written(&output.join(&file.path))?;
        }
    }
    cache::write_record(output, &old)?;
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

    fn volume_is_kept(out: &Path) -> bool {
        volume(out, "m").is_some_and(|p| p.is_file())
    }
}
