//! `solidtex synth`: 2D exemplars to a solid texture, with a progress bar on a terminal.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::io;
use crate::progress::Progress;
use crate::synth::{self, Exemplars, LayeredParams, SynthParams};
use crate::volume::Image2d;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Ey, Ez and exemplar shrinking: shared by `synth` and `quality`.
#[derive(Debug, clap::Args)]
pub struct OtherExemplars {
    /// The cross-section orthogonal to y (default: the exemplar).
    #[arg(long)]
    pub ey: Option<PathBuf>,
    /// The cross-section orthogonal to z (default: Ey).
    #[arg(long)]
    pub ez: Option<PathBuf>,
    /// Shrink exemplars whose longer side exceeds this many pixels (8 to 4096; e.g. 128 for photos).
    #[arg(long)]
    pub max_exemplar: Option<usize>,
}

/// The provenance key of the `--max-exemplar` a volume was synthesized with.
pub const MAX_EXEMPLAR_KEY: &str = crate::volume::MAX_EXEMPLAR_KEY;

/// The longer side past which an exemplar read at its own size gets a note about
/// `--max-exemplar`.
const LARGE_EXEMPLAR: usize = 512;

impl OtherExemplars {
    /// Check `--max-exemplar` against its range (a usage error).
    pub fn check(&self) -> Result<()> {
        let (lo, hi) = SynthParams::EXEMPLAR_SIDE;
        self.max_exemplar.map(|m| io::values::within("--max-exemplar", m, lo, hi)).transpose().map_err(usage)?;
        Ok(())
    }

    /// Load one image, shrunk as asked; `what` names it in errors.
    pub fn load(&self, path: &Path, what: &str) -> Result<Image2d> {
        io::read_image_fit(path, self.max_exemplar).map_err(|e| match e {
            Error::Io { path, source } => Error::file(&path, format!("cannot read the {what}: {source}")),
            other => other,
        })
    }

    /// Ey and Ez, if given.
    pub fn load_yz(&self) -> Result<(Option<Image2d>, Option<Image2d>)> {
        let ey = self.ey.as_deref().map(|p| self.load(p, "Ey exemplar")).transpose()?;
        let ez = self.ez.as_deref().map(|p| self.load(p, "Ez exemplar")).transpose()?;
        Ok((ey, ez))
    }

    /// `e` about the exemplars, in the file it is about: the image an [`Error::Exemplar`]
    /// names (Ey standing in for a missing Ez, the exemplar `ex` for a missing Ey), else `ex`.
    pub fn in_file(&self, e: Error, ex: &Path) -> Error {
        let ey = self.ey.as_deref().unwrap_or(ex);
        let path = match &e {
            Error::Exemplar { which: 1, .. } => ey,
            Error::Exemplar { which: 2, .. } => self.ez.as_deref().unwrap_or(ey),
            _ => ex,
        };
        e.in_file(path)
    }

    /// Ey and Ez (as loaded) have the channels of the exemplar `ex` read from `path`; the
    /// error names the image that differs.
    pub fn check_channels(
        &self,
        (path, ex): (&Path, &Image2d),
        (ey, ez): (Option<&Image2d>, Option<&Image2d>),
    ) -> Result<()> {
        for (file, image) in [(&self.ey, ey), (&self.ez, ez)] {
            if let (Some(file), Some(image)) = (file, image)
                && image.channel_count() != ex.channel_count()
            {
                return Err(Error::file(
                    file,
                    format!(
                        "has {} channel(s) ({}) but the exemplar {} has {} ({}); all exemplars need the same channels",
                        image.channel_count(),
                        crate::volume::channel_names(image.channels()),
                        path.display(),
                        ex.channel_count(),
                        crate::volume::channel_names(ex.channels())
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The arguments of `solidtex synth`.
#[derive(Debug, clap::Args)]
pub struct SynthArgs {
    /// The exemplar image (Ex: the cross-section orthogonal to x; alone, all three).
    pub exemplar: PathBuf,
    /// Ey, Ez and shrinking.
    #[command(flatten)]
    pub others: OtherExemplars,
    /// Layered (type 1-b) synthesis: the exemplar's rows run along depth (the volume's z).
    #[arg(long)]
    pub layered: bool,
    /// Depth of each exemplar pixel (grey image, same size; with --layered).
    #[arg(long, requires = "layered")]
    pub depth: Option<PathBuf>,
    /// Switch off the anti-sweeping rule (with --layered; for comparison).
    #[arg(long, requires = "layered")]
    pub no_anti_sweeping: bool,
    /// Weight of the depth channel in neighbourhood distances, 0 to 100 (with --layered).
    #[arg(long, default_value_t = 1.0, requires = "layered")]
    pub depth_weight: f32,
    /// Start from this volume (same size; the exemplar's channels) instead of random
    /// pixels, and refine it: its coarse layout stays, the exemplar's look comes in.
    #[arg(long)]
    pub start: Option<PathBuf>,
    /// The synthesis core: `blend` blends matched colours and matches the photo's
    /// histogram and spectrum (Kopf 2007); `coordinates` copies exemplar pixels in coherent
    /// patches, each voxel one pixel (joints and channels stay more connected, labels stay
    /// labels, layers stay crisp; slower). Default: `coordinates` with --layered and for
    /// label images (each of at most 16 colours), `blend` otherwise; --start,
    /// --no-anti-sweeping and --depth-weight belong to `blend` and select it.
    #[arg(long, value_parser = ["blend", "coordinates"])]
    pub core: Option<String>,
    /// Output size: N for a cube, or XxYxZ; each side 1 to 512, within the voxel budget.
    #[arg(long, default_value = "64")]
    pub size: String,
    /// Seed (any 64-bit whole number): the same inputs and seed give the same volume on any
    /// machine and thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Pyramid levels, 1 to 8.
    #[arg(long, default_value_t = 3)]
    pub levels: usize,
    /// Most iterations per level below the finest, 1 to 16.
    #[arg(long, default_value_t = 4)]
    pub iterations: usize,
    /// Most iterations at the finest level, 1 to 16.
    #[arg(long, default_value_t = 2)]
    pub finest_iterations: usize,
    /// Stop a level when the mean match distance improves by less than this share (0 to 1).
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f32,
    /// Histogram matching strength, 0 (off) to 10; with `--core coordinates`, how much dearer
    /// candidates are in colours the solid holds too much of (1: four times the excess).
    #[arg(long, default_value_t = 1.0)]
    pub histogram: f32,
    /// How much the best-matching neighbourhoods dominate the blend, 0 to 16: a prediction
    /// weighs distance^-power; lower blends more, softer (default: 6; 1.2 with --layered).
    #[arg(long)]
    pub blend_power: Option<f32>,
    /// Leave the finest level's power spectrum as the blend made it (for comparison: the
    /// features come out larger than the photo's).
    #[arg(long)]
    pub no_spectrum: bool,
    /// k-coherence candidates per neighbour, 1 to 32 (more: better matches, slower).
    #[arg(long, default_value_t = 6)]
    pub coherence: usize,
    /// Most PCA dimensions of the neighbourhood search, 1 to 64 (fewer: faster, coarser matches).
    #[arg(long, default_value_t = 16)]
    pub pca_dims: usize,
    /// Share of the neighbourhood variance the PCA keeps, 0.01 to 1, up to --pca-dims dimensions.
    #[arg(long, default_value_t = 0.95)]
    pub pca_variance: f32,
    /// Print every stage with the time it was reached.
    #[arg(long, short)]
    pub verbose: bool,
    /// The volume file to write (.exr, .nrrd, .vol, .png, .vdb, .dds, or a folder).
    #[arg(short, long)]
    pub output: PathBuf,
}

struct Bar {
    bar: ProgressBar,
    verbose: bool,
    started: Instant,
    /// The stage printed last (`-v` prints each stage once, not each step within it).
    printed: std::sync::Mutex<String>,
}

impl Progress for Bar {
    fn update(&self, stage: &str, fraction: f32) {
        self.bar.set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        self.bar.set_message(stage.to_string());
        let mut printed = self.printed.lock().unwrap_or_else(|e| e.into_inner());
        if self.verbose && *printed != stage {
            *printed = stage.to_string();
            self.bar.suspend(|| {
                tell!("{:>8.3} s  {:>5.1} %  {stage}", self.started.elapsed().as_secs_f64(), fraction * 100.0)
            });
        }
    }

    fn warn(&self, message: &str) {
        self.bar.suspend(|| tell!("warning: {message}"));
    }
}

/// Check every number of `solidtex synth` against its range (usage errors).
fn check_values(args: &SynthArgs) -> Result<[usize; 3]> {
    use io::values::within;
    let size = super::commands::parse_size(&args.size)?;
    args.others.check()?;
    let checks = || -> Result<()> {
        within("--levels", args.levels, SynthParams::LEVELS.0, SynthParams::LEVELS.1)?;
        within("--iterations", args.iterations, SynthParams::ITERATIONS.0, SynthParams::ITERATIONS.1)?;
        within("--finest-iterations", args.finest_iterations, SynthParams::ITERATIONS.0, SynthParams::ITERATIONS.1)?;
        within("--tolerance", args.tolerance, SynthParams::TOLERANCE.0, SynthParams::TOLERANCE.1)?;
        within("--histogram", args.histogram, SynthParams::HISTOGRAM.0, SynthParams::HISTOGRAM.1)?;
        within("--coherence", args.coherence, SynthParams::COHERENCE.0, SynthParams::COHERENCE.1)?;
        if let Some(power) = args.blend_power {
            within("--blend-power", power, SynthParams::BLEND_POWER.0, SynthParams::BLEND_POWER.1)?;
        }
        within("--pca-dims", args.pca_dims, SynthParams::PCA_DIMS.0, SynthParams::PCA_DIMS.1)?;
        within("--pca-variance", args.pca_variance, SynthParams::PCA_VARIANCE.0, SynthParams::PCA_VARIANCE.1)?;
        within("--depth-weight", args.depth_weight, LayeredParams::DEPTH_WEIGHT.0, LayeredParams::DEPTH_WEIGHT.1)?;
        options_agree(args)
    };
    checks().map_err(usage)?;
    Ok(size)
}

/// Options that belong together: `--ey`/`--ez` give a homogeneous solid's other
/// cross-sections (a layered solid is made from its one exemplar), and `--start`,
/// `--no-anti-sweeping` and `--depth-weight` belong to the blend core.
fn options_agree(args: &SynthArgs) -> Result<()> {
    let given = |name: &'static str, on: bool| on.then_some(name);
    if args.layered
        && let Some(flag) = given("--ey", args.others.ey.is_some()).or(given("--ez", args.others.ez.is_some()))
    {
        return Err(Error::invalid(format!(
            "{flag} gives a homogeneous solid's other cross-section; --layered makes the solid from its one exemplar, \
             whose rows are the layers"
        )));
    }
    let blend_only = given("--start", args.start.is_some())
        .or(given("--no-anti-sweeping", args.no_anti_sweeping))
        .or(given("--depth-weight", args.depth_weight != 1.0));
    if let (Some("coordinates"), Some(flag)) = (args.core.as_deref(), blend_only) {
        return Err(Error::invalid(format!(
            "{flag} belongs to the blend core; --core coordinates cannot take it (leave out --core or give --core blend)"
        )));
    }
    Ok(())
}

/// The core `args` ask for: named, or by default the coordinate core for a layered solid
/// and for label images (docs/synthesis.md) unless a blend-only option is given.
fn core_of(args: &SynthArgs, images: &[&crate::volume::Image2d]) -> synth::Core {
    let blend_only = args.start.is_some() || args.no_anti_sweeping || args.depth_weight != 1.0;
    match args.core.as_deref() {
        Some("coordinates") => synth::Core::Coordinates,
        Some(_) => synth::Core::Blend,
        None if blend_only => synth::Core::Blend,
        None => synth::Core::for_exemplars(images, args.layered),
    }
}

/// Warn when one directional image is asked to make a homogeneous solid: the same grain
/// in all three cut directions leaves one cut a smear.
fn warn_if_directional(image: &crate::volume::Image2d, path: &Path) {
    if let Some(warning) = synth::directional_warning(image) {
        tell!(
            "warning: {}: {warning}. Give the other cross-sections with --ey/--ez, or use --layered if the image \
             is layers along its rows",
            path.display()
        );
    }
}

/// Run `solidtex synth`.
pub fn run(args: &SynthArgs) -> Result<()> {
    let size = check_values(args)?;
    let inputs = [Some(&args.exemplar), args.others.ey.as_ref(), args.others.ez.as_ref(), args.depth.as_ref()];
    let inputs: Vec<&Path> = inputs.into_iter().chain([args.start.as_ref()]).flatten().map(PathBuf::as_path).collect();
    io::check_output(&args.output, &inputs)?;
    let budget = io::budget_from_env()?;
    let ex = args.others.load(&args.exemplar, "exemplar")?;
    let (ey, ez) = if args.layered { (None, None) } else { args.others.load_yz()? };
    let images: Vec<&crate::volume::Image2d> = [Some(&ex), ey.as_ref(), ez.as_ref()].into_iter().flatten().collect();
    let params = SynthParams {
        core: core_of(args, &images),
        size,
        levels: args.levels,
        max_iterations: args.iterations,
        finest_iterations: args.finest_iterations,
        histogram_strength: args.histogram,
        blend_power: args.blend_power,
        spectrum: !args.no_spectrum,
        tolerance: args.tolerance,
        coherence: args.coherence,
        max_pca_dims: args.pca_dims,
        pca_variance: args.pca_variance,
        budget_bytes: budget,
        start: args.start.as_deref().map(|p| io::read_volume(p, budget)).transpose()?,
        ..SynthParams::default()
    };
    if args.others.max_exemplar.is_none() && ex.width().max(ex.height()) > LARGE_EXEMPLAR {
        tell!(
            "note: {} is {}x{} pixels; synthesis prepares every pixel's neighbourhood, which takes long at this size: \
             photos are usually shrunk with --max-exemplar 128 or 256",
            args.exemplar.display(),
            ex.width(),
            ex.height()
        );
    }
    if let Some(path) = &args.start {
        synth::check_start(&params, ex.channels(), args.layered).map_err(|e| e.in_file(path))?;
    }
    let started = Instant::now();
    let bar = Bar { bar: ProgressBar::new(1000), verbose: args.verbose, started, printed: Default::default() };
    bar.bar.set_style(
        ProgressStyle::with_template("{elapsed:>4} [{bar:40}] {percent:>3}% {msg}").expect("valid template"),
    );
    let volume = if args.layered {
        let depth = args.depth.as_deref().map(|p| args.others.load(p, "depth image")).transpose()?;
        if let (None, Some(warning)) = (&depth, synth::layering_warning(&ex)) {
            tell!(
                "warning: {}: {warning}. Turn the image so its rows are the layers, or give each pixel's depth with \
                 --depth",
                args.exemplar.display()
            );
        }
        let layered = LayeredParams { anti_sweeping: !args.no_anti_sweeping, depth_weight: args.depth_weight };
        if let (Some(d), Some(path)) = (&depth, &args.depth)
            && (d.width(), d.height()) != (ex.width(), ex.height())
        {
            return Err(Error::file(
                path,
                format!(
                    "the depth image is {}x{} pixels but the exemplar {} is {}x{}; they must be the same size",
                    d.width(),
                    d.height(),
                    args.exemplar.display(),
                    ex.width(),
                    ex.height()
                ),
            ));
        }
        synth::synthesize_layered(&ex, depth.as_ref(), &params, &layered, args.seed, &bar)
            .map_err(|e| e.in_file(&args.exemplar))?
    } else {
        if ey.is_none() && ez.is_none() {
            warn_if_directional(&ex, &args.exemplar);
        }
        let exemplars = Exemplars { x: &ex, y: ey.as_ref(), z: ez.as_ref() };
        synth::synthesize(exemplars, &params, args.seed, &bar).map_err(|e| args.others.in_file(e, &args.exemplar))?
    };
    bar.bar.finish_and_clear();
    let mut volume = volume;
    if let Some(side) = args.others.max_exemplar {
        // `quality` shrinks the exemplars alike when it is not told otherwise
        volume.meta.set(MAX_EXEMPLAR_KEY, side.to_string());
    }
    super::write_volume(&args.output, &volume)?;
    let [x, y, z] = volume.dims();
    tell!("wrote {} ({x}x{y}x{z}) in {:.2} s", args.output.display(), started.elapsed().as_secs_f64());
    if let Some(axis) = volume.meta.get(synth::finer::FINER_KEY) {
        tell!(
            "  {axis} was synthesized twice as finely: the exemplars' features along it are at most {} of their \
             length along the other axes",
            synth::finer::THIN
        );
    }
    Ok(())
}
