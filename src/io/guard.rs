//! What a command may write, checked before any work:
//!
//! - never one of its own inputs (the same file by device and inode, through links and
//!   hard links too), except a volume a command edits in place by design;
//! - only under the extension of what it writes (a PNG writer writes `.png`);
//! - a side file (a flipbook's layout beside its image, a mask beside its preset) only where
//!   no file is, or where the file there is one solidtex wrote and nobody changed since: a
//!   text side file carries a seal, the blake3 hash of its own text ([`seal`]); a volume
//!   side file carries the hash of its samples in its provenance ([`seal_volume`]).

use super::atomic;
use crate::error::{Error, Result};
use crate::volume::Volume;
use std::fs;
use std::path::Path;

/// Whether two paths name the same file (device and inode; the canonical path off Unix).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (fs::metadata(a), fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        matches!((atomic::canonical(a), atomic::canonical(b)), (Some(x), Some(y)) if x == y)
    }
}

/// Refuse an output that is one of the command's inputs, or lies inside an input that is a
/// folder (a stack of slices, whose files are all read) (exit code 2).
pub fn not_an_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    if let Some(input) = inputs.iter().find(|input| same_file(output, input)) {
        return Err(Error::usage(format!(
            "{}: is the input {} of this command; solidtex never writes over its own inputs (name another output \
             file)",
            output.display(),
            input.display()
        )));
    }
    match inputs.iter().find(|input| inside_folder(output, input)) {
        Some(input) => Err(Error::usage(format!(
            "{}: is inside the folder {}, an input of this command (its slices are read as one volume); solidtex \
             never writes into its own inputs (name an output outside it)",
            output.display(),
            input.display()
        ))),
        None => Ok(()),
    }
}

/// Whether `path` lies inside the existing folder `folder` (at any depth, through links
/// too: each folder above `path` is compared with `folder` as a file).
pub fn inside_folder(path: &Path, folder: &Path) -> bool {
    folder.is_dir() && super::resolved(path).ancestors().skip(1).any(|above| same_file(above, folder))
}

/// Refuse an `output` that is the folder `kept`, where solidtex keeps `what`, or lies
/// inside it: the user's files and solidtex's own would mix there. Neither need exist yet.
pub fn outside_folder(output: &Path, kept: &Path, what: &str) -> Result<()> {
    let (out, folder) = (super::resolved(output), super::resolved(kept));
    if !out.starts_with(&folder) {
        return Ok(());
    }
    Err(Error::file(
        output,
        format!(
            "{} {}, the folder where solidtex keeps {what}; choose an output elsewhere",
            if out == folder { "is" } else { "is inside" },
            kept.display()
        ),
    ))
}

/// Extensions of the files solidtex reads or writes: a name that is one of them after a dot
/// and nothing else (`.png`) is taken for a forgotten name, not a hidden file.
const KNOWN_EXTENSIONS: [&str; 17] = [
    "exr", "nrrd", "vol", "png", "vdb", "dds", "snap", "ply", "obj", "stl", "lst", "json", "glb", "html", "guided",
    "toml", "txt",
];

/// Refuse an output named by an extension alone (`-o .png`, `convert v.exr .exr`): the
/// system reads it as a hidden file (or folder) without an extension (exit code 2).
pub fn named(output: &Path) -> Result<()> {
    let name = output.file_name().map(|n| n.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let bare = name.strip_prefix('.').filter(|rest| KNOWN_EXTENSIONS.contains(rest));
    if bare.is_none() || output.to_string_lossy().ends_with('/') {
        return Ok(());
    }
    Err(Error::usage(format!(
        "{}: the name is an extension alone; give the file a name, like out{name}",
        output.display()
    )))
}

/// Refuse an output whose extension is none of `allowed` (lower case, no dot); `what` names
/// what the command writes, e.g. "a PNG picture" (exit code 2).
pub fn extension(output: &Path, allowed: &[&str], what: &str) -> Result<()> {
    named(output)?;
    let ext = output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    if ext.as_deref().is_some_and(|e| allowed.contains(&e)) {
        return Ok(());
    }
    let names: Vec<String> = allowed.iter().map(|e| format!(".{e}")).collect();
    Err(Error::usage(format!(
        "{}: this command writes {what}; name a file ending in {}",
        output.display(),
        names.join(" or ")
    )))
}

/// Check a file output before any work: its folder exists, it is no folder, its extension
/// is one of `allowed`, and it is none of `inputs`.
pub fn file_output(output: &Path, inputs: &[&Path], allowed: &[&str], what: &str) -> Result<()> {
    extension(output, allowed, what)?;
    atomic::check_folder(output)?;
    atomic::not_a_link(output)?;
    if output.is_dir() {
        return Err(Error::file(output, "is a folder; name a file to write"));
    }
    not_an_input(output, inputs)
}

/// A PNG picture output: [`file_output`] with `.png`.
pub fn png_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    file_output(output, inputs, &["png"], "a PNG picture")
}

/// The text that marks a seal; the hash follows it.
const SEAL: &str = "solidtex-seal:";

/// The hex digits of a seal's hash.
const SEAL_DIGITS: usize = 64;

/// `text` sealed: its one [`SEAL_MARK`] gets the blake3 hash of the text as written with
/// the mark in it, so any later change to the text breaks the seal.
pub fn seal(text: &str) -> String {
    let hash = blake3::hash(text.as_bytes()).to_hex();
    text.replacen(SEAL_MARK, &format!("{SEAL}{hash}"), 1)
}

/// The placeholder a text puts where its seal goes (e.g. a JSON value or a comment).
pub const SEAL_MARK: &str = "solidtex-seal:0000000000000000000000000000000000000000000000000000000000000000";

/// Whether `bytes` hold a text sealed by [`seal`] and unchanged since.
pub fn is_sealed(bytes: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(bytes) else { return false };
    let Some(at) = text.find(SEAL) else { return false };
    let start = at + SEAL.len();
    let Some(hash) = text.get(start..start + SEAL_DIGITS) else { return false };
    let unsealed = format!("{}{SEAL_MARK}{}", &text[..at], &text[start + SEAL_DIGITS..]);
    blake3::hash(unsealed.as_bytes()).to_hex().as_str() == hash
}

/// The provenance key of a volume's seal.
const VOLUME_SEAL: &str = "seal";

/// The hash of a volume's dims, channels and samples.
fn volume_hash(volume: &Volume) -> String {
    let mut hasher = blake3::Hasher::new();
    for d in volume.dims() {
        hasher.update(&(d as u64).to_le_bytes());
    }
    hasher.update(crate::volume::channel_names(volume.channels()).as_bytes());
    for v in volume.data() {
        hasher.update(&v.to_bits().to_le_bytes());
    }
    hasher.finalize().to_hex().to_string()
}

/// `volume` sealed: the hash of its samples in its provenance.
pub fn seal_volume(mut volume: Volume) -> Volume {
    let hash = volume_hash(&volume);
    volume.meta.set(VOLUME_SEAL, hash);
    volume
}

/// Refuse to replace `path`, a side file of a command, unless no file is there or the file
/// there is one solidtex sealed and nobody changed since. `how` says what the user can do.
pub fn side_file(path: &Path, how: &str) -> Result<()> {
    let meta = match fs::symlink_metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(path, e)),
    };
    if meta.is_file() && sealed_file(path) {
        return Ok(());
    }
    Err(Error::file(
        path,
        format!("exists and was not written by solidtex, or was changed since; solidtex does not replace it ({how})"),
    ))
}

/// Whether the file at `path` carries an unbroken seal: a sealed text, or a volume whose
/// samples match the hash it carries.
fn sealed_file(path: &Path) -> bool {
    if super::Format::of(path).is_ok_and(|f| f == super::Format::Exr) {
        let budget = super::budget_from_env().unwrap_or(0);
        return super::read_volume(path, budget)
            .is_ok_and(|v| v.meta.get(VOLUME_SEAL).is_some_and(|hash| hash == volume_hash(&v)));
    }
    atomic::read_bytes_within(path, atomic::TEXT_CAP).is_ok_and(|bytes| is_sealed(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seal_breaks_on_any_change() {
        let text = format!("{{\n  \"seal\": \"{SEAL_MARK}\",\n  \"rows\": 4\n}}\n");
        let sealed = seal(&text);
        assert!(!sealed.contains(SEAL_MARK) && is_sealed(sealed.as_bytes()));
        for edited in [sealed.replace("4", "5"), sealed.clone() + " ", sealed.replacen("seal", "Seal", 1)] {
            assert!(!is_sealed(edited.as_bytes()), "{edited}");
        }
        assert!(!is_sealed(text.as_bytes()), "the placeholder is no seal");
        assert!(!is_sealed(b"rows: 4\n"));
    }

    /// `-o .png` or `.exr` is a forgotten name: refused, naming an example; a hidden file
    /// with a name (`.cut.png`), a folder (`.exr/`) and other hidden names pass.
    #[test]
    fn an_extension_alone_is_no_name() {
        for bad in [".png", "out/.EXR", ".glb"] {
            let error = named(Path::new(bad)).unwrap_err().to_string();
            assert!(error.contains("an extension alone") && error.contains("like out."), "{bad}: {error}");
            assert!(png_output(Path::new(bad), &[]).is_err());
        }
        for good in [".cut.png", ".exr/", ".cache", "cut.png", "slices"] {
            assert!(named(Path::new(good)).is_ok(), "{good}");
        }
    }

    #[test]
    fn an_output_may_not_be_an_input_even_through_a_link() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("v.exr");
        fs::write(&input, "x").unwrap();
        let link = dir.path().join("link.exr");
        std::os::unix::fs::symlink(&input, &link).unwrap();
        let hard = dir.path().join("hard.exr");
        fs::hard_link(&input, &hard).unwrap();
        for output in [&input, &link, &hard] {
            let err = not_an_input(output, &[Path::new("other"), &input]).unwrap_err();
            assert_eq!(err.exit_code(), 2);
            assert!(err.to_string().contains("is the input"), "{err}");
        }
        assert!(not_an_input(&dir.path().join("new.exr"), &[&input]).is_ok());
        assert!(extension(Path::new("a.PNG"), &["png"], "a PNG picture").is_ok());
        let err = extension(Path::new("w.lst"), &["png"], "a PNG picture").unwrap_err().to_string();
        assert!(err.contains("w.lst") && err.contains(".png"), "{err}");
    }
}
