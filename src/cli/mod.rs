//! The command line: argument definitions and one function per subcommand.
//! Exit codes: 0 success, 1 failure, 2 usage (clap's own).

/// `println!` for command output: a closed pipe (`solidtex info x.exr | head`) ends the
/// program quietly instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => { $crate::cli::write_out(&format!($($arg)*)) };
}

/// `eprintln!` for notes, warnings and the files written: a closed error stream is ignored,
/// so it cannot turn a command's result into a panic.
macro_rules! tell {
    ($($arg:tt)*) => { $crate::cli::write_err(&format!($($arg)*)) };
}

/// Write a volume in the format its path names, warning when the format drops its
/// channel names ([`crate::io::channels_lost`]) or its place in model space
/// ([`crate::io::model_grid_lost`]).
fn write_volume(path: &std::path::Path, volume: &crate::volume::Volume) -> crate::error::Result<()> {
    // a large volume takes seconds to encode: say so rather than sit silent
    let megabytes = volume.data().len() * 4 / (1 << 20);
    if megabytes >= LARGE_WRITE_MB {
        tell!("writing {} ({megabytes} MB of samples)…", path.display());
    }
    crate::io::write_volume(path, volume)?;
    let notes = [crate::io::channels_lost(path, volume), crate::io::model_grid_lost(path, volume)];
    for note in notes.into_iter().flatten() {
        tell!("warning: {note}");
    }
    Ok(())
}

/// Volumes of at least this many megabytes of samples are announced before they are
/// written (a 256³ RGB volume, 192 MB, takes over ten seconds as EXR).
const LARGE_WRITE_MB: usize = 64;

mod bench;
mod bench_fill;
mod bench_guided;
mod bench_surface;
pub mod build;
mod commands;
mod export;
mod fill;
mod guided;
mod handmade;
mod info;
mod masks;
mod quality;
mod snapshot;
mod surface;
mod synth;
mod types;
pub mod web;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// solidtex: author solid texture exemplars and look at them.
#[derive(Debug, Parser)]
#[command(name = "solidtex", version, about, long_about = None)]
pub struct Cli {
    /// What to do (none: open the terminal UI on exemplars/library.toml).
    #[command(subcommand)]
    pub command: Option<Command>,
}

impl Cli {
    /// Parse `args` as [`clap::Parser::parse_from`] does (exiting with clap's message and
    /// code 2 on a usage error), except that a negative number given to an option is its
    /// value: `--size -5` is then refused as a value out of the option's kind or range,
    /// not as an unknown flag.
    pub fn parse_numbers_from<I, T>(args: I) -> Cli
    where
        I: IntoIterator<Item = T>,
        T: Into<std::ffi::OsString> + Clone,
    {
        use clap::{CommandFactory, FromArgMatches};
        let command = with_negative_numbers(Cli::command());
        let matches = command.clone().get_matches_from(args);
        Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.format(&mut command.clone()).exit())
    }
}

/// `command` and its subcommands with every option taking a value accepting negative
/// numbers, and whole-number options saying what they take.
fn with_negative_numbers(command: clap::Command) -> clap::Command {
    command
        .mut_args(|arg| {
            let arg = match arg.get_action().takes_values() && !arg.is_positional() {
                true => arg.allow_negative_numbers(true),
                false => arg,
            };
            let kind = arg.get_value_parser().type_id();
            if kind == std::any::TypeId::of::<usize>() {
                arg.value_parser(whole::<usize>)
            } else if kind == std::any::TypeId::of::<u64>() {
                arg.value_parser(whole::<u64>)
            } else if kind == std::any::TypeId::of::<f32>() {
                arg.value_parser(finite::<f32>)
            } else if kind == std::any::TypeId::of::<f64>() {
                arg.value_parser(finite::<f64>)
            } else {
                arg
            }
        })
        .mut_subcommands(with_negative_numbers)
}

/// A whole number, refused with what was wrong; the option's own range (in its help) is
/// checked after parsing.
fn whole<T: std::str::FromStr>(text: &str) -> std::result::Result<T, String> {
    let trimmed = text.trim();
    let digits = all_digits(trimmed);
    trimmed.parse().map_err(|_| match trimmed.parse::<f64>() {
        _ if trimmed.is_empty() => "an empty value is not a number; give a whole number".to_string(),
        _ if digits => format!("{text} is too large; give a whole number within the option's range (see --help)"),
        Ok(v) if v < 0.0 => format!("{text} is negative; give a whole number within the option's range (see --help)"),
        Ok(_) => format!("{text} is not a whole number; give one without a fraction"),
        Err(_) => format!("{text} is not a number; give a whole number"),
    })
}

/// A finite number, refused with what was wrong (`1e308` overflows an f32 to infinity,
/// `nan` and `inf` parse but are no value an option takes); the option's own range is
/// checked after parsing.
fn finite<T: std::str::FromStr + Into<f64> + Copy>(text: &str) -> std::result::Result<T, String> {
    match text.trim().parse::<T>() {
        Ok(v) if v.into().is_finite() => Ok(v),
        Ok(_) => Err(format!("{text} is not a finite number; give one within the option's range (see --help)")),
        Err(_) if text.trim().is_empty() => Err("an empty value is not a number".to_string()),
        Err(_) => Err(format!("{text} is not a number")),
    }
}

/// Whether `text` is digits only (a whole number that failed to parse is then too large).
fn all_digits(text: &str) -> bool {
    !text.is_empty() && text.bytes().all(|b| b.is_ascii_digit())
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print dims, channels, texture type, provenance and per-channel statistics.
    Info {
        /// A volume file (.exr, .nrrd, .vol, .png atlas, .vdb, .dds, or a folder of PNG slices).
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Convert a volume between formats, chosen by the extensions.
    Convert {
        /// The volume to read.
        input: PathBuf,
        /// Where to write it: .exr, .nrrd, .vol, .png (atlas), .vdb (OpenVDB), .dds (DDS volume
        /// texture) or a folder (PNG slices).
        output: PathBuf,
        /// Pixel format of a .dds output: rgba8, rgba16f (default) or rgba32f.
        #[arg(long)]
        dds_format: Option<String>,
    },
    /// Save one axis-aligned slice as a PNG.
    Slice {
        /// The volume to read.
        file: PathBuf,
        /// The axis the slice is across: x, y or z.
        #[arg(long, default_value = "z")]
        axis: String,
        /// Index along the axis, 0 to the volume's side minus 1 (default: the middle).
        #[arg(long)]
        index: Option<usize>,
        /// An oblique cut instead: `PX,PY,PZ,NX,NY,NZ`, the plane through point P (voxels)
        /// with normal N; as wide as the volume's longest side, trilinear, the volume
        /// repeating past its faces.
        #[arg(long, conflicts_with_all = ["axis", "index"], allow_hyphen_values = true)]
        plane: Option<String>,
        /// The PNG to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Tile the z-slices into an RGBA flipbook PNG for game engines, with a JSON sidecar
    /// (OUT.json) naming the layout (Unity Texture3D, Unreal volume texture).
    Flipbook {
        /// The volume to read.
        file: PathBuf,
        /// The PNG to write (the sidecar goes beside it, with the extension .json).
        #[arg(short, long)]
        output: PathBuf,
        /// Tiles across, 1 to the volume's slices (default: near square, or from --rows).
        #[arg(long)]
        columns: Option<usize>,
        /// Tiles down, 1 to the volume's slices (default: from --columns, or near square).
        #[arg(long)]
        rows: Option<usize>,
        /// Pixels of repeated edge around each tile, 0 to 64 (against bilinear bleeding).
        #[arg(long, default_value_t = 0)]
        padding: usize,
        /// Enlarge the image to powers of two.
        #[arg(long)]
        pow2: bool,
    },
    /// Save a contact sheet: the three central slices and a cut-away corner view.
    Sheet {
        /// The volume to read.
        file: PathBuf,
        /// The PNG to write.
        #[arg(short, long)]
        output: PathBuf,
        /// Title printed on the sheet (default: the file name).
        #[arg(long)]
        title: Option<String>,
    },
    /// Make a procedural volume: marble, strata, wood, the cake's sponge, cream and chocolate, or a 3D truth (foam, channels).
    Make {
        /// marble, strata, wood, sponge, cream, chocolate, or the label volumes foam and
        /// channels (3D truths with long features for `quality --labels --truth`).
        recipe: String,
        /// Size: N for a cube, or XxYxZ; each side 1 to 512, within the voxel budget.
        #[arg(long, default_value = "64")]
        size: String,
        /// Seed for the noise (any 64-bit whole number).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// The volume file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Synthesize a solid texture from 2D exemplars (Kopf 2007; --layered for type 1-b).
    Synth(synth::SynthArgs),
    /// Measure a volume against its exemplars: slice energy, sharpness, line structure,
    /// histograms, layering; or a label volume against its 3D truth.
    Quality(quality::QualityArgs),
    /// Make the control volume quality figures must fail: random-phase noise with the
    /// exemplars' power spectra and exact colours.
    Noise(quality::NoiseArgs),
    /// Time the synthesis workloads (median of several runs) on built-in exemplars.
    Bench(bench::BenchArgs),
    /// Sweep a 2D cross-section into a volume, with noise and a skin.
    Sweep(handmade::SweepArgs),
    /// Stamp a seed mesh (OBJ, STL, PLY) into a volume.
    Stamp(handmade::StampArgs),
    /// Scatter seed meshes without overlaps.
    Scatter(handmade::ScatterArgs),
    /// Blur a volume locally inside a sphere.
    Blur(handmade::BlurArgs),
    /// Draw the project's own inputs: a cross-section image (kiwi, carrot, trunk) or a seed mesh.
    Draw(handmade::DrawArgs),
    /// Write a small text snapshot of a volume, or check a volume against one.
    Snapshot {
        /// The volume.
        volume: PathBuf,
        /// Write the snapshot here.
        #[arg(short, long, conflicts_with = "check")]
        output: Option<PathBuf>,
        /// Compare with this snapshot (exit 1 with the differences when they differ).
        #[arg(long)]
        check: Option<PathBuf>,
        /// With --check: allowed difference of statistics and thumbnail values, 0 to 1000000
        /// (default 0: the content hash must match).
        #[arg(long)]
        tolerance: Option<f64>,
    },
    /// List the seven LST texture types: levels, tiling, tensor field, filling, examples.
    Types,
    /// Estimate the LST texture type of a volume, with the measurements that decided it.
    Classify {
        /// The volume to classify.
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Make alpha masks: splotch, layered (outer/middle/inner), from a mesh, or a preset.
    Mask {
        /// Which mask.
        #[command(subcommand)]
        kind: masks::MaskCommand,
    },
    /// Open the terminal UI on a library manifest.
    Tui {
        /// The manifest.
        #[arg(default_value = "exemplars/library.toml")]
        manifest: PathBuf,
        /// Where builds go.
        #[arg(short, long, default_value = "out")]
        output: PathBuf,
    },
    /// Build every exemplar a manifest lists (in parallel, cached), with a report.
    Build(build::BuildArgs),
    /// Fill a closed mesh with a library exemplar by lapped solid textures (writes a .lst model).
    Fill(fill::FillArgs),
    /// Render a planar cut through one or more filled models as a PNG.
    Cut(fill::CutArgs),
    /// Sample one or more filled models into a volume.
    Bake(fill::BakeArgs),
    /// Render the surface of a filled model as a PNG.
    View(fill::ViewArgs),
    /// Render one or more filled models as translucent material (volume rendering) as a PNG.
    Render(fill::RenderArgs),
    /// Take filled models (or a surface skin) out as a glTF 2.0 binary (.glb): the surface with
    /// vertex colours or a texture atlas, for Blender, game engines and web viewers.
    Export(export::ExportArgs),
    /// Volumes, filled models or a skin as one self-contained HTML page with an interactive
    /// 3D view (WebGL2): slices and cut-aways, the model's surface, its inside, translucent.
    Web(web::WebArgs),
    /// Grow a 2D exemplar over a mesh's surface (Turk 2001): a .ply with vertex colours.
    Surface(surface::SurfaceArgs),
    /// Draw the frame field of sketch-guided synthesis (Zhang 2011) on a cut as a PNG.
    Field(guided::FieldArgs),
    /// Synthesize a solid texture along the frame field (Zhang 2011): a cut on demand as a
    /// PNG, or the whole solid as a volume.
    Guided(guided::GuidedArgs),
}

/// Run one command of the command line. The terminal UI (`tui`, or no command) is the
/// other front end: `main` dispatches it, so this module never calls into it.
pub fn run(command: Command) -> crate::Result<()> {
    match command {
        Command::Info { file, json } => info::run(&file, json),
        Command::Convert { input, output, dds_format } => commands::convert(&input, &output, dds_format.as_deref()),
        Command::Slice { file, axis, index, plane, output } => match plane {
            Some(plane) => commands::oblique_slice(&file, &plane, &output),
            None => commands::slice(&file, &axis, index, &output),
        },
        Command::Sheet { file, output, title } => commands::sheet(&file, &output, title),
        Command::Flipbook { file, output, columns, rows, padding, pow2 } => {
            commands::flipbook(&file, &output, columns, rows, padding, pow2)
        }
        Command::Make { recipe, size, seed, output } => commands::make(&recipe, &size, seed, &output),
        Command::Synth(args) => synth::run(&args),
        Command::Quality(args) => quality::run(&args),
        Command::Noise(args) => quality::noise(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Build(args) => build::run(&args),
        Command::Tui { .. } => Err(crate::Error::usage("the terminal UI is started by the solidtex binary itself")),
        Command::Sweep(args) => handmade::run_sweep(&args),
        Command::Stamp(args) => handmade::run_stamp(&args),
        Command::Scatter(args) => handmade::run_scatter(&args),
        Command::Blur(args) => handmade::run_blur(&args),
        Command::Draw(args) => handmade::run_draw(&args),
        Command::Classify { file, json } => types::classify(&file, json),
        Command::Snapshot { volume, output, check, tolerance } => {
            snapshot::run(&volume, output.as_deref(), check.as_deref(), tolerance)
        }
        Command::Types => {
            types::types();
            Ok(())
        }
        Command::Mask { kind } => masks::run(&kind),
        Command::Fill(args) => fill::run_fill(&args),
        Command::Cut(args) => fill::run_cut(&args),
        Command::Bake(args) => fill::run_bake(&args),
        Command::View(args) => fill::run_view(&args),
        Command::Render(args) => fill::run_render(&args),
        Command::Export(args) => export::run(&args),
        Command::Web(args) => web::run(&args),
        Command::Surface(args) => surface::run(&args),
        Command::Field(args) => guided::run(&args),
        Command::Guided(args) => guided::run_guided(&args),
    }
}

/// Progress that only prints warnings, on stderr.
pub(crate) struct Stderr;

impl crate::progress::Progress for Stderr {
    fn update(&self, _stage: &str, _fraction: f32) {}

    fn warn(&self, message: &str) {
        tell!("warning: {message}");
    }
}

/// Write one line to stdout; exit quietly when the reader has gone away.
pub fn write_out(text: &str) {
    use std::io::Write;
    if writeln!(std::io::stdout().lock(), "{text}").is_err() {
        std::process::exit(0);
    }
}

/// One line on the error stream; a closed stream is ignored.
pub fn write_err(text: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// An error message cut to a readable length: input echoed in a message (a 4 MB line of a
/// broken file, say) keeps its first and last characters and says how much was left out.
pub fn clip(message: &str) -> String {
    const HEAD: usize = 300;
    const TAIL: usize = 120;
    let chars: Vec<char> = message.chars().collect();
    if chars.len() <= HEAD + TAIL + 40 {
        return message.to_string();
    }
    let head: String = chars[..HEAD].iter().collect();
    let tail: String = chars[chars.len() - TAIL..].iter().collect();
    format!("{head} [... {} characters left out ...] {tail}", chars.len() - HEAD - TAIL)
}
