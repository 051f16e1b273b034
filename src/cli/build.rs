//! `solidtex build`: make every exemplar a manifest lists, in parallel, each into
//! `DIR/NAME.exr` and a contact sheet `DIR/NAME.sheet.png`, skipping exemplars whose
//! recipe and inputs have not changed (a content-addressed cache), and write a report.

pub use super::recipe::make;

use super::recipe::extras;
use crate::error::{Error, Result};
use crate::io;
use crate::io::manifest::{self, Entry, MaskKind, SkinSource, Source, Step};
use crate::render;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// The arguments of `solidtex build`.
#[derive(Debug, clap::Args)]
pub struct BuildArgs {
    /// The manifest.
    #[arg(default_value = "exemplars/library.toml")]
    pub manifest: PathBuf,
    /// Output folder (created if missing).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Rebuild even what the cache says is up to date.
    #[arg(long)]
    pub force: bool,
    /// Build only these exemplars (repeatable).
    #[arg(long)]
    pub only: Vec<String>,
    /// Build only shard K of N (0 <= K < N): exemplars are assigned by a stable hash of
    /// their name, so N machines can share a library. `auto/N` takes K from
    /// JOB_COMPLETION_INDEX (Kubernetes Indexed Jobs) or SLURM_ARRAY_TASK_ID (Slurm arrays).
    #[arg(long)]
    pub shard: Option<String>,
    /// Merge the output folders of shard builds into the output folder, with one report.
    #[arg(long, num_args = 1..)]
    pub merge: Vec<PathBuf>,
    /// Print machine-readable progress lines (`progress<TAB>NAME<TAB>FRACTION<TAB>STAGE`)
    /// on stderr, for the terminal UI's gauges.
    #[arg(long, hide = true)]
    pub progress_lines: bool,
}

/// Parse `K/N` or `auto/N` (K from the scheduler's environment).
pub fn parse_shard(text: &str) -> Result<(u64, u64)> {
    let bad = || Error::invalid(format!("--shard {text:?} is not K/N with 0 <= K < N (or auto/N)"));
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let n: u64 = n.parse().map_err(|_| bad())?;
    let k: u64 = if k == "auto" {
        let from_env = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"].iter().find_map(|v| std::env::var(v).ok());
        let value = from_env.ok_or_else(|| {
            Error::invalid("--shard auto/N needs JOB_COMPLETION_INDEX or SLURM_ARRAY_TASK_ID in the environment")
        })?;
        value
            .trim()
            .parse()
            .map_err(|_| Error::invalid(format!("the shard index {value:?} from the environment is not a number")))?
    } else {
        k.parse().map_err(|_| bad())?
    };
    if n == 0 || k >= n {
        return Err(bad());
    }
    Ok((k, n))
}

/// The shard an exemplar belongs to among `n`: a stable hash of its name.
pub fn shard_of(name: &str, n: u64) -> u64 {
    let hash = blake3::hash(name.as_bytes());
    u64::from_le_bytes(hash.as_bytes()[..8].try_into().expect("8 bytes")) % n
}

/// What the cache remembers about a built exemplar (`DIR/.cache/NAME.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Exemplar name.
    pub name: String,
    /// Content hash of the recipe, its input files and the tool version.
    pub key: String,
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
}

/// One file a build wrote.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Written {
    /// Path relative to the output folder.
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
    /// blake3 of the content (hex, 32 characters).
    pub hash: String,
}

enum Outcome {
    Built(Record),
    Cached(Record),
    Failed(String, String),
}

/// Run `solidtex build`.
pub fn run(args: &BuildArgs) -> Result<()> {
    let plan = plan_for(args)?;
    if !args.merge.is_empty() {
        return merge(&plan.entries, &args.merge, &args.output);
    }
    let mut entries = select(&plan.entries, &args.only, &args.manifest)?;
    if let Some(text) = &args.shard {
        let (k, n) = parse_shard(text)?;
        entries.retain(|e| shard_of(&e.name, n) == k);
        eprintln!("shard {k} of {n}: {} exemplar(s)", entries.len());
    }
    let _lock = lock_output(&args.output)?;
    remove_stale_temporaries(&args.output);
    let folder = args.manifest.parent().unwrap_or(Path::new("."));
    let lines = Lines::new(entries.len());
    let budget = io::budget_from_env()?;
    let mut outcomes: Vec<Outcome> = Vec::new();
    for batch in batches(&entries, budget) {
        let done: Vec<Outcome> = batch.par_iter().map(|entry| build_one(entry, folder, args, &lines)).collect();
        outcomes.extend(done);
    }
    lines.finish();
    write_report(&args.output, &outcomes)?;
    summarize(&outcomes, &args.output)
}

/// Copy the outputs of shard builds into `output` and write the combined report.
fn merge(entries: &[Entry], folders: &[PathBuf], output: &Path) -> Result<()> {
    let _lock = lock_output(output)?;
    let mut outcomes = Vec::new();
    for entry in entries {
        let name = &entry.name;
        let found = folders.iter().find(|f| f.join(".cache").join(format!("{name}.json")).exists());
        let Some(folder) = found else {
            outcomes.push(Outcome::Failed(name.clone(), "built by none of the merged folders".to_string()));
            continue;
        };
        let mut files = outputs(entry);
        files.push(format!(".cache/{name}.json"));
        for file in files {
            copy(&folder.join(&file), &output.join(&file))?;
        }
        let record: Record =
            serde_json::from_slice(&io::atomic::read_bytes(&output.join(format!(".cache/{name}.json")))?)
                .map_err(|e| Error::file(folder.join(".cache"), format!("unreadable cache record: {e}")))?;
        outcomes.push(Outcome::Cached(record));
    }
    write_report(output, &outcomes)?;
    summarize(&outcomes, output)
}

/// Create the output folder and its cache, and hold the build lock on it (released when
/// the returned file closes): a second build on the same folder stops with a clear message
/// instead of removing the first one's temporaries.
fn lock_output(output: &Path) -> Result<std::fs::File> {
    let cache = output.join(".cache");
    std::fs::create_dir_all(&cache).map_err(|e| Error::io(output, e))?;
    let path = cache.join("build.lock");
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| Error::io(&path, e))?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(Error::file(
            output,
            "another solidtex build is writing into this folder (it holds .cache/build.lock); \
             wait for it to finish or build into another folder with -o",
        )),
        Err(std::fs::TryLockError::Error(e)) => Err(Error::io(&path, e)),
    }
}

/// Remove the temporaries an interrupted build left (names solidtex gives them:
/// `.NAME.solidtex-` + random letters + `.tmp`, files or folders). Only called under the
/// build lock.
fn remove_stale_temporaries(output: &Path) {
    for folder in [output.to_path_buf(), output.join(".cache")] {
        let Ok(entries) = std::fs::read_dir(&folder) else { continue };
        for path in entries.filter_map(|e| e.ok().map(|e| e.path())) {
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            if io::atomic::is_temporary_name(&name) {
                let _ = if path.is_dir() { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
            }
        }
    }
}

/// Copy a file, or a folder of files, atomically.
fn copy(from: &Path, to: &Path) -> Result<()> {
    if from.is_dir() {
        let entries: Vec<PathBuf> =
            std::fs::read_dir(from).map_err(|e| Error::io(from, e))?.filter_map(|e| e.ok().map(|e| e.path())).collect();
        return io::write_folder(to, |dir| {
            entries.iter().try_for_each(|f| copy(f, &dir.join(f.file_name().unwrap_or_default())))
        });
    }
    io::write_bytes(to, &io::atomic::read_bytes(from)?)
}

/// The manifest's plan. A whole build needs every entry valid; with `--only`, only the named
/// entries must be (a mistake in another entry does not stop them: the terminal UI builds
/// the valid entries of a manifest that still has broken ones). A named entry that is broken
/// fails with its own error.
fn plan_for(args: &BuildArgs) -> Result<manifest::Plan> {
    if args.only.is_empty() || !args.merge.is_empty() {
        return manifest::read_plan(&args.manifest);
    }
    let text = io::read_text(&args.manifest, "manifest")?;
    let folder = args.manifest.parent().unwrap_or(Path::new("."));
    let (entries, _) = manifest::parse_plan_lenient(&text, folder);
    for name in args.only.iter().filter(|n| !entries.iter().any(|e| &e.name == *n)) {
        // Named but not valid: its own error (or, for a name no entry has, the list below).
        if let Err(e) = manifest::parse_entry(&text, folder, name)
            && !e.to_string().starts_with("no exemplar named")
        {
            return Err(e.in_file(&args.manifest));
        }
    }
    Ok(manifest::Plan { entries })
}

fn select<'a>(entries: &'a [Entry], only: &[String], manifest: &Path) -> Result<Vec<&'a Entry>> {
    if let Some(unknown) = only.iter().find(|n| !entries.iter().any(|e| &e.name == *n)) {
        let names: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
        return Err(Error::file(
            manifest,
            format!("--only {unknown:?} is not in the manifest; it has {}", names.join(", ")),
        ));
    }
    Ok(entries.iter().filter(|e| only.is_empty() || only.contains(&e.name)).collect())
}

/// Bytes an exemplar's build may hold at once: its volume several times over (synthesis
/// keeps matches and two grids per level).
fn estimate(entry: &Entry) -> u64 {
    let dims = entry.dims.unwrap_or([64; 3]);
    let voxels = dims.iter().map(|d| *d as u64).product::<u64>();
    let factor = if matches!(entry.source, Source::Synth(_)) { 48 } else { 16 };
    voxels * 4 * factor
}

/// Consecutive groups of entries whose estimates together fit the budget (one entry alone
/// always forms a group); groups run one after another, entries in a group in parallel.
fn batches<'a>(entries: &[&'a Entry], budget: u64) -> Vec<Vec<&'a Entry>> {
    let mut out: Vec<Vec<&Entry>> = Vec::new();
    let mut used = 0;
    for &e in entries {
        let need = estimate(e);
        match out.last_mut() {
            Some(last) if used + need <= budget => {
                last.push(e);
                used += need;
            }
            _ => {
                out.push(vec![e]);
                used = need;
            }
        }
    }
    out
}

/// Progress: a bar above the result lines on a terminal, plain lines otherwise.
/// Progress of one exemplar as `progress` lines on stderr (at most one per percent).
/// With `--progress-lines`, each finished pyramid level is also written as a small volume
/// (`DIR/.cache/NAME.preview.exr`) and announced as `preview<TAB>NAME<TAB>PATH`.
struct LineProgress<'a> {
    name: &'a str,
    enabled: bool,
    last: Mutex<i32>,
    preview: PathBuf,
}

impl crate::progress::Progress for LineProgress<'_> {
    fn update(&self, stage: &str, fraction: f32) {
        let percent = (fraction.clamp(0.0, 1.0) * 100.0) as i32;
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        if self.enabled && percent != *last {
            *last = percent;
            eprintln!("progress\t{}\t{fraction:.3}\t{stage}", self.name);
        }
    }

    fn warn(&self, message: &str) {
        eprintln!("warning: {}: {message}", self.name);
    }

    fn level_done(&self, level: usize, levels: usize, dims: [usize; 3], channels: usize, data: &[f32]) {
        if !self.enabled {
            return;
        }
        let roles = if channels >= 3 { crate::Channel::rgb() } else { crate::Channel::grey() };
        let keep = roles.len();
        let samples: Vec<f32> = data.chunks_exact(channels).flat_map(|v| v[..keep].iter().copied()).collect();
        let written = crate::Volume::from_data(dims, roles, samples).and_then(|v| io::write_volume(&self.preview, &v));
        if written.is_ok() {
            eprintln!("preview\t{}\t{}\t{level}/{levels}", self.name, self.preview.display());
        }
    }
}

struct Lines {
    bar: Option<indicatif::ProgressBar>,
}

impl Lines {
    fn new(total: usize) -> Lines {
        use std::io::IsTerminal;
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(total as u64);
            let style = indicatif::ProgressStyle::with_template("{elapsed:>4} [{bar:30}] {pos}/{len} exemplars");
            bar.set_style(style.expect("valid template"));
            bar
        });
        Lines { bar }
    }

    fn line(&self, text: String) {
        match &self.bar {
            Some(bar) => {
                bar.println(text);
                bar.inc(1);
            }
            None => eprintln!("{text}"),
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Build one entry; an error or a panic fails this entry only.
fn build_one(entry: &Entry, folder: &Path, args: &BuildArgs, lines: &Lines) -> Outcome {
    let result = caught(|| build_entry(entry, folder, args));
    let outcome = result.unwrap_or_else(|e: Error| Outcome::Failed(entry.name.clone(), super::clip(&e.to_string())));
    lines.line(match &outcome {
        Outcome::Built(r) => {
            let [x, y, z] = r.dims;
            format!("built  {} {x}x{y}x{z} in {:.2} s", r.name, r.seconds)
        }
        Outcome::Cached(r) => format!("cached {} (recipe and inputs unchanged)", r.name),
        Outcome::Failed(name, why) => format!("FAILED {name}: {why}"),
    });
    outcome
}

/// Run `work`, turning a panic into an error that says what it was.
fn caught<T>(work: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".to_string());
        Err(Error::invalid(format!("internal error (please report it): {what}")))
    })
}

fn build_entry(entry: &Entry, folder: &Path, args: &BuildArgs) -> Result<Outcome> {
    let (output, force) = (args.output.as_path(), args.force);
    let started = Instant::now();
    {
        let key = cache_key(entry, folder)?;
        let record_path = output.join(".cache").join(format!("{}.json", entry.name));
        if !force && let Some(record) = cached(&record_path, &key, output, entry) {
            return Ok(Outcome::Cached(record));
        }
        let preview = output.join(".cache").join(format!("{}.preview.exr", entry.name));
        let progress = LineProgress { name: &entry.name, enabled: args.progress_lines, last: Mutex::new(-1), preview };
        let volume = super::recipe::make_with(entry, &progress)?;
        io::write_volume(&output.join(format!("{}.exr", entry.name)), &volume)?;
        io::write_rgb8(&output.join(format!("{}.sheet.png", entry.name)), &render::sheet(&volume, &entry.name))?;
        extras(entry, &volume, output)?;
        let classified =
            crate::classify::classify(&volume).map(|c| c.texture_type.to_string()).unwrap_or_else(|_| "-".into());
        let record = Record {
            name: entry.name.clone(),
            key,
            dims: volume.dims(),
            declared: volume.meta.texture_type.map(|t| t.to_string()),
            classified,
            seconds: started.elapsed().as_secs_f64(),
            files: written(output, entry)?,
        };
        let json = serde_json::to_string_pretty(&record).expect("a record always serializes");
        io::write_bytes(&record_path, json.as_bytes())?;
        Ok(Outcome::Built(record))
    }
}

/// The record of an up-to-date build: the key matches and every output the build wrote is
/// still there with its recorded size and hash (a truncated or edited output rebuilds).
fn cached(record_path: &Path, key: &str, output: &Path, entry: &Entry) -> Option<Record> {
    let record: Record = serde_json::from_slice(&io::atomic::read_bytes(record_path).ok()?).ok()?;
    if record.key != key || record.files.is_empty() {
        return None;
    }
    let now = written(output, entry).ok()?;
    (now == record.files).then_some(record)
}

/// Size and hash of every file an entry's outputs hold now, in a fixed order.
fn written(output: &Path, entry: &Entry) -> Result<Vec<Written>> {
    let mut files = Vec::new();
    for name in outputs(entry) {
        let path = output.join(&name);
        if path.is_dir() {
            let mut inner: Vec<String> = std::fs::read_dir(&path)
                .map_err(|e| Error::io(&path, e))?
                .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
                .collect();
            inner.sort();
            files.extend(inner.into_iter().map(|f| format!("{name}/{f}")));
        } else {
            files.push(name);
        }
    }
    files
        .into_iter()
        .map(|name| {
            let bytes = io::atomic::read_bytes(&output.join(&name))?;
            let hash = blake3::hash(&bytes).to_hex()[..32].to_string();
            Ok(Written { path: name, bytes: bytes.len() as u64, hash })
        })
        .collect()
}

/// The files and folders an entry's build writes (relative to the output folder).
fn outputs(entry: &Entry) -> Vec<String> {
    let name = &entry.name;
    let mut files = vec![format!("{name}.exr"), format!("{name}.sheet.png")];
    files.extend(
        entry.exports.iter().map(|e| if e == "slices" { format!("{name}_slices") } else { format!("{name}.{e}") }),
    );
    for kind in &entry.masks {
        files.push(match kind {
            MaskKind::Splotch => format!("{name}.mask.exr"),
            MaskKind::Layered => format!("{name}.masks"),
        });
    }
    files
}

/// blake3 of the tool version, the recipe (paths relative to the manifest) and every input file.
fn cache_key(entry: &Entry, folder: &Path) -> Result<String> {
    let mut hasher = blake3::Hasher::new();
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    let recipe = format!("{entry:?}").replace(&folder.display().to_string(), "");
    hasher.update(recipe.as_bytes());
    for input in inputs(entry) {
        hasher.update(&io::atomic::read_bytes(&input)?);
    }
    Ok(hasher.finalize().to_hex()[..32].to_string())
}

/// The files an entry reads.
fn inputs(entry: &Entry) -> Vec<PathBuf> {
    let mut files = Vec::new();
    match &entry.source {
        Source::Sweep(spec) => {
            files.push(spec.image.clone());
            if let Some((SkinSource::Image(p), _, _)) = &spec.skin {
                files.push(p.clone());
            }
        }
        Source::Synth(spec) => {
            files.push(spec.image.clone());
            files.extend([&spec.ey, &spec.ez, &spec.depth].into_iter().flatten().cloned());
        }
        Source::Load(path) => files.push(path.clone()),
        Source::Procedural(_) => {}
    }
    for step in &entry.steps {
        match step {
            Step::Stamp { mesh, .. } | Step::Scatter { mesh, .. } => files.push(mesh.clone()),
            Step::Blur { .. } => {}
        }
    }
    files
}

fn summarize(outcomes: &[Outcome], output: &Path) -> Result<()> {
    let count = |f: fn(&Outcome) -> bool| outcomes.iter().filter(|o| f(o)).count();
    let built = count(|o| matches!(o, Outcome::Built(_)));
    let cached = count(|o| matches!(o, Outcome::Cached(_)));
    let failed: Vec<&str> =
        outcomes.iter().filter_map(|o| if let Outcome::Failed(n, _) = o { Some(n.as_str()) } else { None }).collect();
    eprintln!(
        "{built} built, {cached} cached, {} failed; report: {}",
        failed.len(),
        output.join("report.html").display()
    );
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Error::invalid(format!("{} exemplar(s) failed: {} (see the lines above)", failed.len(), failed.join(", "))))
    }
}

/// `report.md` and `report.html`: one row per exemplar with its sheet.
fn write_report(output: &Path, outcomes: &[Outcome]) -> Result<()> {
    let mut md = String::from(
        "# Exemplar library\n\n| exemplar | size | declared | classified | build | sheet |\n|---|---|---|---|---|---|\n",
    );
    let mut html = String::from(
        "<!doctype html><meta charset=utf-8><title>Exemplar library</title>\
         <style>body{font-family:sans-serif;background:#222;color:#eee}td,th{padding:4px 10px}img{width:280px}</style>\
         <h1>Exemplar library</h1><table><tr><th>exemplar<th>size<th>declared<th>classified<th>build<th>sheet\n",
    );
    for o in outcomes {
        let (name, size, declared, classified, build) = match o {
            Outcome::Built(r) | Outcome::Cached(r) => {
                let when = if matches!(o, Outcome::Built(_)) { format!("{:.2} s", r.seconds) } else { "cached".into() };
                let [x, y, z] = r.dims;
                (
                    r.name.as_str(),
                    format!("{x}x{y}x{z}"),
                    r.declared.clone().unwrap_or("-".into()),
                    r.classified.clone(),
                    when,
                )
            }
            Outcome::Failed(n, why) => (n.as_str(), "-".into(), "-".into(), "-".into(), format!("failed: {why}")),
        };
        md += &format!("| {name} | {size} | {declared} | {classified} | {build} | ![{name}]({name}.sheet.png) |\n");
        html += &format!(
            "<tr><td>{name}<td>{size}<td>{declared}<td>{classified}<td>{}<td><img src=\"{name}.sheet.png\" alt=\"{name}\">\n",
            build.replace('<', "&lt;")
        );
    }
    html += "</table>\n";
    io::write_bytes(&output.join("report.md"), md.as_bytes())?;
    io::write_bytes(&output.join("report.html"), html.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::manifest::parse_plan;

    #[test]
    fn batches_keep_each_group_within_the_budget() {
        let text = (0..5)
            .map(|i| format!("[[exemplar]]\nname = \"e{i}\"\nrecipe = \"procedural:marble\"\nsize = 16\n"))
            .collect::<String>();
        let plan = parse_plan(&text, Path::new(".")).unwrap();
        let entries: Vec<&Entry> = plan.entries.iter().collect();
        let one = estimate(entries[0]);
        let groups = batches(&entries, 2 * one);
        assert_eq!(groups.iter().map(Vec::len).collect::<Vec<_>>(), [2, 2, 1]);
        assert_eq!(batches(&entries, 1).len(), 5, "an entry over the budget still builds, alone");
        assert_eq!(batches(&entries, u64::MAX).len(), 1);
    }

    #[test]
    fn a_panic_in_one_entry_becomes_its_error() {
        let err = caught(|| -> Result<()> { panic!("octaves out of hand") }).unwrap_err().to_string();
        assert!(err.contains("internal error") && err.contains("octaves out of hand"), "{err}");
        assert_eq!(caught(|| Ok(7)).unwrap(), 7);
    }

    #[test]
    fn shards_split_names_stably() {
        let names = ["kiwi", "carrot", "trunk", "marble", "wood", "strata"];
        let first: Vec<u64> = names.iter().map(|n| shard_of(n, 3)).collect();
        assert_eq!(first, names.iter().map(|n| shard_of(n, 3)).collect::<Vec<_>>());
        assert!(first.iter().all(|k| *k < 3));
        assert_eq!(parse_shard("2/5").unwrap(), (2, 5));
        assert!(parse_shard("5/5").is_err() && parse_shard("x").is_err() && parse_shard("1/0").is_err());
    }
}
