//! What a build remembers about each exemplar (`DIR/.cache/NAME.json`), the key that says
//! whether its recipe or inputs changed, and the plan: which entries are up to date, and
//! why the others are not.
//!
//! The key is blake3 over a canonical text of the recipe (written field by field below,
//! floats as their bits, paths relative to the manifest's folder), the bytes of every input
//! file, the record format and the tool version. It does not depend on `Debug` output,
//! on where the library lives, or on the order a build ran in.

use super::files;
use crate::error::{Error, Result};
use crate::io;
use crate::io::manifest::{Entry, MaskKind, SkinSource, Source, Step};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The version of the canonical recipe text, the record format and what the built files
/// hold (3: layered masks fade before the cube's sides): a change rebuilds everything.
const FORMAT: &str = "solidtex-cache-3";

/// What the cache remembers about a built exemplar.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Exemplar name.
    pub name: String,
    /// Content hash of the recipe, its input files and the tool version.
    pub key: String,
    /// Hash of the canonical recipe text alone (to say what changed).
    #[serde(default)]
    pub recipe: String,
    /// Every input file with its hash when built (to say which one changed).
    #[serde(default)]
    pub inputs: Vec<Written>,
    /// Size in voxels.
    pub dims: [usize; 3],
    /// Declared type, if any.
    pub declared: Option<String>,
    /// Type estimated by `classify`.
    pub classified: String,
    /// Seconds the build took.
    pub seconds: f64,
    /// Every file the build wrote (relative to the output folder), with its size and
    /// blake3 hash: an entry is cached only while they are all unchanged.
    #[serde(default)]
    pub files: Vec<Written>,
    /// For synthesized entries, the sharpness, feature-size and histogram figures against
    /// the photos.
    #[serde(default)]
    pub quality: Option<crate::quality::Glance>,
    /// The warnings the build gave (e.g. a photo whose features run one way), kept so the
    /// report shows them on later, cached builds too.
    #[serde(default)]
    pub warnings: Vec<String>,
}

/// One file with its size and hash.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Written {
    /// Path (relative to the output folder, or to the manifest's folder for inputs).
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
    /// blake3 of the content (hex, 32 characters).
    pub hash: String,
}

/// An entry's recipe and inputs as they are now.
#[derive(Debug, Clone, PartialEq)]
pub struct Key {
    /// The full key.
    pub key: String,
    /// Hash of the canonical recipe text.
    pub recipe: String,
    /// Input files (relative to the manifest's folder) with their hashes.
    pub inputs: Vec<Written>,
}

/// Where an entry stands against its last build.
#[derive(Debug, Clone, PartialEq)]
pub enum Freshness {
    /// No record, or its outputs are gone.
    NotBuilt,
    /// Built, and nothing changed since.
    UpToDate(Record),
    /// Built, but this changed since (the record of the old build).
    Stale(Record, String),
}

/// The key of `entry`, whose relative paths are taken from the manifest folder `folder`.
pub fn key(entry: &Entry, folder: &Path) -> Result<Key> {
    let recipe = canonical(entry, folder);
    let mut hasher = blake3::Hasher::new();
    hasher.update(FORMAT.as_bytes());
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    hasher.update(recipe.as_bytes());
    let mut inputs = Vec::new();
    for (field, input) in input_files(entry) {
        let bytes = input_content(&input).map_err(|e| entry.lines.error(&field, e))?;
        hasher.update(&bytes);
        inputs.push(Written { path: shown(&input, folder), bytes: bytes.len() as u64, hash: short_hash(&bytes) });
    }
    Ok(Key { key: short(hasher.finalize()), recipe: short(blake3::hash(recipe.as_bytes())), inputs })
}

/// What a key hashes of an input: a file's content; a folder's (a stack of slices read as
/// one volume) files' names and content hashes, in name order.
fn input_content(path: &Path) -> Result<Vec<u8>> {
    if !path.is_dir() {
        return io::atomic::read_bytes(path);
    }
    let listed = std::fs::read_dir(path).map_err(|e| crate::error::Error::io(path, e))?;
    let mut files: Vec<PathBuf> = listed.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_file()).collect();
    files.sort();
    let mut out = Vec::new();
    for file in files {
        out.extend_from_slice(file.file_name().unwrap_or_default().as_encoded_bytes());
        out.push(0);
        out.extend_from_slice(blake3::hash(&io::atomic::read_bytes(&file)?).as_bytes());
    }
    Ok(out)
}

/// Whether `entry`'s build in `output` is up to date, and if not, why.
pub fn freshness(entry: &Entry, folder: &Path, output: &Path) -> Freshness {
    match key(entry, folder) {
        Ok(now) => freshness_against(entry, &now, output),
        Err(e) => match recorded(entry, output) {
            Some(record) => Freshness::Stale(record, format!("an input cannot be read: {e}")),
            None => Freshness::NotBuilt,
        },
    }
}

/// [`freshness`] for the key `now` of `entry` (already computed: the inputs are read once).
pub fn freshness_against(entry: &Entry, now: &Key, output: &Path) -> Freshness {
    let Some(record) = recorded(entry, output) else { return Freshness::NotBuilt };
    match stale_because(entry, now, output, &record) {
        Some(why) => Freshness::Stale(record, why),
        None => Freshness::UpToDate(record),
    }
}

/// The record of a build whose volume is still there.
fn recorded(entry: &Entry, output: &Path) -> Option<Record> {
    read_record(output, &entry.name).filter(|_| files::volume(output, &entry.name).is_file())
}

/// Why a build recorded as `record` is out of date (`None`: it is not).
fn stale_because(entry: &Entry, now: &Key, output: &Path, record: &Record) -> Option<String> {
    if now.key != record.key {
        return Some(changed(now, record));
    }
    match written(output, entry) {
        Ok(files) if files == record.files && !files.is_empty() => None,
        Ok(files) => {
            let edited = record.files.iter().find(|f| !files.contains(f));
            Some(match edited {
                Some(f) => format!("the output {} was changed or removed", f.path),
                None => "its outputs differ from the build's".to_string(),
            })
        }
        Err(e) => Some(format!("an output cannot be read: {e}")),
    }
}

/// What differs between the key now and the recorded build.
fn changed(now: &Key, record: &Record) -> String {
    if now.recipe != record.recipe {
        return "the recipe changed".to_string();
    }
    if let Some(input) = now.inputs.iter().find(|i| !record.inputs.contains(i)) {
        return format!("the input {} changed", input.path);
    }
    "built by another solidtex version".to_string()
}

/// The record of exemplar `name` in `output`, if there is a readable one.
pub fn read_record(output: &Path, name: &str) -> Option<Record> {
    serde_json::from_slice(&io::atomic::read_bytes(&output.join(files::record(name))).ok()?).ok()
}

/// Write `record` into `output`'s cache.
pub fn write_record(output: &Path, record: &Record) -> Result<()> {
    let json = serde_json::to_string_pretty(record).expect("a record always serializes");
    io::write_bytes(&output.join(files::record(&record.name)), json.as_bytes())
}

/// Size and hash of every file an entry's outputs hold now, in a fixed order.
pub fn written(output: &Path, entry: &Entry) -> Result<Vec<Written>> {
    let mut names = Vec::new();
    for name in files::outputs(entry) {
        let path = output.join(&name);
        if path.is_dir() {
            let mut inner: Vec<String> = std::fs::read_dir(&path)
                .map_err(|e| Error::io(&path, e))?
                .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
                .collect();
            inner.sort();
            names.extend(inner.into_iter().map(|f| format!("{name}/{f}")));
        } else {
            names.push(name);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let bytes = io::atomic::read_bytes(&output.join(&name))?;
            Ok(Written { path: name, bytes: bytes.len() as u64, hash: short_hash(&bytes) })
        })
        .collect()
}

/// The files an entry reads, each with the manifest field that names it.
pub fn input_files(entry: &Entry) -> Vec<(String, PathBuf)> {
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    let mut put = |field: &str, path: &PathBuf| files.push((field.to_string(), path.clone()));
    match &entry.source {
        Source::Sweep(spec) => {
            put("image", &spec.image);
            if let Some((SkinSource::Image(p), _, _)) = &spec.skin {
                put("skin", p);
            }
            spec.displacement.iter().for_each(|p| put("displacement", p));
        }
        Source::Synth(spec) => {
            put("image", &spec.image);
            for (field, path) in [("ey", &spec.ey), ("ez", &spec.ez), ("depth_image", &spec.depth)] {
                path.iter().for_each(|p| put(field, p));
            }
        }
        Source::Load(path) => put("volume", path),
        Source::Procedural(_) => {}
    }
    for (k, step) in entry.steps.iter().enumerate() {
        match step {
            Step::Stamp { mesh, .. } => put(&format!("steps[{k}].stamp"), mesh),
            Step::Scatter { mesh, .. } => put(&format!("steps[{k}].scatter"), mesh),
            Step::Blur { .. } => {}
        }
    }
    files
}

fn short(hash: blake3::Hash) -> String {
    hash.to_hex()[..32].to_string()
}

fn short_hash(bytes: &[u8]) -> String {
    short(blake3::hash(bytes))
}

/// `path` relative to `folder` when it lies inside it, with `/` between components.
fn shown(path: &Path, folder: &Path) -> String {
    let inside = path.strip_prefix(folder).unwrap_or(path);
    inside.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// The recipe as canonical text: one `field=value` line per field, in a fixed order, floats
/// as the hex of their bits, paths relative to `folder`.
pub fn canonical(entry: &Entry, folder: &Path) -> String {
    let mut c = Canon { text: String::new(), folder };
    c.put("name", &entry.name);
    match &entry.source {
        Source::Procedural(recipe) => c.put("procedural", recipe.name()),
        Source::Sweep(s) => {
            c.path("sweep.image", &s.image);
            c.put("sweep.length", s.length);
            c.put("sweep.axis", s.axis);
            c.put("sweep.depth_axis", s.depth_axis.map_or("-".to_string(), |a| a.to_string()));
            if let Some(n) = s.noise {
                c.floats("sweep.noise", &[n.amplitude, n.frequency, n.jitter]);
            }
            if let Some((look, width, noise)) = &s.skin {
                match look {
                    SkinSource::Colour(rgb) => c.floats("sweep.skin.colour", rgb),
                    SkinSource::Image(p) => c.path("sweep.skin.image", p),
                }
                c.floats("sweep.skin.width", &[*width, *noise]);
            }
            if let Some(p) = &s.displacement {
                c.path("sweep.displacement", p);
            }
        }
        Source::Synth(s) => {
            c.path("synth.image", &s.image);
            for (field, path) in [("synth.ey", &s.ey), ("synth.ez", &s.ez), ("synth.depth", &s.depth)] {
                if let Some(p) = path {
                    c.path(field, p);
                }
            }
            c.put("synth.layered", s.layered);
            c.put("synth.levels", s.levels);
            c.put("synth.max_exemplar", s.max_exemplar.map_or("-".to_string(), |m| m.to_string()));
        }
        Source::Load(path) => c.path("load", path),
    }
    c.put("size", entry.dims.map_or("-".to_string(), |[x, y, z]| format!("{x}x{y}x{z}")));
    c.put("seed", entry.seed);
    c.put("type", entry.texture_type.map_or("-", |t| t.name()));
    entry.steps.iter().for_each(|s| c.step(s));
    for kind in &entry.masks {
        c.put("mask", if *kind == MaskKind::Splotch { "splotch" } else { "layered" });
    }
    c.floats("mask_falloff", &[entry.mask_falloff]);
    entry.exports.iter().for_each(|e| c.put("export", e));
    c.text
}

struct Canon<'a> {
    text: String,
    folder: &'a Path,
}

impl Canon<'_> {
    fn put(&mut self, field: &str, value: impl std::fmt::Display) {
        let _ = writeln!(self.text, "{field}={value}");
    }

    fn floats(&mut self, field: &str, values: &[f32]) {
        let bits: Vec<String> = values.iter().map(|v| format!("{:08x}", v.to_bits())).collect();
        self.put(field, bits.join(","));
    }

    fn path(&mut self, field: &str, path: &Path) {
        let shown = shown(path, self.folder);
        self.put(field, shown);
    }

    fn step(&mut self, step: &Step) {
        match step {
            Step::Stamp { mesh, placement, colour } => {
                self.path("stamp", mesh);
                self.floats("stamp.at", &placement.at.to_array());
                self.floats("stamp.rotation", &placement.rotation.to_array());
                self.floats("stamp.scale", &placement.scale.to_array());
                self.floats("stamp.colour", colour);
            }
            Step::Scatter { mesh, count, region, scale, colour, seed } => {
                self.path("scatter", mesh);
                self.put("scatter.count", count);
                match region {
                    None => self.put("scatter.region", "all"),
                    Some(crate::stamp::Region::Box(lo, hi)) => {
                        self.floats("scatter.box", &[lo.to_array(), hi.to_array()].concat())
                    }
                    Some(crate::stamp::Region::Depth(lo, hi)) => self.floats("scatter.depth", &[*lo, *hi]),
                }
                self.floats("scatter.scale", &[scale.0, scale.1]);
                self.floats("scatter.colour", colour);
                self.put("scatter.seed", seed);
            }
            Step::Blur { at, radius, strength } => {
                self.floats("blur.at", &at.to_array());
                self.floats("blur.radius", &[*radius, *strength]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::manifest::parse_plan;

    const TEXT: &str = "[[exemplar]]\nname = \"k\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = 3\n\
                        masks = [\"splotch\"]\n\
                        [[exemplar.steps]]\nblur = \"4,4,4\"\nradius = 2.5\nstrength = 0.5\n";

    /// The canonical text is fixed: a change to it (or to how the manifest is read) shows
    /// here, and must come with a new FORMAT so old caches rebuild.
    #[test]
    fn the_canonical_recipe_text_is_fixed() {
        let plan = parse_plan(TEXT, Path::new("/lib")).unwrap();
        let text = canonical(&plan.entries[0], Path::new("/lib"));
        assert_eq!(
            text,
            "name=k\nprocedural=marble\nsize=8x8x8\nseed=3\ntype=-\nblur.at=40800000,40800000,40800000\n\
             blur.radius=40200000,3f000000\nmask=splotch\nmask_falloff=3d99999a\n"
        );
    }

    /// The same recipe and inputs give the same key wherever the library lives; a changed
    /// input file changes it and is named as the reason.
    #[test]
    fn the_key_follows_the_inputs_not_the_folder() {
        let keys: Vec<Key> = (0..2)
            .map(|i| {
                let dir = tempfile::tempdir().unwrap();
                let folder = dir.path().join(format!("lib{i}"));
                std::fs::create_dir(&folder).unwrap();
                std::fs::write(folder.join("p.png"), b"pixels").unwrap();
                let text = "[[exemplar]]\nname = \"s\"\nrecipe = \"load\"\nvolume = \"p.png\"\n";
                let plan = parse_plan(text, &folder).unwrap();
                key(&plan.entries[0], &folder).unwrap()
            })
            .collect();
        assert_eq!(keys[0], keys[1]);
        assert_eq!(keys[0].inputs[0].path, "p.png");
        let other = Key { inputs: vec![Written { hash: "x".into(), ..keys[0].inputs[0].clone() }], ..keys[0].clone() };
        let record = Record {
            name: "s".into(),
            key: "old".into(),
            recipe: other.recipe.clone(),
            inputs: other.inputs.clone(),
            dims: [1; 3],
            declared: None,
            classified: "0".into(),
            seconds: 0.0,
            files: Vec::new(),
            quality: None,
            warnings: Vec::new(),
        };
        assert_eq!(changed(&keys[0], &record), "the input p.png changed");
    }
}
