//! `solidtex build`: the library build of [`crate::library::build`] with a progress bar and
//! one line per finished exemplar on stderr.

use crate::error::{Error, Result};
use crate::library::build::{self, Observer, Outcome, Request};
use std::path::{Path, PathBuf};

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
}

/// Parse `K/N` or `auto/N` (K from the scheduler's environment).
pub fn parse_shard(text: &str) -> Result<(u64, u64)> {
    let bad = || Error::usage(format!("--shard {text:?} is not K/N with 0 <= K < N (or auto/N)"));
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let n: u64 = n.parse().map_err(|_| bad())?;
    if k != "auto" {
        let k: u64 = k.parse().map_err(|_| bad())?;
        return if n == 0 || k >= n { Err(bad()) } else { Ok((k, n)) };
    }
    let names = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];
    let (name, value) = names.iter().find_map(|v| std::env::var(v).ok().map(|value| (*v, value))).ok_or_else(|| {
        Error::usage("--shard auto/N needs JOB_COMPLETION_INDEX or SLURM_ARRAY_TASK_ID in the environment")
    })?;
    let k: u64 = value
        .trim()
        .parse()
        .map_err(|_| Error::usage(format!("the shard index {name}={value:?} is not a whole number")))?;
    if n == 0 || k >= n {
        return Err(Error::usage(format!("--shard {text:?}: the shard index {name}={k} is not below N = {n}")));
    }
    Ok((k, n))
}

/// Run `solidtex build`.
pub fn run(args: &BuildArgs) -> Result<()> {
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    let request = Request {
        manifest: args.manifest.clone(),
        output: args.output.clone(),
        force: args.force,
        only: args.only.clone(),
        shard,
    };
    let outcomes = if args.merge.is_empty() {
        let entries = build::select(&request)?;
        if let Some((k, n)) = shard {
            tell!("shard {k} of {n}: {} exemplar(s)", entries.len());
        }
        let lines = Lines::new(entries.len());
        let outcomes = build::build(&request, &entries, &lines);
        lines.finish();
        outcomes?
    } else {
        let outcomes = build::merge(&request, &args.merge)?;
        let lines = Lines { bar: None };
        outcomes.iter().filter(|o| matches!(o, Outcome::Failed(..))).for_each(|o| lines.finished(o));
        outcomes
    };
    summarize(&outcomes, &request)
}

/// A progress bar above the result lines on a terminal, plain lines otherwise; warnings
/// as lines.
pub struct Lines {
    bar: Option<indicatif::ProgressBar>,
}

impl Lines {
    /// Lines for a build of `total` entries.
    pub fn new(total: usize) -> Lines {
        use std::io::IsTerminal;
        let bar = (total > 0 && std::io::stderr().is_terminal()).then(|| {
            let bar = indicatif::ProgressBar::new(total as u64);
            let style = indicatif::ProgressStyle::with_template("{elapsed:>4} [{bar:30}] {pos}/{len} exemplars");
            bar.set_style(style.expect("valid template"));
            bar
        });
        Lines { bar }
    }

    fn line(&self, text: String) {
        match &self.bar {
            Some(bar) => bar.println(text),
            None => tell!("{text}"),
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Observer for Lines {
    fn warn(&self, name: &str, message: &str) {
        self.line(format!("warning: {name}: {message}"));
    }

    fn finished(&self, outcome: &Outcome) {
        self.line(match outcome {
            Outcome::Built(r) => {
                let [x, y, z] = r.dims;
                format!("built  {} {x}x{y}x{z} in {:.2} s", r.name, r.seconds)
            }
            Outcome::Cached(r) => format!("cached {} (recipe and inputs unchanged)", r.name),
            Outcome::Failed(name, why) => format!("FAILED {name}: {}", super::clip(why)),
            Outcome::Cancelled(name) => format!("cancelled {name}"),
        });
        if let Some(bar) = &self.bar {
            bar.inc(1);
        }
    }
}

fn summarize(outcomes: &[Outcome], request: &Request) -> Result<()> {
    let count = |f: fn(&Outcome) -> bool| outcomes.iter().filter(|o| f(o)).count();
    let built = count(|o| matches!(o, Outcome::Built(_)));
    let cached = count(|o| matches!(o, Outcome::Cached(_)));
    let failed: Vec<&str> = outcomes.iter().filter(|o| matches!(o, Outcome::Failed(..))).map(Outcome::name).collect();
    tell!(
        "{built} built, {cached} cached, {} failed; report: {}",
        failed.len(),
        request.output.join("report.html").display()
    );
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Error::invalid(format!("{} exemplar(s) failed: {} (see the lines above)", failed.len(), failed.join(", "))))
    }
}

/// What a command that builds its exemplars first says while another build holds the
/// built folder.
pub fn waiting_for(built: &Path) -> impl Fn() + '_ {
    move || {
        tell!(
            "waiting for another solidtex build of {} to finish (up to {} minutes)…",
            built.display(),
            crate::library::build::LOCK_WAIT.as_secs() / 60
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_are_k_of_n() {
        assert_eq!(parse_shard("2/5").unwrap(), (2, 5));
        assert!(parse_shard("5/5").is_err() && parse_shard("x").is_err() && parse_shard("1/0").is_err());
    }
}
