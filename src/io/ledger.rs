//! The files solidtex wrote into a folder it fills file by file (a library build's output),
//! each with the blake3 hash of what it wrote: `DIR/.cache/written.txt`, one `HASH  NAME`
//! line a file, as in [`super::atomic::FOLDER_LIST`].
//!
//! A file is claimed before it is written: claiming refuses a file that is there but not in
//! the ledger, or changed since (a person's `report.md`, an edited volume), and marks the
//! claimed names `pending` until they are written and recorded. A run killed in between
//! leaves them pending, and the next run may replace them: they were about to be solidtex's.
//! Folders (slice stacks, mask sets) keep their own list and are left to
//! [`super::write_folder`].

use super::atomic;
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The ledger's place inside the folder it describes.
pub const FILE: &str = ".cache/written.txt";

/// What the ledger knows of one file.
#[derive(Debug, Clone, PartialEq)]
enum Mark {
    /// Written with this content hash (hex; a shorter prefix from an older record).
    Hash(String),
    /// Claimed, not yet recorded.
    Pending,
}

/// The ledger of one output folder; shared by the threads of one build (which holds the
/// folder's build lock).
#[derive(Debug)]
pub struct Ledger {
    folder: PathBuf,
    marks: Mutex<BTreeMap<String, Mark>>,
}

impl Ledger {
    /// The ledger of `folder`, empty when it has none yet; `seeds` are files known to be
    /// solidtex's from before the ledger existed (name, hash or hash prefix), taken only then.
    pub fn open(folder: &Path, seeds: impl FnOnce() -> Vec<(String, String)>) -> Result<Ledger> {
        let path = folder.join(FILE);
        let marks = if path.exists() {
            let text = atomic::read_text(&path, "ledger of written files")?;
            parse(&text)
        } else {
            seeds().into_iter().map(|(name, hash)| (name, Mark::Hash(hash))).collect()
        };
        Ok(Ledger { folder: folder.to_path_buf(), marks: Mutex::new(marks) })
    }

    /// Claim the files `names` (relative to the folder) for writing: refused, naming the
    /// first, if one is there and is not solidtex's as written. Folders are not claimed.
    pub fn claim(&self, names: &[String]) -> Result<()> {
        let mut marks = self.marks.lock().unwrap_or_else(|e| e.into_inner());
        for name in names {
            let path = self.folder.join(name);
            let Ok(meta) = std::fs::symlink_metadata(&path) else { continue };
            if meta.is_dir() {
                // a folder keeps its own list; one written before lists held hashes gets
                // them where the ledger knows its files
                let known = |file: &str, hash: &str| matches!(marks.get(&format!("{name}/{file}")), Some(Mark::Hash(h)) if hash.starts_with(h.as_str()));
                atomic::upgrade_list(&path, known)?;
                // a folder holding a file solidtex may not replace fails the entry now,
                // before any of its files are made
                atomic::writable_folder(&path)?;
                continue;
            }
            let ours = match marks.get(name) {
                Some(Mark::Pending) => true,
                Some(Mark::Hash(hash)) => atomic::file_hash(&path).is_some_and(|h| h.starts_with(hash.as_str())),
                None => false,
            };
            if !ours {
                return Err(Error::file(
                    &path,
                    format!(
                        "exists and was not written by solidtex, or was changed since (it is not as {} records \
                         it); solidtex does not replace it: move it away (or remove it to rebuild it) or build into another folder (-o)",
                        FILE
                    ),
                ));
            }
        }
        for name in names {
            marks.insert(name.clone(), Mark::Pending);
        }
        self.save(&marks)
    }

    /// Record the content of the files `names` as written now (folders and missing files
    /// are left out).
    pub fn record(&self, names: &[String]) -> Result<()> {
        let mut marks = self.marks.lock().unwrap_or_else(|e| e.into_inner());
        for name in names {
            match atomic::file_hash(&self.folder.join(name)) {
                Some(hash) => marks.insert(name.clone(), Mark::Hash(hash)),
                None => marks.remove(name),
            };
        }
        self.save(&marks)
    }

    fn save(&self, marks: &BTreeMap<String, Mark>) -> Result<()> {
        let mut text = String::from(
            "# Written by solidtex: the files a build wrote into this folder, each after the blake3 hash of\n\
             # its content. It replaces only these, and only while unchanged.\n",
        );
        for (name, mark) in marks {
            match mark {
                Mark::Hash(hash) => text.push_str(&format!("{hash}  {name}\n")),
                Mark::Pending => text.push_str(&format!("pending  {name}\n")),
            }
        }
        atomic::write_bytes(&self.folder.join(FILE), text.as_bytes())
    }
}

/// The marks of a ledger's text; lines of another shape are skipped.
fn parse(text: &str) -> BTreeMap<String, Mark> {
    let hex = |h: &str| h.len() >= 32 && h.bytes().all(|b| b.is_ascii_hexdigit());
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| l.split_once("  "))
        .filter_map(|(mark, name)| match mark {
            "pending" => Some((name.to_string(), Mark::Pending)),
            h if hex(h) => Some((name.to_string(), Mark::Hash(h.to_string()))),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file the ledger does not know, or one changed since it was recorded, is refused
    /// and kept; a recorded or pending one may be replaced.
    #[test]
    fn only_files_recorded_unchanged_or_pending_may_be_replaced() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join(".cache")).unwrap();
        let names = |n: &[&str]| n.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        std::fs::write(dir.path().join("report.md"), "mine").unwrap();
        let ledger = Ledger::open(dir.path(), Vec::new).unwrap();
        let err = ledger.claim(&names(&["a.exr", "report.md"])).unwrap_err().to_string();
        assert!(err.contains("report.md") && err.contains("not written by solidtex"), "{err}");
        assert_eq!(std::fs::read_to_string(dir.path().join("report.md")).unwrap(), "mine");
        ledger.claim(&names(&["a.exr"])).unwrap();
        std::fs::write(dir.path().join("a.exr"), "built").unwrap();
        let reopened = Ledger::open(dir.path(), Vec::new).unwrap();
        reopened.claim(&names(&["a.exr"])).unwrap();
        reopened.record(&names(&["a.exr"])).unwrap();
        let again = Ledger::open(dir.path(), Vec::new).unwrap();
        again.claim(&names(&["a.exr"])).unwrap();
        again.record(&names(&["a.exr"])).unwrap();
        std::fs::write(dir.path().join("a.exr"), "edited").unwrap();
        let err = again.claim(&names(&["a.exr"])).unwrap_err().to_string();
        assert!(err.contains("a.exr") && err.contains("changed since"), "{err}");
    }
}
