//! `solidtex classify` and `solidtex mask ...`.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::io;
use crate::mask::{self, Layer, MaskMeasures};
use crate::volume::{Axis, Volume};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Run `solidtex classify FILE [--json]`.
pub fn classify(file: &Path, json: bool) -> Result<()> {
    let volume = io::read_volume(file, io::budget_from_env()?)?;
    let c = crate::classify::classify(&volume).map_err(|e| e.in_file(file))?;
    if json {
        say!("{}", serde_json::to_string_pretty(&c).expect("a classification always serializes"));
        return Ok(());
    }
    let t = c.texture_type;
    say!("{}\n  type        {t} (anisotropy {}, variation {})", file.display(), t.anisotropy(), t.variation());
    say!("  primary     {}", c.primary_axis.as_deref().unwrap_or("none (isotropic)"));
    say!("  depth axis  {}", c.depth_axis.as_deref().unwrap_or("none (homogeneous)"));
    say!("  confidence  {:.2}", c.confidence);
    let [gx, gy, gz] = c.gradient_energy;
    let [lx, ly, lz] = c.layering;
    say!("  gradient energy / variance   x {gx:.4}  y {gy:.4}  z {gz:.4}   (alike within a factor 1.8)");
    say!("  within-slice variance share  x {lx:.3}  y {ly:.3}  z {lz:.3}   (layered below 0.45)");
    if let Some(declared) = volume.meta.texture_type.filter(|d| *d != t) {
        say!("  note        the file declares type {declared}");
    }
    for note in &c.notes {
        say!("  note        {note}");
    }
    Ok(())
}

/// Print the table of the seven types.
pub fn types() {
    for t in crate::TextureType::ALL {
        let tiles = ["in no direction", "along one axis", "in a plane", "in 3D"][t.tiling_dimensions() as usize];
        say!("type {:<4} anisotropy {}  variation {}  tiles {tiles}", t.name(), t.anisotropy(), t.variation());
        say!("          tensor field: {}", t.tensor_field());
        say!("          filling:      {}", t.filling());
        say!("          examples:     {}", t.examples());
    }
}

/// The options every mask shares.
#[derive(Debug, clap::Args)]
pub struct Shape {
    /// Side of the cubic mask in voxels, 4 to 512.
    #[arg(long, default_value_t = 64)]
    pub size: usize,
    /// Width of the soft band as a share of the size: over 0 and under 0.5.
    #[arg(long, default_value_t = mask::DEFAULT_FALLOFF)]
    pub falloff: f32,
    /// Seed of the shape (any 64-bit whole number).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl Shape {
    /// Check the size and fall-off against their ranges (usage errors).
    fn check(&self) -> Result<()> {
        let (lo, hi) = mask::SIZE;
        io::values::within("--size", self.size, lo, hi).map_err(usage)?;
        io::values::falloff("--falloff", self.falloff).map_err(usage)?;
        Ok(())
    }
}

/// The `mask` subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum MaskCommand {
    /// A soft noisy ball.
    Splotch {
        /// Size, fall-off and seed.
        #[command(flatten)]
        shape: Shape,
        /// The mask file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Outer, middle and inner masks for depth-varying textures, into a folder.
    Layered {
        /// Size, fall-off and seed.
        #[command(flatten)]
        shape: Shape,
        /// The axis depth runs along (depth 0 at its first face).
        #[arg(long, default_value = "z")]
        depth_axis: String,
        /// The folder to write outer.exr, middle.exr and inner.exr into.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// A mask shaped by a closed mesh, scaled to fit the cube.
    Mesh {
        /// The mesh (OBJ, STL, PLY).
        mesh: PathBuf,
        /// Size, fall-off (the seed is not used).
        #[command(flatten)]
        shape: Shape,
        /// The mask file to write.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Build a preset (`masks/*.toml`) into the file (or folder) beside it.
    Preset {
        /// The preset file.
        preset: PathBuf,
    },
}

/// Run a `mask` subcommand.
pub fn run(command: &MaskCommand) -> Result<()> {
    match command {
        MaskCommand::Splotch { shape, output } => {
            shape.check()?;
            io::check_output(output, &[])?;
            write_one(output, mask::splotch(shape.size, shape.falloff, shape.seed)?)
        }
        MaskCommand::Layered { shape, depth_axis, output } => {
            shape.check()?;
            let depth: Axis = depth_axis.parse().map_err(usage)?;
            io::check_folder_output(output, &[])?;
            write_layers(output, shape.size, shape.falloff, shape.seed, depth)
        }
        MaskCommand::Mesh { mesh, shape, output } => {
            shape.check()?;
            io::check_output(output, &[mesh])?;
            let solid = io::mesh_file::read_mesh(mesh)?.oriented();
            write_one(output, mask::from_mesh(&solid, shape.size, shape.falloff).map_err(|e| e.in_file(mesh))?)
        }
        MaskCommand::Preset { preset } => build_preset(preset),
    }
}

fn report(path: &Path, m: &MaskMeasures) {
    eprintln!(
        "wrote {}: opaque {:.1} %, fall-off {:.1} voxels, inscribed tetrahedron edge {:.1} voxels",
        path.display(),
        m.opaque_fraction * 100.0,
        m.falloff_width,
        m.inscribed_tetrahedron
    );
}

fn write_one(output: &Path, volume: Volume) -> Result<()> {
    io::Format::of(output)?;
    io::write_volume(output, &volume)?;
    report(output, &mask::measure(&volume));
    Ok(())
}

fn write_layers(output: &Path, size: usize, falloff: f32, seed: u64, depth: Axis) -> Result<()> {
    let layers: Vec<(Layer, Volume)> =
        Layer::ALL.iter().map(|l| Ok((*l, mask::layered(size, falloff, seed, *l, depth)?))).collect::<Result<_>>()?;
    io::write_folder(output, |dir| {
        for (layer, volume) in &layers {
            io::write_volume(&dir.join(format!("{}.exr", layer.name())), volume)?;
        }
        Ok(())
    })?;
    for (layer, volume) in &layers {
        report(&output.join(format!("{}.exr", layer.name())), &mask::measure(volume));
    }
    Ok(())
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Preset {
    kind: String,
    #[serde(default = "default_size")]
    size: usize,
    #[serde(default = "default_falloff")]
    falloff: f32,
    #[serde(default)]
    seed: u64,
    depth_axis: Option<String>,
    mesh: Option<String>,
}

fn default_size() -> usize {
    64
}

fn default_falloff() -> f32 {
    mask::DEFAULT_FALLOFF
}

fn build_preset(path: &Path) -> Result<()> {
    let text = io::read_text(path, "mask preset")?;
    let quote = io::manifest::has_toml_name(path);
    let p: Preset =
        toml::from_str(&text).map_err(|e| io::manifest::syntax_error(&text, &e, "mask preset", quote).in_file(path))?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let fail = |e: Error| e.in_file(path);
    let (lo, hi) = mask::SIZE;
    io::values::within("size =", p.size, lo, hi).map_err(fail)?;
    io::values::falloff("falloff =", p.falloff).map_err(fail)?;
    let file = folder.join(format!("{stem}.exr"));
    match p.kind.as_str() {
        "splotch" => {
            io::check_output(&file, &[path])?;
            write_one(&file, mask::splotch(p.size, p.falloff, p.seed).map_err(fail)?)
        }
        "layered" => {
            let depth: Axis = p.depth_axis.as_deref().unwrap_or("z").parse().map_err(fail)?;
            io::check_folder_output(&folder.join(&stem), &[path])?;
            write_layers(&folder.join(&stem), p.size, p.falloff, p.seed, depth).map_err(fail)
        }
        "mesh" => {
            let mesh = folder.join(p.mesh.as_deref().ok_or_else(|| Error::file(path, "mesh = \"FILE\" is missing"))?);
            io::check_output(&file, &[path, &mesh])?;
            let shape = io::mesh_file::read_mesh(&mesh)?.oriented();
            write_one(&file, mask::from_mesh(&shape, p.size, p.falloff).map_err(fail)?)
        }
        other => Err(Error::file(path, format!("kind = {other:?} is unknown; allowed: splotch, layered, mesh"))),
    }
}

/// Run `solidtex snapshot VOLUME (-o NAME.snap | --check NAME.snap [--tolerance T])`.
pub fn snapshot(volume: &Path, output: Option<&Path>, check: Option<&Path>, tolerance: f64) -> Result<()> {
    io::values::within("--tolerance", tolerance, 0.0, 1.0e6).map_err(usage)?;
    let v = io::read_volume(volume, io::budget_from_env()?)?;
    match (output, check) {
        (Some(out), None) => {
            io::snapshot_file::write(out, &v)?;
            eprintln!("wrote {}", out.display());
            Ok(())
        }
        (None, Some(snap)) => {
            io::snapshot_file::check(snap, &v, tolerance)?;
            eprintln!("{} matches {}", volume.display(), snap.display());
            Ok(())
        }
        _ => Err(Error::invalid("give either -o NAME.snap (write) or --check NAME.snap (compare)")),
    }
}
