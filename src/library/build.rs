//! Building a library: make the chosen entries in parallel within the memory budget, each
//! into `DIR/NAME.exr`, a contact sheet and its masks and exports, skip the ones the cache
//! says are up to date, and write a report. Both front ends call [`build`] in-process; what
//! happens is told to an [`Observer`], which may also cancel.

use super::cache::{self, Freshness, Record};
use super::{files, recipe};
use crate::error::{Error, Result};
use crate::io;
use crate::io::ledger::Ledger;
use crate::io::manifest::{self, Entry, Source};
use crate::progress::Progress;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// What to build, and where.
#[derive(Debug, Clone)]
pub struct Request {
    /// The manifest.
    pub manifest: PathBuf,
    /// Output folder (created if missing).
    pub output: PathBuf,
    /// Rebuild even what the cache says is up to date.
    pub force: bool,
    /// Build only these entries (empty: all).
    pub only: Vec<String>,
    /// Build only shard K of N.
    pub shard: Option<(u64, u64)>,
}

/// How one entry's build ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Made and written.
    Built(Record),
    /// Up to date: nothing was written.
    Cached(Record),
    /// Failed with this message; its previous output (if any) is kept.
    Failed(String, String),
    /// Stopped before it finished; its previous output (if any) is kept.
    Cancelled(String),
}

impl Outcome {
    /// The entry's name.
    pub fn name(&self) -> &str {
        match self {
            Outcome::Built(r) | Outcome::Cached(r) => &r.name,
            Outcome::Failed(n, _) | Outcome::Cancelled(n) => n,
        }
    }
}

/// Hears what a build does. Every method has a default that ignores it; called from the
/// build's worker threads.
pub trait Observer: Sync {
    /// Progress of entry `name`: `stage` and a fraction in [0, 1].
    fn progress(&self, _name: &str, _stage: &str, _fraction: f32) {}
    /// A warning about entry `name` that does not stop it.
    fn warn(&self, _name: &str, _message: &str) {}
    /// A pyramid level of entry `name`'s synthesis finished (see [`Progress::level_done`]).
    fn level_done(
        &self,
        _name: &str,
        _level: usize,
        _levels: usize,
        _dims: [usize; 3],
        _channels: usize,
        _data: &[f32],
    ) {
    }
    /// An entry finished (built, cached, failed or cancelled).
    fn finished(&self, _outcome: &Outcome) {}
    /// Return true to stop: running entries stop at their next check, the others do not start.
    fn cancelled(&self) -> bool {
        false
    }
}

/// An observer that hears nothing.
pub struct Quiet;

impl Observer for Quiet {}

/// The entries a request builds: all of the manifest's, or the named ones (then only they
/// must be valid: a mistake in another entry does not stop them), or one shard's.
pub fn select(request: &Request) -> Result<Vec<Entry>> {
    let folder = manifest_folder(&request.manifest);
    let entries = if request.only.is_empty() {
        manifest::read_plan(&request.manifest)?.entries
    } else {
        let text = io::read_text(&request.manifest, "manifest")?;
        let (valid, _) = manifest::parse_plan_lenient(&text, folder);
        let mut chosen = Vec::new();
        for (k, name) in request.only.iter().enumerate() {
            if request.only[..k].contains(name) {
                continue;
            }
            match valid.iter().find(|e| &e.name == name) {
                Some(entry) => {
                    let lines = manifest::Lines { manifest: Some(request.manifest.clone()), ..entry.lines.clone() };
                    chosen.push(manifest::Entry { lines, ..entry.clone() });
                }
                None => return Err(unknown_or_broken(&text, folder, name, &valid, &request.manifest)),
            }
        }
        chosen
    };
    Ok(match request.shard {
        Some((k, n)) => entries.into_iter().filter(|e| shard_of(&e.name, n) == k).collect(),
        None => entries,
    })
}

/// The error for `--only NAME` when no valid entry has that name: the entry's own mistake,
/// or the list of names there are.
fn unknown_or_broken(text: &str, folder: &Path, name: &str, valid: &[Entry], file: &Path) -> Error {
    if let Err(e) = manifest::parse_entry(text, folder, name)
        && !e.to_string().starts_with("no exemplar named")
    {
        return e.in_file(file);
    }
    let names: Vec<&str> = valid.iter().map(|e| e.name.as_str()).collect();
    Error::file(file, format!("--only {name:?} is not in the manifest; it has {}", names.join(", ")))
}

/// The folder a manifest's relative paths start from.
pub fn manifest_folder(manifest: &Path) -> &Path {
    manifest.parent().unwrap_or(Path::new("."))
}

/// Build `entries` of `request`'s manifest into its output folder, holding the folder's
/// build lock; one entry's failure (or panic) never takes the others down. Writes the
/// report and returns one outcome per entry, in order.
pub fn build(request: &Request, entries: &[Entry], observer: &dyn Observer) -> Result<Vec<Outcome>> {
    not_the_current_folder(&request.output)?;
    not_inside_an_input(&request.output, entries)?;
    let lock = lock_output(&request.output)?;
    build_holding(request, entries, observer, lock, Reports::Required)
}

/// Whether a build must write its reports, or (for a command that only needs the
/// exemplars) may leave them when the folder's report files are not solidtex's.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Reports {
    Required,
    IfOurs,
}

/// How long [`build_when_free`] waits for another build of the same folder.
pub const LOCK_WAIT: Duration = Duration::from_secs(600);

/// [`build`], but when another build holds the folder's lock, wait up to `wait` for it
/// (calling `waiting` once, when the wait starts) instead of stopping: for a command that
/// needs the exemplars built, not a build of its own.
pub fn build_when_free(
    request: &Request,
    entries: &[Entry],
    observer: &dyn Observer,
    (wait, waiting): (Duration, &dyn Fn()),
) -> Result<Vec<Outcome>> {
    not_the_current_folder(&request.output)?;
    not_inside_an_input(&request.output, entries)?;
    let lock = lock_waiting(&request.output, wait, waiting)?;
    build_holding(request, entries, observer, lock, Reports::IfOurs)
}

fn build_holding(
    request: &Request,
    entries: &[Entry],
    observer: &dyn Observer,
    _lock: std::fs::File,
    reports: Reports,
) -> Result<Vec<Outcome>> {
    let output = request.output.as_path();
    remove_stale_temporaries(output);
    let ledger = open_ledger(output)?;
    let report = match ledger.claim(&REPORTS.map(String::from)) {
        Ok(()) => true,
        Err(_) if reports == Reports::IfOurs => {
            let folder = output.display().to_string();
            observer.warn(
                &folder,
                "holds a report.md or report.html solidtex did not write: left as it is, no build report written",
            );
            false
        }
        Err(e) => return Err(e),
    };
    let folder = manifest_folder(&request.manifest);
    let budget = io::budget_from_env()?;
    let refs: Vec<&Entry> = entries.iter().collect();
    let mut outcomes: Vec<Outcome> = Vec::new();
    for batch in batches(&refs, budget) {
        let done: Vec<Outcome> = batch
            .par_iter()
            .map(|entry| {
                let outcome = match reads_no_output(entry, output) {
                    Ok(()) => build_one(entry, folder, (output, &ledger), request.force, observer),
                    Err(e) => Outcome::Failed(entry.name.clone(), e.to_string()),
                };
                observer.finished(&outcome);
                outcome
            })
            .collect();
        outcomes.extend(done);
    }
    if report {
        write_report(output, &ledger, &report_rows(request, &outcomes))?;
    }
    Ok(outcomes)
}

/// One row of the library report.
enum Row<'a> {
    /// How this build ended for the entry.
    Now(&'a Outcome),
    /// This build failed or was cancelled, and the last good build's files are kept.
    Kept(&'a Outcome, Box<Record>),
    /// Not asked this time: its last build's record.
    Earlier(Box<Record>),
    /// Not asked this time and never built.
    NotBuilt(String),
}

/// The report's rows: every valid entry of the manifest in order, this build's outcome for
/// those it built, the last build's record for the others (a build of one entry keeps the
/// other rows).
fn report_rows<'a>(request: &Request, outcomes: &'a [Outcome]) -> Vec<Row<'a>> {
    let text = io::read_text(&request.manifest, "manifest").unwrap_or_default();
    let (entries, _) = manifest::parse_plan_lenient(&text, manifest_folder(&request.manifest));
    let mut rows: Vec<Row> = entries
        .iter()
        .map(|e| match outcomes.iter().find(|o| o.name() == e.name) {
            Some(o @ (Outcome::Failed(..) | Outcome::Cancelled(_))) => match kept_record(request, &e.name) {
                Some(record) => Row::Kept(o, Box::new(record)),
                None => Row::Now(o),
            },
            Some(o) => Row::Now(o),
            None => match cache::read_record(&request.output, &e.name) {
                Some(record) => Row::Earlier(Box::new(record)),
                None => Row::NotBuilt(e.name.clone()),
            },
        })
        .collect();
    let listed = |o: &Outcome| entries.iter().any(|e| e.name == o.name());
    rows.extend(outcomes.iter().filter(|o| !listed(o)).map(Row::Now));
    rows
}

/// The record of entry `name`'s last good build when its volume is still in the output
/// folder (kept when a later build failed or was cancelled).
fn kept_record(request: &Request, name: &str) -> Option<Record> {
    let record = cache::read_record(&request.output, name)?;
    files::volume(&request.output, name).is_file().then_some(record)
}

/// The reports a build writes into its output folder.
const REPORTS: [&str; 2] = ["report.md", "report.html"];

/// The output folder's ledger of written files; a folder built before the ledger existed
/// starts from its cache records and its reports.
pub(crate) fn open_ledger(output: &Path) -> Result<Ledger> {
    Ledger::open(output, || {
        let records = std::fs::read_dir(output.join(files::CACHE)).into_iter().flatten().filter_map(|e| {
            let name = e.ok()?.file_name().to_string_lossy().strip_suffix(".json")?.to_string();
            cache::read_record(output, &name)
        });
        let mut seeds: Vec<(String, String)> =
            records.flat_map(|r| r.files.into_iter().map(|f| (f.path, f.hash))).collect();
        for (name, start) in REPORTS.iter().zip(REPORT_STARTS) {
            let text = io::atomic::read_bytes_within(&output.join(name), io::atomic::TEXT_CAP).unwrap_or_default();
            if let Some(hash) = text.starts_with(start.as_bytes()).then(|| blake3::hash(&text).to_hex().to_string()) {
                seeds.push((name.to_string(), hash));
            }
        }
        seeds
    })
}

/// How each report begins (for folders built before the ledger).
const REPORT_STARTS: [&str; 2] =
    ["# Exemplar library\n\n| exemplar | size |", "<!doctype html><meta charset=utf-8><title>Exemplar library</title>"];

/// Build one entry; an error or a panic fails this entry only.
fn build_one(entry: &Entry, folder: &Path, output: (&Path, &Ledger), force: bool, observer: &dyn Observer) -> Outcome {
    if observer.cancelled() {
        return Outcome::Cancelled(entry.name.clone());
    }
    match caught(|| build_entry(entry, folder, output, force, observer)) {
        Ok(outcome) => outcome,
        Err(Error::Cancelled) => Outcome::Cancelled(entry.name.clone()),
        Err(e) => Outcome::Failed(entry.name.clone(), e.to_string()),
    }
}

/// Refuse an entry that reads a file it writes itself (or one inside a folder it writes): the
/// build would replace what it reads, and the entry would change on every build. (An entry
/// may read another entry's volume: its key follows that file, so it is rebuilt when the
/// other changes.)
fn reads_no_output(entry: &Entry, output: &Path) -> Result<()> {
    let written: Vec<PathBuf> = files::outputs(entry).into_iter().map(|f| output.join(f)).collect();
    for (field, input) in cache::input_files(entry) {
        let inside = |out: &PathBuf| input.parent().is_some_and(|folder| io::guard::same_file(folder, out));
        if let Some(out) = written.iter().find(|out| io::guard::same_file(&input, out) || inside(out)) {
            return Err(Error::invalid(format!(
                "{field} = {:?} is {} this entry writes ({}); solidtex never writes over its own inputs: read a copy \
                 kept outside the output folder",
                input.display().to_string(),
                if inside(out) { "inside a folder" } else { "a file" },
                out.display()
            )));
        }
    }
    Ok(())
}

/// Refuse an output folder that is, or lies inside, a folder an entry reads (a stack of
/// slices): the build's reports and cache would land among the slices.
fn not_inside_an_input(output: &Path, entries: &[Entry]) -> Result<()> {
    for entry in entries {
        for (field, input) in cache::input_files(entry).into_iter().filter(|(_, input)| input.is_dir()) {
            if io::guard::same_file(output, &input) || io::guard::inside_folder(output, &input) {
                return Err(Error::usage(format!(
                    "-o {}: is inside the folder {field} = {:?} of exemplar {}, an input of this build; solidtex \
                     never writes into its own inputs (build into another folder)",
                    output.display(),
                    input.display().to_string(),
                    entry.name
                )));
            }
        }
    }
    Ok(())
}

/// Run `work`, turning a panic into an error that says what it was.
pub fn caught<T>(work: impl FnOnce() -> Result<T>) -> Result<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".to_string());
        Err(Error::invalid(format!("internal error (please report it): {what}")))
    })
}

/// One entry's progress, passed to its recipe; it keeps the warnings for the record.
struct EntryProgress<'a> {
    name: &'a str,
    observer: &'a dyn Observer,
    warnings: std::sync::Mutex<Vec<String>>,
}

impl Progress for EntryProgress<'_> {
    fn update(&self, stage: &str, fraction: f32) {
        self.observer.progress(self.name, stage, fraction);
    }

    fn cancelled(&self) -> bool {
        self.observer.cancelled()
    }

    fn warn(&self, message: &str) {
        self.warnings.lock().unwrap_or_else(|e| e.into_inner()).push(message.to_string());
        self.observer.warn(self.name, message);
    }

    fn level_done(&self, level: usize, levels: usize, dims: [usize; 3], channels: usize, data: &[f32]) {
        self.observer.level_done(self.name, level, levels, dims, channels, data);
    }
}

/// Make and write one entry, unless it is up to date. Nothing is written until its volume
/// is made, so a cancelled or failed entry keeps its previous output; a file in the way
/// that solidtex did not write fails the entry before any work.
fn build_entry(
    entry: &Entry,
    folder: &Path,
    (output, ledger): (&Path, &Ledger),
    force: bool,
    observer: &dyn Observer,
) -> Result<Outcome> {
    let started = Instant::now();
    let key = cache::key(entry, folder)?;
    if !force && let Freshness::UpToDate(record) = cache::freshness_against(entry, &key, output) {
        return Ok(Outcome::Cached(record));
    }
    // Tests of the front ends name an entry here to see a build panic and be caught.
    if std::env::var_os("SOLIDTEX_TEST_PANIC").is_some_and(|n| n == entry.name.as_str()) {
        panic!("SOLIDTEX_TEST_PANIC names {}", entry.name);
    }
    let outputs = files::outputs(entry);
    ledger.claim(&outputs)?;
    let progress = EntryProgress { name: &entry.name, observer, warnings: Default::default() };
    let made = make_and_write(entry, output, &progress);
    // what is there now is solidtex's either way: the new files, or the earlier build's
    // where this one stopped first (a claim left pending would let a later run replace a
    // file a person changed in between)
    ledger.record(&outputs)?;
    let volume = made?;
    let classified =
        crate::classify::classify(&volume).map(|c| c.texture_type.to_string()).unwrap_or_else(|_| "-".into());
    let record = Record {
        name: entry.name.clone(),
        key: key.key,
        recipe: key.recipe,
        inputs: key.inputs,
        dims: volume.dims(),
        declared: volume.meta.texture_type.map(|t| t.to_string()),
        classified,
        seconds: started.elapsed().as_secs_f64(),
        files: cache::written(output, entry)?,
        quality: recipe::glance(entry, &volume),
        warnings: progress.warnings.into_inner().unwrap_or_else(|e| e.into_inner()),
    };
    cache::write_record(output, &record)?;
    Ok(Outcome::Built(record))
}

/// Make entry `entry`'s volume and write its files into `output` (unless cancelled first).
fn make_and_write(entry: &Entry, output: &Path, progress: &EntryProgress) -> Result<crate::volume::Volume> {
    let volume = recipe::make_with(entry, progress)?;
    // everything that can fail is made before the first file is written: a failed entry
    // leaves its earlier build as it was
    let masks = recipe::masks(entry, &volume)?;
    let page = io::web::preview_page(&entry.name, &volume)?;
    if progress.cancelled() {
        return Err(Error::Cancelled);
    }
    io::write_volume(&files::volume(output, &entry.name), &volume)?;
    io::write_rgb8(&output.join(files::sheet(&entry.name)), &crate::render::sheet(&volume, &entry.name))?;
    io::write_bytes(&output.join(files::view(&entry.name)), page.as_bytes())?;
    recipe::write_extras(entry, &volume, &masks, output)?;
    Ok(volume)
}

/// Copy the outputs of shard builds (`folders`) into `request`'s output folder and write
/// the combined report.
pub fn merge(request: &Request, folders: &[PathBuf]) -> Result<Vec<Outcome>> {
    let entries = manifest::read_plan(&request.manifest)?.entries;
    let output = request.output.as_path();
    not_the_current_folder(output)?;
    not_inside_an_input(output, &entries)?;
    let _lock = lock_output(output)?;
    let ledger = open_ledger(output)?;
    ledger.claim(&REPORTS.map(String::from))?;
    let manifest_folder = manifest_folder(&request.manifest);
    let mut outcomes = Vec::new();
    for entry in &entries {
        let name = &entry.name;
        let folder = match merged_from(entry, manifest_folder, folders) {
            Ok(folder) => folder,
            Err(why) => {
                outcomes.push(Outcome::Failed(name.clone(), why));
                continue;
            }
        };
        let mut names = files::outputs(entry);
        ledger.claim(&names)?;
        names.push(files::record(name));
        for file in &names {
            copy(&folder.join(file), &output.join(file))?;
        }
        ledger.record(&names)?;
        let record = cache::read_record(output, name)
            .ok_or_else(|| Error::file(output.join(files::record(name)), "unreadable cache record"))?;
        outcomes.push(Outcome::Cached(record));
    }
    write_report(output, &ledger, &outcomes.iter().map(Row::Now).collect::<Vec<_>>())?;
    Ok(outcomes)
}

/// The first of `folders` holding `entry`'s build up to date with the manifest (its recipe,
/// inputs and solidtex version) with every output file as recorded, or why none does (an
/// older build, a file changed or missing, an input that cannot be read here): merged, a
/// stale copy would pass for fresh.
fn merged_from<'a>(
    entry: &Entry,
    manifest_folder: &Path,
    folders: &'a [PathBuf],
) -> std::result::Result<&'a PathBuf, String> {
    let key = cache::key(entry, manifest_folder)
        .map_err(|e| format!("its inputs cannot be read to check the merged builds against: {e}"))?;
    let mut stale = None;
    for folder in folders {
        match cache::freshness_against(entry, &key, folder) {
            Freshness::UpToDate(_) => return Ok(folder),
            Freshness::Stale(_, why) => {
                stale.get_or_insert_with(|| {
                    format!("the build in {} is out of date ({why}): build it again", folder.display())
                });
            }
            Freshness::NotBuilt => {}
        }
    }
    Err(stale.unwrap_or_else(|| "built by none of the merged folders".to_string()))
}

/// The shard an exemplar belongs to among `n`: a stable hash of its name.
pub fn shard_of(name: &str, n: u64) -> u64 {
    let hash = blake3::hash(name.as_bytes());
    u64::from_le_bytes(hash.as_bytes()[..8].try_into().expect("8 bytes")) % n
}

/// A build writes into a folder of its own, never the current folder or one above it (where
/// a person's files are).
fn not_the_current_folder(output: &Path) -> Result<()> {
    if io::atomic::holds_current_folder(output) {
        return Err(Error::file(
            output,
            "is the current folder (or holds it); build into a folder of its own, e.g. -o out",
        ));
    }
    if std::fs::symlink_metadata(output).is_ok_and(|m| m.is_file()) {
        return Err(Error::file(output, "is a file, not a folder; build writes a library into a folder, e.g. -o out"));
    }
    Ok(())
}

/// Create the output folder and its cache, and hold the build lock on it (released when
/// the returned file closes): a second build on the same folder stops with a clear message
/// instead of removing the first one's temporaries.
fn lock_output(output: &Path) -> Result<std::fs::File> {
    try_lock_output(output)?.ok_or_else(|| {
        Error::file(
            output,
            "another solidtex build is writing into this folder (it holds .cache/build.lock); \
             wait for it to finish or build into another folder with -o",
        )
    })
}

/// Hold the build lock on `output`, waiting up to `wait` while another build holds it
/// (polling twice a second); `waiting` is called once when the wait starts.
fn lock_waiting(output: &Path, wait: Duration, waiting: &dyn Fn()) -> Result<std::fs::File> {
    let started = Instant::now();
    let mut told = false;
    loop {
        if let Some(file) = try_lock_output(output)? {
            return Ok(file);
        }
        if started.elapsed() >= wait {
            return Err(Error::file(
                output,
                format!(
                    "another solidtex build has been writing into this folder for over {} s (it holds \
                     .cache/build.lock); run this again once it has finished",
                    wait.as_secs()
                ),
            ));
        }
        if !told {
            waiting();
            told = true;
        }
        std::thread::sleep(Duration::from_millis(500).min(wait));
    }
}

/// The build lock on `output`, or `None` while another build holds it.
fn try_lock_output(output: &Path) -> Result<Option<std::fs::File>> {
    let cache = output.join(files::CACHE);
    std::fs::create_dir_all(output).map_err(|e| Error::io(output, e))?;
    check_cache_folder(&cache)?;
    std::fs::create_dir_all(&cache).map_err(|e| Error::io(output, e))?;
    let path = cache.join("build.lock");
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| Error::io(&path, e))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(file)),
        Err(std::fs::TryLockError::WouldBlock) => Ok(None),
        Err(std::fs::TryLockError::Error(e)) => Err(Error::io(&path, e)),
    }
}

/// Refuse a cache folder that is a symbolic link (solidtex would write and clean up where
/// it points) or not a folder.
fn check_cache_folder(cache: &Path) -> Result<()> {
    match std::fs::symlink_metadata(cache) {
        Ok(m) if m.file_type().is_symlink() => Err(Error::file(
            cache,
            "is a symbolic link; solidtex keeps its build cache only in a real folder (remove the link, or \
             build into another folder with -o)",
        )),
        Ok(m) if !m.is_dir() => Err(Error::file(
            cache,
            "exists and is not a folder; solidtex keeps its build cache there (move it away, or build into \
             another folder with -o)",
        )),
        _ => Ok(()),
    }
}

/// Remove the temporaries an interrupted run left in the output folder and its cache
/// (names solidtex gives them, files or folders), but none a running solidtex still writes
/// (see [`io::atomic::remove_stale_temporaries`]).
fn remove_stale_temporaries(output: &Path) {
    for folder in [output.to_path_buf(), output.join(files::CACHE)] {
        io::atomic::remove_stale_temporaries(&folder, None);
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

/// `report.md` and `report.html`: one row per exemplar with its sheet.
fn write_report(output: &Path, ledger: &Ledger, rows: &[Row]) -> Result<()> {
    let mut md = String::from(
        "# Exemplar library\n\n| exemplar | size | declared | classified | build | sheet | 3D |\n|---|---|---|---|---|---|---|\n",
    );
    let mut html = String::from(
        "<!doctype html><meta charset=utf-8><title>Exemplar library</title>\
         <style>body{font-family:sans-serif;background:#222;color:#eee}td,th{padding:4px 10px}img{width:280px}\
         .warning{color:#fc6}iframe{border:0;width:640px;height:440px}a{color:#9cf}</style>\
         <h1>Exemplar library</h1><table><tr><th>exemplar<th>size<th>declared<th>classified<th>build<th>sheet\n",
    );
    for row in rows {
        fn recorded(r: &Record, when: String) -> (String, String, String, String, String, Vec<String>) {
            let [x, y, z] = r.dims;
            let size = format!("{x}x{y}x{z}");
            let declared = r.declared.clone().unwrap_or("-".into());
            let mut warnings = r.warnings.clone();
            warnings.extend(type_disagrees(r));
            (r.name.clone(), size, declared, r.classified.clone(), when, warnings)
        }
        let none = |name: &str, why: String| (name.to_string(), "-".into(), "-".into(), "-".into(), why, Vec::new());
        let (name, size, declared, classified, build, warnings) = match row {
            Row::Now(Outcome::Built(r)) => recorded(r, format!("{:.2} s", r.seconds)),
            Row::Now(Outcome::Cached(r)) => recorded(r, "cached".into()),
            Row::Earlier(r) => recorded(r, "earlier build".into()),
            Row::Kept(Outcome::Failed(_, why), r) => recorded(r, format!("failed: {why} (earlier build kept)")),
            Row::Kept(_, r) => recorded(r, "cancelled (earlier build kept)".into()),
            Row::Now(Outcome::Failed(name, why)) => none(name, format!("failed: {why}")),
            Row::Now(Outcome::Cancelled(name)) => none(name, "cancelled".into()),
            Row::NotBuilt(name) => none(name, "not built".into()),
        };
        let (sheet, view) = (files::sheet(&name), files::view(&name));
        // a failed, cancelled or unbuilt entry without a kept build shows no picture: one on
        // disk would be of a build this report does not describe
        let current = matches!(row, Row::Now(Outcome::Built(_) | Outcome::Cached(_)) | Row::Earlier(_) | Row::Kept(..));
        let has_sheet = current && output.join(&sheet).is_file();
        let has_view = current && output.join(&view).is_file();
        let warned: String = warnings.iter().map(|w| format!("; warning: {w}")).collect();
        md += &format!(
            "| {name} | {size} | {declared} | {classified} | {} | {} | {} |\n",
            format!("{build}{warned}").replace('|', "\\|"),
            if has_sheet { format!("![{name}]({sheet})") } else { "-".into() },
            if has_view { format!("[3D view]({view})") } else { "-".into() }
        );
        let escaped = |t: &str| t.replace('&', "&amp;").replace('<', "&lt;");
        let mut cell = escaped(&build);
        for warning in &warnings {
            cell += &format!("<br><span class=warning>warning: {}</span>", escaped(warning));
        }
        html += &format!(
            "<tr><td>{name}<td>{size}<td>{declared}<td>{classified}<td>{cell}<td>{}{}\n",
            if has_sheet { format!("<img src=\"{sheet}\" alt=\"{name}\">") } else { "-".into() },
            if has_view { viewer_cell(&view) } else { String::new() }
        );
    }
    html += "</table>\n";
    html += VIEWER_SCRIPT;
    io::write_bytes(&output.join(REPORTS[0]), md.as_bytes())?;
    io::write_bytes(&output.join(REPORTS[1]), html.as_bytes())?;
    ledger.record(&REPORTS.map(String::from))
}

/// A warning when the classifier reads another texture type than the one declared: fill
/// and guided go by the declared type, so the designer should know they disagree.
fn type_disagrees(r: &Record) -> Option<String> {
    let declared = r.declared.as_deref()?;
    (r.classified != "-" && r.classified != declared).then(|| {
        format!(
            "declared type {declared}, classified {}: fill and guided use the declared type (docs/types-and-masks.md)",
            r.classified
        )
    })
}

/// A report row's 3D view: opened in place (the page loads only then) or in a tab of its own.
fn viewer_cell(view: &str) -> String {
    format!("<br><details data-view=\"{view}\"><summary>3D view</summary></details><a href=\"{view}\">open alone</a>")
}

/// Loads a row's 3D view into a frame the first time it is opened.
const VIEWER_SCRIPT: &str = "<script>for (const d of document.querySelectorAll('details[data-view]')) \
    d.addEventListener('toggle', () => { if (d.open && !d.querySelector('iframe')) { \
    const f = document.createElement('iframe'); f.src = d.dataset.view; d.append(f); } });</script>\n";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::manifest::parse_plan;
    use std::sync::atomic::{AtomicBool, Ordering};

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
    fn a_wait_for_the_lock_takes_it_once_free_and_times_out_with_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let held = lock_output(dir.path()).unwrap();
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let waiting = || {
            calls.fetch_add(1, Ordering::SeqCst);
        };
        let err = lock_waiting(dir.path(), Duration::from_millis(300), &waiting).unwrap_err().to_string();
        assert!(err.contains("run this again once it has finished") && !err.contains("-o"), "{err}");
        assert_eq!(calls.load(Ordering::SeqCst), 1, "told once");
        let freed = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            drop(held);
        });
        assert!(lock_waiting(dir.path(), Duration::from_secs(20), &waiting).is_ok());
        freed.join().unwrap();
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
    }

    /// Cancels once the synthesis reports its first level.
    struct CancelAtLevel(AtomicBool);

    impl Observer for CancelAtLevel {
        fn level_done(&self, _: &str, _: usize, _: usize, _: [usize; 3], _: usize, _: &[f32]) {
            self.0.store(true, Ordering::Relaxed);
        }
        fn cancelled(&self) -> bool {
            self.0.load(Ordering::Relaxed)
        }
    }

    /// The plan: a new entry is not built; after a build it is up to date; an edited
    /// recipe makes it stale with the reason; a cancelled rebuild keeps the previous
    /// output byte for byte and is reported as cancelled, not built.
    #[test]
    fn the_plan_sees_changes_and_a_cancelled_build_keeps_the_old_output() {
        let dir = tempfile::tempdir().unwrap();
        let pixels = (0..1024).flat_map(|i| [((i % 32 / 4 + i / 128) % 2) as f32, 0.5, (i % 3) as f32 / 2.0]).collect();
        let photo = crate::volume::Image2d::from_data(32, 32, crate::Channel::rgb(), pixels).unwrap();
        io::write_image(&dir.path().join("p.png"), &photo).unwrap();
        let manifest = dir.path().join("lib.toml");
        let write = |seed: u64| {
            let text = format!(
                "[[exemplar]]\nname = \"s\"\nrecipe = \"synth\"\nimage = \"p.png\"\nsize = 16\nlevels = 2\nseed = {seed}\n"
            );
            std::fs::write(&manifest, text).unwrap();
        };
        write(1);
        let request = Request {
            manifest: manifest.clone(),
            output: dir.path().join("out"),
            force: false,
            only: Vec::new(),
            shard: None,
        };
        let entries = select(&request).unwrap();
        let fresh = |entries: &[Entry]| cache::freshness(&entries[0], dir.path(), &request.output);
        assert_eq!(fresh(&entries), Freshness::NotBuilt);
        let outcomes = build(&request, &entries, &Quiet).unwrap();
        assert!(matches!(&outcomes[0], Outcome::Built(_)), "{outcomes:?}");
        assert!(matches!(fresh(&entries), Freshness::UpToDate(_)));
        let before = std::fs::read(files::volume(&request.output, "s")).unwrap();

        write(2);
        let entries = select(&request).unwrap();
        assert!(matches!(fresh(&entries), Freshness::Stale(_, why) if why == "the recipe changed"));
        let outcomes = build(&request, &entries, &CancelAtLevel(AtomicBool::new(false))).unwrap();
        assert_eq!(outcomes, [Outcome::Cancelled("s".into())]);
        assert_eq!(std::fs::read(files::volume(&request.output, "s")).unwrap(), before);
        assert!(matches!(fresh(&entries), Freshness::Stale(..)));
    }
}
