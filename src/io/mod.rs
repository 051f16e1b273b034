//! Files: the only module that reads or writes them. Every write is atomic.
//!
//! | extension        | format                                            |
//! |------------------|---------------------------------------------------|
//! | `.exr`           | native: f32 flipbook atlas + description (lossless) |
//! | `.nrrd`          | NRRD, raw f32 (3D Slicer, ParaView, ITK)          |
//! | `.vol`           | Kopf's solid texture format, f32, cubes only      |
//! | `.png`           | 8-bit flipbook atlas with a description chunk     |
//! | `.dds`           | DDS volume texture, RGBA16F (DirectX engines)     |
//! | `.vdb`           | OpenVDB: `density`, `color` and named float grids (Blender, Houdini) |
//! | a folder (no extension, or ending in `/`) | 8-bit PNG slice stack    |
//!
//! See `docs/formats.md` for the byte-level layouts. Reads take regular files within a
//! size cap; writes never touch a file solidtex did not write (see [`atomic`]).

mod atlas;
pub mod atomic;
pub mod dds;
mod exr_file;
mod fields;
pub mod fill_spec;
pub mod flipbook;
pub mod gltf;
pub mod guard;
pub mod guided_cache;
pub mod guided_model;
mod kopf_vol;
pub mod ledger;
pub mod lst_file;
pub mod manifest;
pub mod mesh_file;
mod nrrd;
mod png_file;
pub mod snapshot_file;
pub mod values;
mod vdb;
pub mod web;

pub use atlas::layout as atlas_layout;
pub use atomic::{check_folder, read_text, write_bytes, write_folder};
pub use fields::parse_dims;
pub use png_file::{write_image, write_rgb8};

use crate::error::{Error, Result};
use crate::volume::{Channel, Image2d, Volume};
use std::path::{Path, PathBuf};

/// A volume file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// OpenEXR atlas (native).
    Exr,
    /// NRRD.
    Nrrd,
    /// Kopf's `.vol`.
    Vol,
    /// 8-bit PNG atlas.
    PngAtlas,
    /// A folder of 8-bit PNG slices.
    PngStack,
    /// OpenVDB.
    Vdb,
    /// DDS volume texture.
    Dds,
}

impl Format {
    /// The format a path names by its extension; a path without one is a slice folder.
    pub fn of(path: &Path) -> Result<Format> {
        if path.to_string_lossy().ends_with('/') {
            return Ok(Format::PngStack);
        }
        let Some(format) = Format::named(path) else {
            return match path.extension() {
                None => Ok(Format::PngStack),
                Some(_) if path.is_dir() => Ok(Format::PngStack),
                Some(e) => Err(Error::file(
                    path,
                    format!(
                        "unknown volume extension .{}; allowed: .exr, .nrrd, .vol, .png, .vdb, .dds, or a folder for a PNG slice stack",
                        e.to_string_lossy().to_ascii_lowercase()
                    ),
                )),
            };
        };
        if path.is_dir() {
            return Err(Error::file(
                path,
                "is a folder, though its name ends like a volume file; name a file, or end the name with / for a \
                 folder of PNG slices",
            ));
        }
        Ok(format)
    }

    /// The volume file format `path`'s extension names, if it names one.
    fn named(path: &Path) -> Option<Format> {
        Some(match path.extension()?.to_string_lossy().to_ascii_lowercase().as_str() {
            "exr" => Format::Exr,
            "nrrd" => Format::Nrrd,
            "vol" => Format::Vol,
            "png" => Format::PngAtlas,
            "vdb" => Format::Vdb,
            "dds" => Format::Dds,
            _ => return None,
        })
    }
}

/// The voxel budget in bytes: `SOLIDTEX_MAX_BYTES` if set (and not empty), else the
/// default: 4 GiB, or less where the process may take less memory ([`memory_room`]).
pub fn budget_from_env() -> Result<u64> {
    match std::env::var("SOLIDTEX_MAX_BYTES") {
        Ok(text) if !text.trim().is_empty() => text
            .trim()
            .parse::<u64>()
            .map_err(|_| Error::invalid(format!("SOLIDTEX_MAX_BYTES={text:?} is not a whole number of bytes"))),
        _ => Ok(default_budget(memory_room())),
    }
}

/// The default budget given the memory the process may still take: half of it less a
/// reserve for the program itself (work holds its volume about twice over), at most 4 GiB.
pub fn default_budget(room: Option<u64>) -> u64 {
    const RESERVE: u64 = 256 << 20;
    let cap = crate::volume::DEFAULT_BUDGET_BYTES;
    room.map_or(cap, |room| (room.saturating_sub(RESERVE) / 2).min(cap))
}

/// The bytes the process may still take under its limits, if any is set: the address
/// space limit (`ulimit -v`) less what is mapped already, and the control group's memory
/// limit less what the group uses.
pub fn memory_room() -> Option<u64> {
    let address_space = address_space_room();
    let group = cgroup_room();
    match (address_space, group) {
        (Some(a), Some(g)) => Some(a.min(g)),
        (a, g) => a.or(g),
    }
}

#[cfg(target_os = "linux")]
fn address_space_room() -> Option<u64> {
    let limit = rustix::process::getrlimit(rustix::process::Resource::As).current?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let mapped_kb: u64 =
        status.lines().find_map(|l| l.strip_prefix("VmSize:"))?.trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(limit.saturating_sub(mapped_kb * 1024))
}

#[cfg(not(target_os = "linux"))]
fn address_space_room() -> Option<u64> {
    None
}

/// The control group's memory limit less its use: cgroup v2's `memory.max` ("max": none)
/// and `memory.current`, or v1's `memory.limit_in_bytes` and `memory.usage_in_bytes`
/// (where page cache counts as use, so the use is not taken off).
fn cgroup_room() -> Option<u64> {
    let read = |name: &str| -> Option<u64> {
        std::fs::read_to_string(format!("/sys/fs/cgroup/{name}")).ok()?.trim().parse().ok()
    };
    if let Some(max) = read("memory.max") {
        return Some(max.saturating_sub(read("memory.current").unwrap_or(0)));
    }
    // v1 says "no limit" with a number near 2^63.
    read("memory/memory.limit_in_bytes").filter(|max| *max < 1 << 60)
}

/// Read a volume in the format its path names, within `budget` bytes.
pub fn read_volume(path: &Path, budget: u64) -> Result<Volume> {
    if !path.exists() {
        return Err(Error::file(path, "no such file or folder"));
    }
    // Each reader opens its file through `atomic`, which takes regular files only.
    if Format::of(path)? == Format::PngStack && !path.is_dir() {
        return Err(Error::file(
            path,
            "has no volume extension and is not a folder; allowed: .exr, .nrrd, .vol, .png, .vdb, .dds, or a folder of PNG slices",
        ));
    }
    match Format::of(path)? {
        Format::Exr => exr_file::read(path, budget),
        Format::Nrrd => nrrd::read(path, budget),
        Format::Vol => kopf_vol::read(path, budget),
        Format::PngAtlas => png_file::read_atlas(path, budget),
        Format::PngStack => png_file::read_stack(path, budget),
        Format::Vdb => vdb::read(path, budget),
        Format::Dds => dds::read(path, budget),
    }
}

/// Check, before any work, that a command may write the volume `output` given the files it
/// reads: a file output's folder exists, the output is not a folder and none of the inputs
/// ([`guard`]); a folder output is one solidtex may write ([`atomic::writable_folder`]) and
/// holds none of the inputs.
pub fn check_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    guard::named(output)?;
    // an output the command line names in no format solidtex writes: a usage error
    let format = Format::of(output).map_err(|e| Error::usage(e.to_string()))?;
    if format != Format::PngStack {
        check_folder(output)?;
        atomic::not_a_link(output)?;
        if output.is_dir() {
            return Err(Error::file(output, "is a folder; name a file to write"));
        }
        return guard::not_an_input(output, inputs);
    }
    check_folder_output(output, inputs)
}

/// [`check_output`] for a command that edits the volume `edited` (`stamp`, `scatter`,
/// `blur`): the output may be that volume, written atomically, but none of the `others`.
pub fn check_edit_output(output: &Path, edited: &Path, others: &[&Path]) -> Result<()> {
    if Format::of(output).map_err(|e| Error::usage(e.to_string()))? == Format::PngStack {
        let all: Vec<&Path> = others.iter().copied().chain([edited]).collect();
        return check_folder_output(output, &all);
    }
    check_output(output, others)
}

/// [`check_output`] for an output that is a folder whatever its name (a set of masks).
pub fn check_folder_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    if Format::named(output).is_some() && !output.to_string_lossy().ends_with('/') {
        let ext = output.extension().map(|e| e.to_string_lossy()).unwrap_or_default();
        return Err(Error::usage(format!(
            "{}: this command writes a folder of files, but the name ends in .{ext}, like a volume file; give a \
             folder name without an extension",
            output.display()
        )));
    }
    check_folder(output)?;
    atomic::writable_folder(output)?;
    let Some(folder) = atomic::canonical(output) else { return Ok(()) };
    for input in inputs {
        if atomic::canonical(input).is_some_and(|i| i.starts_with(&folder)) {
            return Err(Error::file(
                output,
                format!("holds the input {}; write the output into another folder", input.display()),
            ));
        }
    }
    Ok(())
}

/// What the format of `path` does not keep of `volume`'s channel names, as a note: a
/// `.vol` holds none, so its channels read back by position (grey, grey and alpha, RGB,
/// RGBA, extras); `None` when the names come back as they are.
pub fn channels_lost(path: &Path, volume: &Volume) -> Option<String> {
    let format = Format::of(path).ok()?;
    if format == Format::Dds {
        let left: Vec<Channel> =
            volume.channels().iter().filter(|c| !stored_channels(path, volume).contains(c)).cloned().collect();
        return (!left.is_empty()).then(|| {
            format!(
                "{}: a DDS texture holds R, G, B and A only; {} not stored (write .exr or .nrrd to keep every channel)",
                path.display(),
                crate::volume::channel_names(&left)
            )
        });
    }
    if format != Format::Vol {
        return None;
    }
    let back = nrrd::default_channels(volume.channel_count());
    (back != volume.channels()).then(|| {
        format!(
            "{}: a .vol keeps no channel names, so its channels {} read back as {} (write .exr or .nrrd to keep them)",
            path.display(),
            crate::volume::channel_names(volume.channels()),
            crate::volume::channel_names(&back)
        )
    })
}

/// The channels the file `path` holds when `volume` is written there: a DDS texture's
/// R, G, B and A, every other format's the volume's own.
pub fn stored_channels(path: &Path, volume: &Volume) -> Vec<Channel> {
    match Format::of(path) {
        Ok(Format::Dds) => Channel::rgba(),
        _ => volume.channels().to_vec(),
    }
}

/// A warning when the format of `path` cannot hold where `volume` sits in model space
/// (a bake's origin and voxel side): Kopf's `.vol` and DDS have no place for it.
pub fn model_grid_lost(path: &Path, volume: &Volume) -> Option<String> {
    let lost = matches!(Format::of(path).ok()?, Format::Vol | Format::Dds);
    (lost && volume.model_grid.is_some()).then(|| {
        format!(
            "{}: this format keeps no place in model space, so the volume's origin and voxel side are not recorded \
             (write .exr, .nrrd, .vdb or .png to keep them)",
            path.display()
        )
    })
}

/// The folder a model's relative paths start from: the folder of the file itself, or of
/// the file a link at `model` points to (a model linked elsewhere reads what it was
/// written beside).
pub fn model_folder(model: &Path) -> PathBuf {
    let linked = std::fs::symlink_metadata(model).is_ok_and(|m| m.file_type().is_symlink());
    let real =
        if linked { std::fs::canonicalize(model).unwrap_or_else(|_| model.to_path_buf()) } else { model.to_path_buf() };
    real.parent().map_or_else(
        || PathBuf::from("."),
        |p| if p.as_os_str().is_empty() { PathBuf::from(".") } else { p.to_path_buf() },
    )
}

/// Refuse a file that `model` names in `field` (`file`, already joined to the model's
/// folder `base`) when it is not there, naming the model, the field and where it looked.
pub fn model_input(model: &Path, field: &str, file: &Path, base: &Path) -> Result<()> {
    if file.is_file() {
        return Ok(());
    }
    let named: PathBuf = match file.strip_prefix(base) {
        Ok(inside) if inside.as_os_str().is_empty() => PathBuf::from("."),
        Ok(inside) => inside.components().collect(),
        Err(_) => file.components().collect(),
    };
    let what = if file.is_dir() { "is a folder, not a file," } else { "no such file" };
    Err(Error::file(
        model,
        format!(
            "{field} = {:?}: {what} in {} (paths in a model are relative to the model's folder)",
            named.display().to_string(),
            base.display()
        ),
    ))
}

/// Write a volume in the format its path names (atomically).
pub fn write_volume(path: &Path, volume: &Volume) -> Result<()> {
    match Format::of(path)? {
        Format::Exr => exr_file::write(path, volume),
        Format::Nrrd => nrrd::write(path, volume),
        Format::Vol => {
            let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            kopf_vol::write(path, volume, volume.meta.get("name").unwrap_or(&stem))
        }
        Format::PngAtlas => png_file::write_atlas(path, volume),
        Format::PngStack => png_file::write_stack(path, volume),
        Format::Vdb => vdb::write(path, volume),
        Format::Dds => dds::write(path, volume, dds::DdsFormat::Rgba16F),
    }
}

/// `path` relative to the folder `base` (both absolute, or both relative to one folder),
/// with `..` where it lies outside; `path` itself when they share no root.
pub fn relative_to(path: &Path, base: &Path) -> PathBuf {
    use std::path::Component;
    let (p, b): (Vec<Component>, Vec<Component>) = (path.components().collect(), base.components().collect());
    let shared = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if shared == 0 && (path.has_root() || base.has_root()) {
        return path.to_path_buf();
    }
    let mut out: PathBuf = b[shared..].iter().map(|_| Component::ParentDir).collect();
    out.extend(&p[shared..]);
    out
}

/// How a file in the folder `base` names `path`: both resolved (through links where they
/// exist), then [`relative_to`], with `/` between the parts. Only on Windows is `\\` a
/// separator; elsewhere it is part of a name and kept.
pub fn written_relative(path: &Path, base: &Path) -> String {
    let relative = relative_to(&resolved(path), &resolved(base));
    let text = relative.to_string_lossy();
    if cfg!(windows) { text.replace('\\', "/") } else { text.into_owned() }
}

/// `path` made absolute, its `.` and `..` taken away and its links followed as far as it
/// exists (a `..` after a link leaves the link's target, as the system reads it); the part
/// that does not exist yet follows as written.
pub(crate) fn resolved(path: &Path) -> PathBuf {
    use std::path::Component;
    // the folder of a bare file name is the empty path: the current folder
    let path = if path.as_os_str().is_empty() { Path::new(".") } else { path };
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = PathBuf::new();
    for part in absolute.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                if let Ok(real) = out.canonicalize() {
                    out = real;
                }
                out.pop();
            }
            other => out.push(other),
        }
    }
    let mut existing = out.as_path();
    let mut missing = Vec::new();
    while !existing.exists() {
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                missing.push(name);
                existing = parent;
            }
            _ => return out.clone(),
        }
    }
    let mut real = existing.canonicalize().unwrap_or_else(|_| existing.to_path_buf());
    real.extend(missing.iter().rev());
    real
}

/// Load a 2D image (PNG, JPEG, EXR, TIFF, HDR) as f32 samples in its own channels:
/// grey -> `[R]`, grey+alpha -> `[R, A]`, RGB, RGBA.
pub fn read_image(path: &Path) -> Result<Image2d> {
    read_image_fit(path, None)
}

/// [`read_image`], shrunk (Lanczos, aspect kept) so its longer side is at most `max_side`.
pub fn read_image_fit(path: &Path, max_side: Option<usize>) -> Result<Image2d> {
    let budget = budget_from_env()?;
    let bytes = atomic::read_bytes_within(path, atomic::file_cap(budget))?;
    check_image_memory(path, &bytes, budget)?;
    refuse_volume(path, &bytes)?;
    let mut reader = image::ImageReader::new(std::io::Cursor::new(&bytes[..]))
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    let mut limits = image::Limits::default();
    // The decoded pixels become f32 samples, four times the bytes of 8-bit ones.
    limits.max_alloc = Some(budget / 4);
    reader.limits(limits);
    // A decoder may panic on a hostile file; that is a broken file, not a crash.
    let decoded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| reader.decode()))
        .map_err(|_| Error::file(path, "cannot decode image: the decoder failed on this file (corrupt or hostile)"))?;
    let decoded = decoded.map_err(|e| match e {
        image::ImageError::Limits(_) => Error::file(
            path,
            format!(
                "image is too large: decoding it needs more than {} bytes, a quarter of the voxel budget \
                 (raise it with SOLIDTEX_MAX_BYTES)",
                budget / 4
            ),
        ),
        e => Error::file(path, format!("cannot decode image (corrupt, truncated, or not PNG/JPEG/EXR/TIFF/HDR): {e}")),
    })?;
    let decoded = match max_side {
        Some(0) => return Err(Error::invalid("the largest exemplar side must be at least 1 pixel")),
        Some(side) if decoded.width().max(decoded.height()) as usize > side => {
            decoded.resize(side as u32, side as u32, image::imageops::FilterType::Lanczos3)
        }
        _ => decoded,
    };
    let (w, h) = (decoded.width() as usize, decoded.height() as usize);
    let color = decoded.color();
    let (channels, data) = match (color.has_color(), color.has_alpha()) {
        (false, false) => (Channel::grey(), decoded.to_luma32f().into_raw()),
        (false, true) => (vec![Channel::R, Channel::A], decoded.to_luma_alpha32f().into_raw()),
        (true, false) => (Channel::rgb(), decoded.to_rgb32f().into_raw()),
        (true, true) => (Channel::rgba(), decoded.to_rgba32f().into_raw()),
    };
    let image = Image2d::from_data(w, h, channels, data).map_err(|e| e.in_file(path))?;
    if let Some([x, y, c]) = image.first_non_finite() {
        return Err(Error::file(
            path,
            format!("pixel ({x}, {y}) channel {c} is not finite; NaN and infinity are not allowed"),
        ));
    }
    Ok(image)
}

/// Refuse a solidtex volume (an EXR or PNG flipbook atlas with its description) where a 2D
/// image is asked for: its tiles would be read as one picture, empty tiles and all.
fn refuse_volume(path: &Path, bytes: &[u8]) -> Result<()> {
    let dims = match bytes {
        [0x76, 0x2f, 0x31, 0x01, ..] => exr_file::volume_dims(bytes),
        [0x89, b'P', b'N', b'G', ..] => png_file::volume_dims(bytes),
        _ => None,
    };
    let kind = if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) { "exr" } else { "png" };
    let named = path.extension().is_some_and(|e| e.eq_ignore_ascii_case(kind));
    let slice = |file: &str| format!("`solidtex slice {file} --axis z -o slice.png`");
    let advice = if named {
        format!("give one of its slices instead ({})", slice(&path.display().to_string()))
    } else {
        let renamed = path.with_extension(kind);
        format!(
            "it is a .{kind} file under another extension: renamed to {}, {} gives one of its slices",
            renamed.display(),
            slice(&renamed.display().to_string())
        )
    };
    match dims {
        Some([x, y, z]) => Err(Error::file(
            path,
            format!(
                "this is a solidtex volume ({x}x{y}x{z} voxels, stored as a flipbook of its slices), not a 2D \
                 image; {advice}"
            ),
        )),
        None => Ok(()),
    }
}

/// Refuse an image whose decoding would need more than `budget` bytes at its peak, from
/// its header alone: the decoded pixels, their f32 copy, and a shrunk copy of that.
fn check_image_memory(path: &Path, bytes: &[u8], budget: u64) -> Result<()> {
    use image::ImageDecoder;
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format();
    let Ok(Ok(decoder)) = reader.map(|r| r.into_decoder()) else {
        // Not an image the header reader knows: the decoder says why.
        return Ok(());
    };
    let (w, h) = decoder.dimensions();
    let colour = decoder.color_type();
    let pixels = w as u128 * h as u128;
    let decoded = pixels * colour.bytes_per_pixel() as u128;
    let samples = pixels * colour.channel_count() as u128 * 4;
    let peak = decoded + 2 * samples;
    if peak > budget as u128 {
        return Err(Error::file(
            path,
            format!(
                "image is too large: {w}x{h} pixels need about {peak} bytes to decode and convert, over the voxel \
                 budget of {budget} bytes (raise it with SOLIDTEX_MAX_BYTES, or shrink the image)"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model's missing input is named as the model gives it; a folder is said to be one.
    #[test]
    fn a_models_input_is_named_as_given() {
        let dir = tempfile::tempdir().unwrap();
        let (base, model) = (dir.path(), dir.path().join("m.guided"));
        let missing = model_input(&model, "exemplar", &base.join("a.png"), base).unwrap_err().to_string();
        assert!(missing.contains("exemplar = \"a.png\": no such file in"), "{missing}");
        let folder = model_input(&model, "exemplar", &base.join("."), base).unwrap_err().to_string();
        assert!(folder.contains("exemplar = \".\": is a folder, not a file,"), "{folder}");
    }

    #[test]
    fn paths_are_written_relative_to_a_folder() {
        let rel = |p: &str, b: &str| relative_to(Path::new(p), Path::new(b));
        assert_eq!(rel("/w/lib/photos/a.png", "/w/lib"), PathBuf::from("photos/a.png"));
        assert_eq!(rel("/w/data/a.png", "/w/lib"), PathBuf::from("../data/a.png"));
        assert_eq!(rel("/w/lib/a.png", "/w/lib"), PathBuf::from("a.png"));
        assert_eq!(rel("lib/a.png", "/w"), PathBuf::from("lib/a.png"), "no shared root: as given");
    }

    /// On Unix a backslash is part of a file name, not a separator, and is kept.
    #[cfg(unix)]
    #[test]
    fn a_backslash_in_a_name_is_kept_on_unix() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        assert_eq!(written_relative(&root.join("sub/we\"ird \\ name.png"), &root), "sub/we\"ird \\ name.png");
    }

    /// A folder given with `..`, through a link or not there yet names a file as the
    /// system finds it from that folder.
    #[test]
    fn a_file_is_named_as_found_from_a_folder_given_with_dots_or_links() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        std::fs::create_dir_all(root.join("proj/out")).unwrap();
        std::fs::create_dir_all(root.join("renders")).unwrap();
        let volume = root.join("proj/out/marble.exr");
        std::fs::write(&volume, b"v").unwrap();
        let found = |base: &Path| base.join(written_relative(&volume, base)).canonicalize().unwrap();
        assert_eq!(found(&root.join("proj/../renders")), volume);
        assert_eq!(found(&root.join("proj/./out/../../renders")), volume);
        assert_eq!(written_relative(&volume, &root.join("proj/../renders/new/deeper")), "../../../proj/out/marble.exr");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(root.join("proj/out"), root.join("renders/link")).unwrap();
            // renders/link/.. is proj, where the link leads
            assert_eq!(written_relative(&volume, &root.join("renders/link/..")), "out/marble.exr");
        }
    }
}
