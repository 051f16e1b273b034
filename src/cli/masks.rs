//! `solidtex mask ...`: splotch, layered and mesh masks, and mask presets.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::io;
use crate::mask::{self, Layer, MaskMeasures};
use crate::volume::{Axis, Volume};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The options every mask shares.
#[derive(Debug, clap::Args)]
pub struct Shape {
    /// Side of the cubic mask in voxels, 6 to 512.
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
    tell!(
        "wrote {}: opaque {:.1} %, fall-off {:.1} voxels, inscribed tetrahedron edge {:.1} voxels",
        path.display(),
        m.opaque_fraction * 100.0,
        m.falloff_width,
        m.inscribed_tetrahedron
    );
    if m.opaque_fraction < THIN_CORE {
        tell!(
            "warning: {} is opaque in under {:.0} % of its voxels: a patch with it covers a model only where several \
             add up their soft alpha (more, smaller patches); a smaller --falloff leaves a larger opaque core",
            path.display(),
            THIN_CORE * 100.0
        );
    }
}

/// An opaque share under this (1 %) is warned about: the soft band takes nearly the whole
/// shape (a splotch of size 64 at fall-off 0.4 keeps a handful of opaque voxels).
const THIN_CORE: f64 = 0.01;

fn write_one(output: &Path, volume: Volume) -> Result<()> {
    io::Format::of(output)?;
    super::write_volume(output, &volume)?;
    report(output, &mask::measure(&volume));
    Ok(())
}

fn write_layers(output: &Path, size: usize, falloff: f32, seed: u64, depth: Axis) -> Result<()> {
    let layers: Vec<(Layer, Volume)> =
        Layer::ALL.iter().map(|l| Ok((*l, mask::layered(size, falloff, seed, *l, depth)?))).collect::<Result<_>>()?;
    io::write_folder(output, |dir| {
        for (layer, volume) in &layers {
            super::write_volume(&dir.join(format!("{}.exr", layer.name())), volume)?;
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
            beside_preset(&file, &[path])?;
            write_one(&file, io::guard::seal_volume(mask::splotch(p.size, p.falloff, p.seed).map_err(fail)?))
        }
        "layered" => {
            let depth: Axis = p.depth_axis.as_deref().unwrap_or("z").parse().map_err(fail)?;
            io::check_folder_output(&folder.join(&stem), &[path])?;
            write_layers(&folder.join(&stem), p.size, p.falloff, p.seed, depth).map_err(fail)
        }
        "mesh" => {
            let mesh = folder.join(p.mesh.as_deref().ok_or_else(|| Error::file(path, "mesh = \"FILE\" is missing"))?);
            beside_preset(&file, &[path, &mesh])?;
            let shape = io::mesh_file::read_mesh(&mesh)
                .map_err(|e| Error::file(path, format!("mesh = {:?}: {e}", p.mesh.as_deref().unwrap_or_default())))?
                .oriented();
            write_one(&file, io::guard::seal_volume(mask::from_mesh(&shape, p.size, p.falloff).map_err(fail)?))
        }
        other => Err(Error::file(path, format!("kind = {other:?} is unknown; allowed: splotch, layered, mesh"))),
    }
}

/// The mask a preset writes beside itself replaces only a mask solidtex wrote there and
/// nobody changed since.
fn beside_preset(file: &Path, inputs: &[&Path]) -> Result<()> {
    io::check_output(file, inputs)?;
    io::guard::side_file(file, "the preset writes its mask there: move that file away or rename the preset")
}
