//! The exemplar library manifest (`exemplars/library.toml`): a raw serde form, then a
//! validated [`Plan`]. Every error names the file, the entry, the field, the value and
//! what is allowed. Paths in the manifest are relative to the manifest's folder.
//! The format, with examples: `docs/manifest.md`.

use super::values;
use crate::error::{Error, Result};
use crate::procedural::Recipe;
use crate::stamp::{Placement, RADIUS, Region, SCALE};
use crate::sweep::Noise;
use crate::texture_type::TextureType;
use crate::volume::Axis;
use glam::Vec3;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    #[serde(default)]
    exemplar: Vec<RawExemplar>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExemplar {
    name: String,
    recipe: String,
    size: Option<RawSize>,
    #[serde(default)]
    seed: u64,
    #[serde(rename = "type")]
    texture_type: Option<String>,
    image: Option<String>,
    length: Option<usize>,
    axis: Option<String>,
    depth_axis: Option<String>,
    noise: Option<Vec<f32>>,
    skin: Option<String>,
    skin_width: Option<f32>,
    skin_noise: Option<f32>,
    displacement: Option<String>,
    ey: Option<String>,
    ez: Option<String>,
    depth_image: Option<String>,
    levels: Option<usize>,
    max_exemplar: Option<usize>,
    #[serde(default)]
    masks: Vec<String>,
    mask_falloff: Option<f32>,
    #[serde(default)]
    exports: Vec<String>,
    volume: Option<String>,
    #[serde(default)]
    steps: Vec<RawStep>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawSize {
    Cube(usize),
    Dims(Vec<usize>),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStep {
    stamp: Option<String>,
    scatter: Option<String>,
    blur: Option<String>,
    at: Option<String>,
    rotate: Option<String>,
    scale: Option<String>,
    color: Option<String>,
    count: Option<usize>,
    region: Option<String>,
    radius: Option<f32>,
    strength: Option<f32>,
    seed: Option<u64>,
}

/// How the skin looks.
#[derive(Debug, Clone, PartialEq)]
pub enum SkinSource {
    /// A flat colour.
    Colour([f32; 3]),
    /// An image file.
    Image(PathBuf),
}

/// The one rule for a skin, on the command line and in a manifest: a colour when the text
/// reads as one, otherwise an image file that must exist (relative to `folder`).
pub fn skin_source(field: &str, text: &str, folder: &Path) -> Result<SkinSource> {
    match values::colour(field, text) {
        Ok(c) => Ok(SkinSource::Colour(c)),
        Err(_) if folder.join(text).is_file() => Ok(SkinSource::Image(folder.join(text))),
        Err(e) => Err(Error::invalid(format!("{e}; or name an image file that exists (none at {text:?})"))),
    }
}

/// A sweep recipe (see [`crate::sweep`]), with file paths resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSpec {
    /// Cross-section image.
    pub image: PathBuf,
    /// Voxels along the sweep axis.
    pub length: usize,
    /// Sweep axis.
    pub axis: Axis,
    /// Depth axis, if any.
    pub depth_axis: Option<Axis>,
    /// Noise, if any.
    pub noise: Option<Noise>,
    /// Skin look, width and width noise, if any.
    pub skin: Option<(SkinSource, f32, f32)>,
    /// A grey relief image swept into a Displacement channel, if any.
    pub displacement: Option<PathBuf>,
}

/// A synthesis recipe (see [`crate::synth`]), with file paths resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSpec {
    /// The exemplar (Ex; the layered exemplar).
    pub image: PathBuf,
    /// Ey, if different.
    pub ey: Option<PathBuf>,
    /// Ez, if different.
    pub ez: Option<PathBuf>,
    /// Layered (type 1-b) synthesis.
    pub layered: bool,
    /// Depth image for layered synthesis.
    pub depth: Option<PathBuf>,
    /// Pyramid levels.
    pub levels: usize,
    /// Shrink exemplars to this longest side first.
    pub max_exemplar: Option<usize>,
}

/// What makes an exemplar's volume.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// A procedural recipe.
    Procedural(Recipe),
    /// A swept cross-section.
    Sweep(SweepSpec),
    /// 2D-to-3D synthesis.
    Synth(SynthSpec),
    /// An existing volume file (any format solidtex reads).
    Load(PathBuf),
}

/// Masks built beside an exemplar.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskKind {
    /// `NAME.mask.exr`: a splotch.
    Splotch,
    /// `NAME.masks/{outer,middle,inner}.exr`.
    Layered,
}

/// Extra formats written beside the native EXR.
pub const EXPORTS: [&str; 6] = ["nrrd", "vol", "png", "vdb", "dds", "slices"];

/// A step applied after the source, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Stamp one seed mesh.
    Stamp {
        /// Mesh file.
        mesh: PathBuf,
        /// Where.
        placement: Placement,
        /// Fill colour.
        colour: [f32; 3],
    },
    /// Scatter seeds.
    Scatter {
        /// Mesh file.
        mesh: PathBuf,
        /// How many.
        count: usize,
        /// Where (`None`: the whole volume).
        region: Option<Region>,
        /// Scale range.
        scale: (f32, f32),
        /// Fill colour.
        colour: [f32; 3],
        /// Seed of this step.
        seed: u64,
    },
    /// Blur inside a sphere.
    Blur {
        /// Centre.
        at: Vec3,
        /// Radius.
        radius: f32,
        /// Strength at the centre.
        strength: f32,
    },
}

/// One validated library entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Output file stem.
    pub name: String,
    /// What makes the volume.
    pub source: Source,
    /// Size in voxels, when given (procedural: required; sweep: checked against the image).
    pub dims: Option<[usize; 3]>,
    /// Seed for everything random.
    pub seed: u64,
    /// Declared texture type (overrides the recipe's).
    pub texture_type: Option<TextureType>,
    /// Steps after the source.
    pub steps: Vec<Step>,
    /// Masks to build.
    pub masks: Vec<MaskKind>,
    /// Fall-off of the masks, as a share of their size.
    pub mask_falloff: f32,
    /// Extra formats: any of [`EXPORTS`].
    pub exports: Vec<String>,
    /// Where the entry is written in its manifest.
    pub lines: Lines,
}

/// Where an entry is written in its manifest, for the errors about its input files that
/// only its build finds (a file missing or of the wrong kind, a size that does not fit):
/// the manifest (when read from a file), the line of the entry's `[[exemplar]]` header and
/// the line of each field it gives (a step's as `steps[k].field`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Lines {
    /// The manifest file, when the entry was read from one.
    pub manifest: Option<PathBuf>,
    /// The line (from 1) of the entry's header.
    pub header: usize,
    /// The line (from 1) of each field given.
    pub fields: Vec<(String, usize)>,
}

impl Lines {
    /// `error` about the value of `field` (`image`, `steps[0].stamp`), said after the
    /// manifest, the field's line (the header's when the field is not written) and name.
    pub fn error(&self, field: &str, error: Error) -> Error {
        if matches!(error, Error::Cancelled) {
            return error;
        }
        let line = self.fields.iter().find(|(f, _)| f == field).map_or(self.header, |(_, at)| *at);
        let named = match field.strip_prefix("steps[").and_then(|r| r.split_once("].")) {
            Some((k, f)) => format!("step {}, field {f:?}", k.parse::<usize>().map_or(0, |k| k + 1)),
            None => format!("field {field:?}"),
        };
        let message = format!("line {line}, {named}: {error}");
        match &self.manifest {
            Some(manifest) => Error::file(manifest, message),
            None => Error::invalid(message),
        }
    }
}

/// Where entry `i` of manifest `text` (parsed as `document`) is written, without the
/// manifest's name.
fn entry_lines(text: &str, document: Option<&toml_edit::Document<&str>>, i: usize) -> Lines {
    let table = document.and_then(|d| d.as_item().get("exemplar")?.get(i)?.as_table_like());
    let mut fields = Vec::new();
    let mut put = |key: String, item: &toml_edit::Item| {
        if let Some(span) = item.span() {
            fields.push((key, line_at(text, span.start)));
        }
    };
    for (key, item) in table.into_iter().flat_map(|t| t.iter()) {
        match item.as_array_of_tables().filter(|_| key == "steps") {
            Some(steps) => {
                for (k, step) in steps.iter().enumerate() {
                    step.iter().for_each(|(f, value)| put(format!("steps[{k}].{f}"), value));
                }
            }
            None => put(key.to_string(), item),
        }
    }
    Lines { manifest: None, header: entry_line(text, i), fields }
}

/// A validated manifest: what `solidtex build` will make.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Entries in manifest order.
    pub entries: Vec<Entry>,
}

/// Largest side accepted in a manifest.
pub const MAX_SIDE: usize = 512;

/// Most scattered seeds per step (see [`crate::stamp::MAX_COUNT`]).
pub const MAX_COUNT: usize = crate::stamp::MAX_COUNT;

/// Read and validate a manifest file; relative paths in it are resolved from its folder.
/// A file that is not TOML is named as such, and its content is not quoted.
pub fn read_plan(path: &Path) -> Result<Plan> {
    let text = super::read_text(path, "manifest")?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut plan = plan_of(&text, folder, has_toml_name(path)).map_err(|e| e.in_file(path))?;
    for entry in &mut plan.entries {
        entry.lines.manifest = Some(path.to_path_buf());
    }
    Ok(plan)
}

/// Validate manifest text; `folder` resolves relative paths.
pub fn parse_plan(text: &str, folder: &Path) -> Result<Plan> {
    plan_of(text, folder, true)
}

/// Entry `name` of manifest `text`, valid, whatever mistakes other entries have; the error
/// is this entry's own (or the file's syntax error, or that no entry has the name).
pub fn parse_entry(text: &str, folder: &Path, name: &str) -> Result<Entry> {
    let (entries, errors) = parse_plan_lenient(text, folder);
    if let Some(entry) = entries.into_iter().find(|e| e.name == name) {
        return Ok(entry);
    }
    let shown = shown_name(name);
    let own = errors.iter().find(|e| e.contains(&format!("({shown})")) || e.contains(&format!("{name:?}")));
    let whole = errors.iter().find(|e| !e.contains(": entry "));
    match own.or(whole) {
        Some(error) => Err(Error::invalid(error.clone())),
        None => Err(Error::invalid(format!("no exemplar named {name:?}"))),
    }
}

/// Whether a path ends in `.toml`: only then may a TOML error quote a line of it.
pub(crate) fn has_toml_name(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// [`parse_plan`]; `quote` allows a syntax error to show the line it is on.
fn plan_of(text: &str, folder: &Path, quote: bool) -> Result<Plan> {
    let raw: RawManifest = toml::from_str(text).map_err(|e| syntax_error(text, &e, "manifest", quote))?;
    let document = toml_edit::Document::parse(text).ok();
    let mut entries: Vec<Entry> = Vec::new();
    for (i, e) in raw.exemplar.into_iter().enumerate() {
        let name = e.name.clone();
        let mut entry = validate(e, folder).map_err(|err| Error::invalid(entry_error(text, i, &name, &err)))?;
        entry.lines = entry_lines(text, document.as_ref(), i);
        if entries.iter().any(|x| x.name == entry.name) {
            let line = entry_line(text, i);
            return Err(Error::invalid(format!(
                "line {line}: entry {}: name = {name:?} is used twice; names must be unique",
                i + 1
            )));
        }
        entries.push(entry);
    }
    if entries.is_empty() {
        return Err(Error::invalid("the manifest has no [[exemplar]] entries"));
    }
    Ok(Plan { entries })
}

/// Like [`parse_plan`], but keeps going past bad entries: the valid entries, and one
/// message per bad one (or one for the whole text when it is not valid TOML).
pub fn parse_plan_lenient(text: &str, folder: &Path) -> (Vec<Entry>, Vec<String>) {
    let (raw, mut errors) = match toml::from_str::<RawManifest>(text) {
        Ok(raw) => (raw.exemplar.into_iter().map(Some).collect(), Vec::new()),
        Err(e) => match each_entry(text) {
            Some(each) => each,
            None => return (Vec::new(), vec![syntax_error(text, &e, "manifest", true).to_string()]),
        },
    };
    let document = toml_edit::Document::parse(text).ok();
    let mut entries: Vec<Entry> = Vec::new();
    let read_errors = std::mem::take(&mut errors);
    for (i, e) in raw.into_iter().enumerate() {
        let Some(e) = e else { continue };
        let name = e.name.clone();
        let line = entry_line(text, i);
        match validate(e, folder) {
            Ok(entry) if entries.iter().any(|x| x.name == entry.name) => errors
                .push(format!("line {line}: entry {}: name = {name:?} is used twice; names must be unique", i + 1)),
            Ok(entry) => entries.push(Entry { lines: entry_lines(text, document.as_ref(), i), ..entry }),
            Err(err) => errors.push(entry_error(text, i, &name, &err)),
        }
    }
    // every mistake in the manifest's order (a message without a line first)
    errors.extend(read_errors);
    let line = |e: &String| e.strip_prefix("line ").and_then(|r| r.split(':').next()?.parse::<usize>().ok());
    errors.sort_by_key(|e| line(e).unwrap_or(0));
    (entries, errors)
}

/// A manifest that is good TOML but whose entries do not all read, read entry by entry: each
/// entry that reads (`None` for one that does not), and a message per entry that does not
/// and per unknown top-level key. `None` when the text is not a TOML table.
#[allow(clippy::type_complexity)]
fn each_entry(text: &str) -> Option<(Vec<Option<RawExemplar>>, Vec<String>)> {
    let table: toml::Table = toml::from_str(text).ok()?;
    let mut errors: Vec<String> = table
        .keys()
        .filter(|k| *k != "exemplar")
        .map(|k| format!("unknown top-level key {k:?}; a manifest holds [[exemplar]] tables only"))
        .collect();
    let list = match table.get("exemplar") {
        Some(toml::Value::Array(list)) => list.clone(),
        Some(_) => {
            errors.push("exemplar must be a list of [[exemplar]] tables".to_string());
            Vec::new()
        }
        None => Vec::new(),
    };
    let mut raw = Vec::new();
    for (i, value) in list.into_iter().enumerate() {
        match value.try_into::<RawExemplar>() {
            Ok(entry) => raw.push(Some(entry)),
            Err(e) => {
                errors.push(format!("line {}: entry {}: {}", entry_line(text, i), i + 1, plain(e.message().trim())));
                raw.push(None);
            }
        }
    }
    Some((raw, errors))
}

/// The line (from 1) of the `i`-th `[[exemplar]]` header.
fn entry_line(text: &str, i: usize) -> usize {
    text.lines().enumerate().filter(|(_, l)| l.trim() == "[[exemplar]]").nth(i).map_or(0, |(n, _)| n + 1)
}

/// The message of an error in entry `i`: the entry's line and name, and the line of the
/// field the error is about when that is another line.
fn entry_error(text: &str, i: usize, name: &str, error: &Error) -> String {
    let line = entry_line(text, i);
    let message = error.to_string();
    let (step, rest) = match message.strip_prefix("steps[").and_then(|r| r.split_once("]: ")) {
        Some((k, rest)) => (Some(k), rest),
        None => (None, message.as_str()),
    };
    let mut path = format!("exemplar[{i}]");
    if let Some(k) = step {
        path += &format!(".steps[{k}]");
    }
    let field = leading_path(rest);
    let field_line = line_of(text, &format!("{path}.{field}")).or_else(|| line_of(text, &path));
    let said = match step.and_then(|k| k.parse::<usize>().ok()) {
        Some(k) => format!("step {}: {rest}", k + 1),
        None => message.clone(),
    };
    let entry = format!("entry {} ({})", i + 1, shown_name(name));
    match field_line {
        Some(at) if at != line => format!("line {line}: {entry}, line {at}: {said}"),
        _ => format!("line {line}: {entry}: {said}"),
    }
}

/// The field path a validation message starts with, e.g. `depth.points[0]` or `count`.
pub(crate) fn leading_path(message: &str) -> &str {
    let end = message
        .find(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '[' | ']')))
        .unwrap_or(message.len());
    message[..end].trim_end_matches('.')
}

/// The line (from 1) where the value at `path` (keys and `[index]`es joined by dots, e.g.
/// `exemplar[0].steps[1].count`) is written in TOML `text`, if it is there.
pub(crate) fn line_of(text: &str, path: &str) -> Option<usize> {
    let document = toml_edit::Document::parse(text).ok()?;
    let mut item = document.as_item();
    let mut span = None;
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let (key, index) = match part.split_once('[') {
            Some((key, rest)) => (key, Some(rest.trim_end_matches(']').parse::<usize>().ok()?)),
            None => (part, None),
        };
        item = item.get(key)?;
        span = item.span().or(span);
        if let Some(index) = index {
            item = item.get(index)?;
            span = item.span().or(span);
        }
    }
    span.map(|s| line_at(text, s.start))
}

/// The line (from 1) of byte `offset` of `text`.
pub(crate) fn line_at(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())].iter().filter(|b| **b == b'\n').count() + 1
}

/// A TOML error of a `what` (manifest, fill spec) as a message with its line. With `quote`
/// (a `.toml` file, or text from the editor) and a line of printable text, the line is
/// shown, cut to 80 characters; otherwise the file is said not to be TOML and nothing of
/// it is echoed.
pub(crate) fn syntax_error(text: &str, error: &toml::de::Error, what: &str, quote: bool) -> Error {
    let plain = plain(error.message().trim_end());
    let message = plain.as_str();
    let Some(start) = error.span().map(|s| s.start.min(text.len())) else {
        return Error::invalid(format!("invalid {what}: {message}"));
    };
    let line = line_at(text, start);
    let shown = text.lines().nth(line - 1).unwrap_or_default();
    let printable = !shown.chars().any(|c| c.is_control() && c != '\t');
    if !(quote && printable) {
        return Error::invalid(format!(
            "is not a TOML {what} (TOML error at line {line}: {}); name the {what}'s .toml file",
            clip(message, 80)
        ));
    }
    Error::invalid(format!("invalid {what} at line {line}: {message}: {:?}", clip(shown.trim(), 80)))
}

/// A reader's message (`invalid value: integer \`-5\`, expected usize`) in the user's
/// words (`must be a whole number, 0 or more, got -5`).
fn plain(message: &str) -> String {
    if message.contains("untagged enum RawSize") {
        return format!("size must be one whole number or three, each 1 to {MAX_SIDE}, e.g. 64 or [64, 64, 32]");
    }
    if message.contains("as i128") {
        // the TOML reader's own words for an integer past 64 bits
        return "is a whole number too large to read (past 64 bits); every number a manifest holds is far \
                smaller (a size is 1 to 512)"
            .to_string();
    }
    const WANTS: [(&str, &str); 7] = [
        ("expected usize", "a whole number, 0 or more"),
        ("expected u64", "a whole number, 0 or more"),
        ("expected f32", "a number"),
        ("expected a sequence", "a list, e.g. [1, 2]"),
        ("expected a string", "text in quotes"),
        ("expected struct RawStep", "a [[exemplar.steps]] table"),
        ("expected struct RawExemplar", "an [[exemplar]] table"),
    ];
    for (tail, want) in WANTS {
        if let Some(head) = message.strip_suffix(tail) {
            let got = head.trim_end_matches([',', ' ']);
            let got = got.strip_prefix("invalid value: ").or(got.strip_prefix("invalid type: ")).unwrap_or(got);
            let got = got.replace('`', "").replace("integer ", "").replace("floating point ", "");
            return format!("must be {want}, got {got}");
        }
    }
    message.to_string()
}

/// `text` cut to `most` characters, with `...` where it was cut.
fn clip(text: &str, most: usize) -> String {
    match text.char_indices().nth(most) {
        Some((at, _)) => format!("{}...", &text[..at]),
        None => text.to_string(),
    }
}

/// Which recipes take a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Takers {
    /// Every recipe.
    All,
    /// `synth` and `synth-layered`.
    Synth,
    /// `synth-layered` only.
    Layered,
    /// `synth` only (a homogeneous solid's other cross-sections).
    Homogeneous,
    /// `sweep` only.
    Sweep,
    /// `load` only.
    Load,
    /// The recipes that make a volume of a given size: procedural ones and synthesis.
    Sized,
}

impl Takers {
    /// Whether `recipe` takes the field.
    pub fn take(self, recipe: &str) -> bool {
        let synth = recipe == "synth" || recipe == "synth-layered";
        match self {
            Takers::All => true,
            Takers::Synth => synth,
            Takers::Layered => recipe == "synth-layered",
            Takers::Homogeneous => recipe == "synth",
            Takers::Sweep => recipe == "sweep",
            Takers::Load => recipe == "load",
            Takers::Sized => synth || recipe.starts_with("procedural:"),
        }
    }
}

/// One field of an `[[exemplar]]` entry: the recipes that take it, whether they need it,
/// the values it allows and the value a new one starts with. The manifest's checks and the
/// TUI's field picker read this one table.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldRule {
    /// The key.
    pub key: &'static str,
    /// The recipes that take it.
    pub takers: Takers,
    /// Whether those recipes need it.
    pub required: bool,
    /// What values it allows, in words.
    pub allowed: String,
    /// A new field's value (TOML).
    pub start: String,
}

/// Every entry field but `name`, `recipe` and `steps`, in the order a picker lists them.
pub fn field_rules() -> Vec<FieldRule> {
    use crate::sweep::{AMPLITUDE, FREQUENCY, JITTER, SKIN_WIDTH};
    use crate::synth::SynthParams;
    let rule = |key, takers, required, allowed: String, start: &str| FieldRule {
        key,
        takers,
        required,
        allowed,
        start: start.to_string(),
    };
    let image = "an image file, relative to the manifest's folder".to_string();
    let axis = "\"x\", \"y\" or \"z\"".to_string();
    let (levels, side) = (SynthParams::LEVELS, SynthParams::EXEMPLAR_SIDE);
    vec![
        rule("size", Takers::Sized, true, format!("N or [x, y, z], each 1 to {MAX_SIDE}"), "64"),
        rule("size", Takers::Sweep, false, format!("the size the sweep must make, each side 1 to {MAX_SIDE}"), "64"),
        rule("seed", Takers::All, false, "a whole number, 0 or more".into(), "1"),
        rule(
            "type",
            Takers::All,
            false,
            "\"0\", \"1-a\", \"1-b\", \"2-a\", \"2-b\", \"2-c\" or \"2-d\"".into(),
            "\"0\"",
        ),
        rule("image", Takers::Synth, true, image.clone(), "\"\""),
        rule("image", Takers::Sweep, true, image.clone(), "\"\""),
        rule("levels", Takers::Synth, false, format!("{} to {}", levels.0, levels.1), "3"),
        rule("max_exemplar", Takers::Synth, false, format!("{} to {} pixels", side.0, side.1), "128"),
        rule("ey", Takers::Homogeneous, false, format!("{image} (the cut across y)"), "\"\""),
        rule("ez", Takers::Homogeneous, false, format!("{image} (the cut across z)"), "\"\""),
        rule("depth_image", Takers::Layered, false, format!("{image}, grey: each pixel's depth"), "\"\""),
        rule("length", Takers::Sweep, true, format!("1 to {MAX_SIDE} voxels along the axis"), "64"),
        rule("axis", Takers::Sweep, true, axis.clone(), "\"z\""),
        rule("depth_axis", Takers::Sweep, false, axis, "\"z\""),
        rule(
            "noise",
            Takers::Sweep,
            false,
            format!(
                "[amplitude {}-{}, frequency {}-{}] or with a jitter {}-{}",
                AMPLITUDE.0, AMPLITUDE.1, FREQUENCY.0, FREQUENCY.1, JITTER.0, JITTER.1
            ),
            "[2.0, 4.0]",
        ),
        rule(
            "skin",
            Takers::Sweep,
            false,
            "a colour (\"#5a3a1a\" or \"0.35,0.23,0.1\") or an image file".into(),
            "\"#5a3a1a\"",
        ),
        rule("skin_width", Takers::Sweep, false, format!("{} to {} voxels", SKIN_WIDTH.0, SKIN_WIDTH.1), "2.0"),
        rule("skin_noise", Takers::Sweep, false, format!("{} to {} voxels", SKIN_WIDTH.0, SKIN_WIDTH.1), "0.0"),
        rule("displacement", Takers::Sweep, false, format!("{image}, grey relief"), "\"\""),
        rule("volume", Takers::Load, true, "a volume file (exr, nrrd, vol, png, vdb, dds)".into(), "\"\""),
        rule("masks", Takers::All, false, "a list of \"splotch\" and \"layered\"".into(), "[\"splotch\"]"),
        rule("mask_falloff", Takers::All, false, "more than 0, less than 0.5".into(), "0.075"),
        rule(
            "exports",
            Takers::All,
            false,
            format!("a list of {}", EXPORTS.map(|e| format!("\"{e}\"")).join(", ")),
            "[\"nrrd\"]",
        ),
    ]
}

/// The fields `recipe` takes, in the table's order.
pub fn fields_of(recipe: &str) -> Vec<FieldRule> {
    field_rules().into_iter().filter(|r| r.takers.take(recipe)).collect()
}

/// The fields an entry sets (besides `name`, `recipe` and `steps`).
fn set_fields(raw: &RawExemplar) -> Vec<&'static str> {
    let options = [
        ("size", raw.size.is_some()),
        ("type", raw.texture_type.is_some()),
        ("image", raw.image.is_some()),
        ("length", raw.length.is_some()),
        ("axis", raw.axis.is_some()),
        ("depth_axis", raw.depth_axis.is_some()),
        ("noise", raw.noise.is_some()),
        ("skin", raw.skin.is_some()),
        ("skin_width", raw.skin_width.is_some()),
        ("skin_noise", raw.skin_noise.is_some()),
        ("displacement", raw.displacement.is_some()),
        ("ey", raw.ey.is_some()),
        ("ez", raw.ez.is_some()),
        ("depth_image", raw.depth_image.is_some()),
        ("levels", raw.levels.is_some()),
        ("max_exemplar", raw.max_exemplar.is_some()),
        ("volume", raw.volume.is_some()),
    ];
    options.iter().filter(|(_, set)| *set).map(|(key, _)| *key).collect()
}

/// An error when the entry sets a field its recipe does not take (the table says which).
fn check_fields(raw: &RawExemplar) -> Result<()> {
    let takes = fields_of(&raw.recipe);
    match set_fields(raw).into_iter().find(|key| !takes.iter().any(|r| r.key == *key)) {
        None => Ok(()),
        Some(key) => {
            let mut keys: Vec<&str> = takes.iter().map(|r| r.key).collect();
            keys.dedup();
            Err(Error::invalid(format!(
                "{key} does not apply to recipe {:?}; its fields: {}",
                raw.recipe,
                keys.join(", ")
            )))
        }
    }
}

/// The longest exemplar name in bytes: its files (`NAME.sheet.png`, `NAME_slices`) and their
/// temporaries (`.NAME.sheet.png.solidtex-XXXXXX.tmp`) stay within the 255 bytes a file
/// name may have.
pub const MAX_NAME: usize = 200;

/// An exemplar name as shown in a message: at most 40 characters.
fn shown_name(name: &str) -> String {
    clip(name, 40)
}

fn validate(raw: RawExemplar, folder: &Path) -> Result<Entry> {
    let ok_name = !raw.name.is_empty() && raw.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if !ok_name {
        return Err(Error::invalid(format!(
            "name = {:?} is not allowed: use ASCII letters, digits, '-' and '_'",
            shown_name(&raw.name)
        )));
    }
    if raw.name.len() > MAX_NAME {
        return Err(Error::invalid(format!(
            "name = {:?} ({} bytes) is too long: a name has at most {MAX_NAME} bytes, as it becomes file names",
            shown_name(&raw.name),
            raw.name.len()
        )));
    }
    let dims = raw.size.as_ref().map(dims_of).transpose()?;
    let source = match raw.recipe.as_str() {
        "sweep" => Source::Sweep(sweep_spec(&raw, folder)?),
        "synth" | "synth-layered" => Source::Synth(synth_spec(&raw, folder)?),
        "load" => Source::Load(
            folder.join(
                raw.volume
                    .as_deref()
                    .ok_or_else(|| Error::invalid("volume is missing; recipe load needs volume = FILE"))?,
            ),
        ),
        other => match other.strip_prefix("procedural:") {
            Some(r) => Source::Procedural(r.parse::<Recipe>().map_err(|e| Error::invalid(format!("recipe: {e}")))?),
            None => {
                let procedural: Vec<String> = Recipe::ALL.iter().map(|r| format!("procedural:{}", r.name())).collect();
                return Err(Error::invalid(format!(
                    "recipe = {other:?} is unknown; allowed: {}, sweep, synth, synth-layered, load",
                    procedural.join(", ")
                )));
            }
        },
    };
    check_fields(&raw)?;
    if matches!(source, Source::Procedural(_) | Source::Synth(_)) && dims.is_none() {
        return Err(Error::invalid(format!("size is missing; recipe {} needs size = N or [x, y, z]", raw.recipe)));
    }
    let masks = raw
        .masks
        .iter()
        .map(|m| match m.as_str() {
            "splotch" => Ok(MaskKind::Splotch),
            "layered" => Ok(MaskKind::Layered),
            other => Err(Error::invalid(format!("masks: {other:?} is unknown; allowed: splotch, layered"))),
        })
        .collect::<Result<Vec<_>>>()?;
    let mask_falloff = values::falloff("mask_falloff =", raw.mask_falloff.unwrap_or(crate::mask::DEFAULT_FALLOFF))?;
    if let Some(bad) = raw.exports.iter().find(|e| !EXPORTS.contains(&e.as_str())) {
        return Err(Error::invalid(format!("exports: {bad:?} is unknown; allowed: {}", EXPORTS.join(", "))));
    }
    if let Some(dims) = dims {
        check_exports(&raw.exports, dims)?;
    }
    let texture_type = raw
        .texture_type
        .as_deref()
        .map(|t| t.parse::<TextureType>())
        .transpose()
        .map_err(|e| Error::invalid(format!("type: {e}")))?;
    let steps = raw
        .steps
        .iter()
        .enumerate()
        .map(|(k, s)| step(s, folder).map_err(|e| Error::invalid(format!("steps[{k}]: {e}"))))
        .collect::<Result<_>>()?;
    Ok(Entry {
        name: raw.name,
        source,
        dims,
        seed: raw.seed,
        texture_type,
        steps,
        masks,
        mask_falloff,
        exports: raw.exports,
        lines: Lines::default(),
    })
}

/// An error when `exports` asks for a format that cannot hold a volume of `dims`: a `.vol`
/// file holds cubes only.
pub fn check_exports(exports: &[String], dims: [usize; 3]) -> Result<()> {
    if exports.iter().any(|e| e == "vol") && !(dims[0] == dims[1] && dims[1] == dims[2]) {
        return Err(Error::invalid(format!(
            "exports: \"vol\" needs a cube, but the volume is {}x{}x{}; a .vol file holds cubes only \
             (export \"nrrd\" instead, or make the size a cube)",
            dims[0], dims[1], dims[2]
        )));
    }
    Ok(())
}

fn dims_of(size: &RawSize) -> Result<[usize; 3]> {
    let dims = match size {
        RawSize::Cube(n) => [*n; 3],
        RawSize::Dims(v) if v.len() == 3 => [v[0], v[1], v[2]],
        RawSize::Dims(v) => {
            return Err(Error::invalid(format!(
                "size = {v:?} must be one whole number or three, each 1 to {MAX_SIDE}, e.g. 64 or [64, 64, 32]"
            )));
        }
    };
    if dims.iter().any(|d| *d == 0 || *d > MAX_SIDE) {
        let written = match size {
            RawSize::Cube(n) => n.to_string(),
            RawSize::Dims(v) => format!("{v:?}"),
        };
        return Err(Error::invalid(format!("size = {written} is out of range; each side must be 1..={MAX_SIDE}")));
    }
    Ok(dims)
}

fn sweep_spec(raw: &RawExemplar, folder: &Path) -> Result<SweepSpec> {
    let need = |field: &str| Error::invalid(format!("{field} is missing; a sweep needs image, length and axis"));
    let image = folder.join(raw.image.as_deref().ok_or_else(|| need("image"))?);
    let length = raw.length.ok_or_else(|| need("length"))?;
    if length == 0 || length > MAX_SIDE {
        return Err(Error::invalid(format!("length = {length} is out of range; allowed 1..={MAX_SIDE}")));
    }
    let axis: Axis =
        raw.axis.as_deref().ok_or_else(|| need("axis"))?.parse().map_err(|e| Error::invalid(format!("axis: {e}")))?;
    let depth_axis = raw
        .depth_axis
        .as_deref()
        .map(str::parse::<Axis>)
        .transpose()
        .map_err(|e| Error::invalid(format!("depth_axis: {e}")))?;
    if depth_axis == Some(axis) {
        return Err(Error::invalid(format!(
            "depth_axis = \"{axis}\" is the sweep's axis; depth must run along one of the cross-section's axes"
        )));
    }
    if raw.skin.is_some() && depth_axis.is_none() {
        return Err(Error::invalid("skin needs depth_axis: a skin covers the face where depth is 0"));
    }
    let noise = match raw.noise.as_deref() {
        None => None,
        Some([a, f]) => Some(noise("noise", *a, *f, 0.0)?),
        Some([a, f, j]) => Some(noise("noise", *a, *f, *j)?),
        Some(v) => {
            return Err(Error::invalid(format!(
                "noise = {v:?} must be [amplitude, frequency] or [amplitude, frequency, jitter]"
            )));
        }
    };
    let skin = raw
        .skin
        .as_deref()
        .map(|s| {
            let look = skin_source("skin", s, folder)?;
            let (lo, hi) = crate::sweep::SKIN_WIDTH;
            let width = values::within("skin_width =", raw.skin_width.unwrap_or(2.0), lo, hi)?;
            let width_noise = values::within("skin_noise =", raw.skin_noise.unwrap_or(0.0), lo, hi)?;
            Ok((look, width, width_noise))
        })
        .transpose()?;
    let displacement = raw.displacement.as_deref().map(|p| folder.join(p));
    Ok(SweepSpec { image, length, axis, depth_axis, noise, skin, displacement })
}

/// Sweep noise with each part in its range; `label` names the option or field.
pub fn noise(label: &str, amplitude: f32, frequency: f32, jitter: f32) -> Result<Noise> {
    use crate::sweep::{AMPLITUDE, FREQUENCY, JITTER};
    let noise = Noise {
        amplitude: values::within(&format!("{label} amplitude"), amplitude, AMPLITUDE.0, AMPLITUDE.1)?,
        frequency: values::within(&format!("{label} frequency"), frequency, FREQUENCY.0, FREQUENCY.1)?,
        jitter: values::within(&format!("{label} jitter"), jitter, JITTER.0, JITTER.1)?,
    };
    crate::sweep::check_frequency(label, &noise)?;
    Ok(noise)
}

fn synth_spec(raw: &RawExemplar, folder: &Path) -> Result<SynthSpec> {
    let image = folder
        .join(raw.image.as_deref().ok_or_else(|| Error::invalid("image is missing; synth needs an exemplar image"))?);
    let (lo, hi) = crate::synth::SynthParams::LEVELS;
    let levels = values::within("levels =", raw.levels.unwrap_or(3), lo, hi)?;
    let (lo, hi) = crate::synth::SynthParams::EXEMPLAR_SIDE;
    let max_exemplar = raw.max_exemplar.map(|m| values::within("max_exemplar =", m, lo, hi)).transpose()?;
    let layered = raw.recipe == "synth-layered";
    if !layered && raw.depth_image.is_some() {
        return Err(Error::invalid("depth_image needs recipe = \"synth-layered\""));
    }
    let join = |p: &Option<String>| p.as_deref().map(|p| folder.join(p));
    Ok(SynthSpec {
        image,
        ey: join(&raw.ey),
        ez: join(&raw.ez),
        layered,
        depth: join(&raw.depth_image),
        levels,
        max_exemplar,
    })
}

fn step(raw: &RawStep, folder: &Path) -> Result<Step> {
    let actions = [raw.stamp.is_some(), raw.scatter.is_some(), raw.blur.is_some()].iter().filter(|b| **b).count();
    if actions != 1 {
        return Err(Error::invalid(
            "each step needs exactly one of stamp = \"MESH\", scatter = \"MESH\", blur = \"X,Y,Z\"",
        ));
    }
    let colour = || values::colour("color", raw.color.as_deref().ok_or_else(|| Error::invalid("color is missing"))?);
    if let Some(mesh) = &raw.stamp {
        let at = values::point("at", raw.at.as_deref().ok_or_else(|| Error::invalid("at is missing"))?)?;
        let rotation = raw.rotate.as_deref().map(|r| values::rotation("rotate", r)).transpose()?.unwrap_or_default();
        let scale = values::scale("scale =", raw.scale.as_deref().unwrap_or("1"), SCALE.0, SCALE.1)?;
        return Ok(Step::Stamp {
            mesh: folder.join(mesh),
            placement: Placement { at, rotation, scale },
            colour: colour()?,
        });
    }
    if let Some(mesh) = &raw.scatter {
        let count = raw.count.ok_or_else(|| Error::invalid("count is missing"))?;
        let count = values::within("count =", count, 1, MAX_COUNT)?;
        let region = raw.region.as_deref().map(region).transpose()?;
        let scale = values::range("scale =", raw.scale.as_deref().unwrap_or("1"), SCALE.0, SCALE.1)?;
        return Ok(Step::Scatter {
            mesh: folder.join(mesh),
            count,
            region,
            scale,
            colour: colour()?,
            seed: raw.seed.unwrap_or(1),
        });
    }
    let at = values::point("blur", raw.blur.as_deref().unwrap_or_default())?;
    let radius = raw.radius.ok_or_else(|| Error::invalid("radius is missing"))?;
    let radius = values::within("radius =", radius, RADIUS.0, RADIUS.1)?;
    let strength = values::within("strength =", raw.strength.unwrap_or(1.0), 0.0, 1.0)?;
    Ok(Step::Blur { at, radius, strength })
}

/// `box:X0,Y0,Z0,X1,Y1,Z1` (the first corner nowhere past the second) or `depth:FROM,TO`
/// (0 <= FROM <= TO <= 1).
pub fn region(text: &str) -> Result<Region> {
    if let Some(rest) = text.strip_prefix("box:") {
        let v = values::numbers("region box", rest, &[6])?;
        values::positions("region box", rest, &v)?;
        let (a, b) = (Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5]));
        if let Some(why) = crate::stamp::reversed_corners(a, b) {
            return Err(Error::invalid(format!("region box {rest:?} {why}")));
        }
        return Ok(Region::Box(a, b));
    }
    if let Some(rest) = text.strip_prefix("depth:") {
        let v = values::numbers("region depth", rest, &[2])?;
        if !(0.0 <= v[0] && v[0] <= v[1] && v[1] <= 1.0) {
            return Err(Error::invalid(format!(
                "region depth {rest:?} is out of range; allowed: 0 <= FROM <= TO <= 1"
            )));
        }
        return Ok(Region::Depth(v[0], v[1]));
    }
    Err(Error::invalid(format!("region {text:?} is not box:X0,Y0,Z0,X1,Y1,Z1 or depth:FROM,TO")))
}

#[cfg(test)]
mod tests {

    #[test]
    fn lenient_parsing_keeps_the_valid_entries_and_names_each_bad_one() {
        let text = "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n\n[[exemplar]]\nname = \"b\"\nrecipe = \"procedural:nope\"\nsize = 8\n\n[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:wood\"\nsize = 8\n";
        let (entries, errors) = parse_plan_lenient(text, Path::new("."));
        assert_eq!(entries.iter().map(|e| e.name.as_str()).collect::<Vec<_>>(), ["a"]);
        assert_eq!(errors.len(), 2, "{errors:?}");
        assert!(errors[0].starts_with("line 6: entry 2 (b), line 8: recipe"), "{errors:?}");
        assert!(errors[1].contains("line 11") && errors[1].contains("used twice"), "{errors:?}");
        let (none, broken) = parse_plan_lenient("[[exemplar]\n", Path::new("."));
        assert!(none.is_empty() && broken[0].contains("invalid manifest"));
        // an entry that does not read (no name, a field of the wrong type) takes only itself
        // down; every mistake is listed, in the manifest's order
        let marble = "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n";
        let nameless = "[[exemplar]]\nrecipe = \"procedural:wood\"\nsize = 8\n";
        let lava = "[[exemplar]]\nname = \"z\"\nrecipe = \"procedural:lava\"\nsize = 99999\n";
        let typed = "[[exemplar]]\nname = \"t\"\nrecipe = \"procedural:wood\"\nsize = \"big\"\n";
        let strata = "[[exemplar]]\nname = \"s\"\nrecipe = \"procedural:strata\"\nsize = 8\n";
        let text = [marble, lava, nameless, typed, strata].join("\n");
        let (entries, errors) = parse_plan_lenient(&text, Path::new("."));
        assert_eq!(entries.iter().map(|e| e.name.as_str()).collect::<Vec<_>>(), ["a", "s"]);
        assert_eq!(errors.len(), 3, "{errors:?}");
        assert!(errors[0].starts_with("line 6: entry 2 (z)"), "{errors:?}");
        assert!(errors[1].starts_with("line 11: entry 3: missing field `name`"), "{errors:?}");
        assert!(errors[2].starts_with("line 15: entry 4: ") && errors[2].contains("size"), "{errors:?}");
    }

    #[test]
    fn values_out_of_range_name_their_line_field_value_and_range() {
        let head = "[[exemplar]]\nname = \"k\"\nrecipe = \"sweep\"\nimage = \"i.png\"\nlength = 8\naxis = \"x\"\n";
        let cases = [
            ("noise = [1.0, 2000000.0]", "line 7: noise frequency 2000000 is out of range; allowed: 0 to 64"),
            ("noise = [1.0, nan]", "line 7: noise frequency NaN is out of range"),
            ("depth_axis = \"z\"\nskin = \"#000000\"\nskin_width = 1e9", "line 9: skin_width = 1000000000"),
            (
                "[[exemplar.steps]]\nscatter = \"s.obj\"\ncolor = \"#000000\"\ncount = 10000000",
                "line 10: step 1: count = 10000000 is out of range; allowed: 1 to 2000",
            ),
            (
                "[[exemplar.steps]]\nblur = \"1,1,1\"\nradius = 1e9",
                "line 9: step 1: radius = 1000000000 is out of range; allowed: 0.1 to 64",
            ),
            ("[[exemplar.steps]]\nblur = \"1,1,1\"\nradius = 2\nstrength = 3", "line 10: step 1: strength = 3"),
            (
                "[[exemplar.steps]]\nstamp = \"s.obj\"\nat = \"1,1,1\"\nscale = \"0\"\ncolor = \"#000000\"",
                "line 10: step 1: scale = \"0\" is out of range",
            ),
            (
                "[[exemplar.steps]]\nscatter = \"s.obj\"\ncolor = \"#000000\"\ncount = 1\nregion = \"box:0,0,0,1e30,1,1\"",
                "line 11: step 1: region box",
            ),
            (
                "[[exemplar.steps]]\nscatter = \"s.obj\"\ncolor = \"#000000\"\ncount = 1\nregion = \"box:0,5,0,1,1,1\"",
                "line 11: step 1: region box \"0,5,0,1,1,1\" has its corners reversed: Y0 5 is past Y1 1",
            ),
        ];
        for (body, expected) in cases {
            let err = plan(&format!("{head}{body}\n")).unwrap_err().to_string();
            assert!(err.starts_with("line 1: entry 1 (k), "), "{err}");
            assert!(err.contains(expected), "{body}: {err}");
        }
        let synth = "[[exemplar]]\nname = \"s\"\nrecipe = \"synth\"\nimage = \"i.png\"\nsize = 8\nmax_exemplar = 0\n";
        assert!(
            plan(synth)
                .unwrap_err()
                .to_string()
                .contains("line 6: max_exemplar = 0 is out of range; allowed: 8 to 4096")
        );
        // a size is quoted as written; a number past 64 bits is named as such
        let marble =
            |size: &str| format!("[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = {size}\n");
        let err = plan(&marble("99999")).unwrap_err().to_string();
        assert!(err.contains("size = 99999 is out of range; each side must be 1..=512"), "{err}");
        let err = plan(&marble("[8, 0, 8]")).unwrap_err().to_string();
        assert!(err.contains("size = [8, 0, 8] is out of range"), "{err}");
        let err = plan(&marble("99999999999999999999")).unwrap_err().to_string();
        assert!(err.contains("too large to read") && err.contains("1 to 512"), "{err}");
    }

    #[test]
    fn a_vol_export_of_a_volume_that_is_not_a_cube_is_refused() {
        let text =
            "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = [8, 8, 4]\nexports = [\"vol\"]\n";
        let err = plan(text).unwrap_err().to_string();
        assert!(err.contains("line 5: exports: \"vol\" needs a cube, but the volume is 8x8x4"), "{err}");
        assert!(plan(&text.replace("[8, 8, 4]", "8")).is_ok());
        assert!(check_exports(&["nrrd".to_string()], [8, 8, 4]).is_ok());
    }

    #[test]
    fn syntax_errors_quote_a_toml_line_but_nothing_of_other_files() {
        let bad = "[[exemplar]]\nname = \"a\"\nrecipe = = 2\n";
        let quoted = plan_of(bad, Path::new("."), true).unwrap_err().to_string();
        assert!(quoted.contains("invalid manifest at line 3") && quoted.contains("recipe = = 2"), "{quoted}");
        let text = "v 0 0 0\nv 1 0 0 secret\n";
        let plain = plan_of(text, Path::new("."), false).unwrap_err().to_string();
        assert!(plain.contains("is not a TOML manifest") && plain.contains("line 1"), "{plain}");
        assert!(!plain.contains("v 0 0") && !plain.contains("secret"), "{plain}");
        let control = plan_of("\u{1}\u{2}PNG\n", Path::new("."), true).unwrap_err().to_string();
        assert!(control.contains("is not a TOML manifest") && !control.contains("PNG"), "{control}");
    }
    use super::*;

    #[test]
    fn a_skin_is_a_colour_or_an_existing_image_by_one_rule() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("bark"), b"an image without an extension").unwrap();
        assert_eq!(skin_source("skin", "#336699", dir.path()).unwrap(), SkinSource::Colour([0.2, 0.4, 0.6]));
        assert_eq!(skin_source("skin", "bark", dir.path()).unwrap(), SkinSource::Image(dir.path().join("bark")));
        let err = skin_source("skin", "bark.png", dir.path()).unwrap_err().to_string();
        assert!(err.contains("bark.png") && err.contains("image file that exists"), "{err}");
    }

    fn plan(text: &str) -> Result<Plan> {
        parse_plan(text, Path::new("lib"))
    }

    #[test]
    fn a_good_manifest_becomes_a_plan() {
        let p = plan(
            "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = 3\n\
             [[exemplar]]\nname = \"k\"\nrecipe = \"sweep\"\nimage = \"kiwi.png\"\nlength = 16\naxis = \"x\"\n\
             depth_axis = \"z\"\nnoise = [1.0, 2.0]\nskin = \"#503010\"\ntype = \"2-b\"\n\
             [[exemplar.steps]]\nscatter = \"seed.obj\"\ncount = 5\nregion = \"depth:0.5,0.7\"\nscale = \"1..2\"\ncolor = \"0,0,0\"\n\
             [[exemplar.steps]]\nblur = \"4,4,4\"\nradius = 3\n",
        )
        .unwrap();
        assert_eq!(p.entries[0].dims, Some([8, 8, 8]));
        let k = &p.entries[1];
        assert_eq!(k.texture_type, Some(TextureType::T2b));
        let Source::Sweep(s) = &k.source else { panic!("a sweep") };
        assert_eq!(s.image, Path::new("lib/kiwi.png"));
        assert_eq!(s.depth_axis, Some(Axis::Z));
        assert!(matches!(k.steps[0], Step::Scatter { count: 5, region: Some(Region::Depth(_, _)), .. }));
        assert!(matches!(k.steps[1], Step::Blur { strength: 1.0, .. }));
    }

    #[test]
    fn each_mistake_names_its_field() {
        let cases = [
            ("name = \"a b\"\nrecipe = \"procedural:marble\"\nsize = 8", "name = \"a b\""),
            ("name = \"a\"\nrecipe = \"weave\"\nsize = 8", "recipe = \"weave\""),
            ("name = \"a\"\nrecipe = \"procedural:granite\"\nsize = 8", "granite"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = [8, 8]", "size = [8, 8]"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 0", "out of range"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"", "size is missing"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\ncolour = 1", "colour"),
            ("name = \"a\"\nrecipe = \"sweep\"\nlength = 4\naxis = \"x\"", "image is missing"),
            (
                "name = \"a\"\nrecipe = \"sweep\"\nimage = \"i.png\"\nlength = 4\naxis = \"w\"",
                "axis: unknown axis \"w\"",
            ),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\ntype = \"3\"", "type: unknown texture type"),
            (
                "name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n[[exemplar.steps]]\nradius = 2",
                "step 1: each step needs exactly one",
            ),
            (
                "name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n[[exemplar.steps]]\nstamp = \"s.obj\"\ncolor = \"#000000\"",
                "step 1: at is missing",
            ),
        ];
        for (body, expected) in cases {
            let err = plan(&format!("[[exemplar]]\n{body}\n")).unwrap_err().to_string();
            assert!(err.contains(expected), "{body}: {err}");
            assert!(err.contains("entry 1") || err.contains("invalid manifest"), "{err}");
        }
    }

    /// A field its recipe does not take is refused with the recipe's fields; the table
    /// lists every field the raw entry reads.
    #[test]
    fn a_field_the_recipe_does_not_take_is_named_with_the_ones_it_does() {
        let text = "[[exemplar]]\nname = \"s\"\nrecipe = \"procedural:marble\"\nsize = 8\nlength = 4\n";
        let err = parse_plan(text, Path::new(".")).unwrap_err().to_string();
        assert!(err.contains("length does not apply to recipe \"procedural:marble\"; its fields: size, seed"), "{err}");
        let keys: Vec<&str> = field_rules().iter().map(|r| r.key).collect();
        for key in ["size", "type", "image", "length", "axis", "noise", "levels", "volume", "masks", "exports"] {
            assert!(keys.contains(&key), "{key}");
        }
        assert!(fields_of("load").iter().any(|r| r.key == "volume" && r.required));
        assert!(!fields_of("sweep").iter().any(|r| r.key == "levels"));
        assert!(fields_of("sweep").iter().any(|r| r.key == "size" && !r.required), "a sweep's size is checked");
        assert!(!fields_of("load").iter().any(|r| r.key == "size"));
    }

    /// A value of the wrong kind reads in the user's words, not the reader's.
    #[test]
    fn wrong_kinds_of_value_are_said_plainly() {
        let base = "[[exemplar]]\nname = \"s\"\nrecipe = \"procedural:marble\"\n";
        for (field, says) in [
            ("size = 8\nseed = -5", "seed must be a whole number, 0 or more, got -5"),
            ("size = -5", "size must be one whole number or three, each 1 to 512"),
            ("size = \"big\"", "size must be one whole number or three"),
            ("size = 8\nmask_falloff = \"x\"", "must be a number, got string \"x\""),
        ] {
            let err = parse_plan(&format!("{base}{field}\n"), Path::new(".")).unwrap_err().to_string();
            let plain = says.split_once(' ').map_or(says, |(_, rest)| rest);
            assert!(err.contains(plain) && !err.contains("expected"), "{field}: {err}");
        }
    }
}
