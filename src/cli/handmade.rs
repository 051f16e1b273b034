//! `solidtex sweep | stamp | scatter | blur | draw`: the hand-made exemplar steps.

use crate::error::{Error, Result};
use crate::io;
use crate::io::values as parse;
use crate::stamp::{self, Placement, Region, Scatter};
use crate::sweep::{self, Noise, Skin, SkinLook, Sweep};
use crate::volume::{Axis, Volume};
use std::path::{Path, PathBuf};

/// `solidtex sweep`.
#[derive(Debug, clap::Args)]
pub struct SweepArgs {
    /// The cross-section image (its x runs along the first other axis, its y along the second).
    pub image: PathBuf,
    /// Voxels along the sweep axis.
    #[arg(long)]
    pub length: usize,
    /// The axis to sweep along.
    #[arg(long, default_value = "x")]
    pub axis: String,
    /// Add a Depth channel running along this in-plane axis (0 at its first face).
    #[arg(long)]
    pub depth_axis: Option<String>,
    /// Displacement noise: AMPLITUDE,FREQUENCY[,JITTER] (voxels, cells per side, colour).
    #[arg(long)]
    pub noise: Option<String>,
    /// Skin at the depth-0 face: a colour (R,G,B or #rrggbb) or an image file.
    #[arg(long, requires = "depth_axis")]
    pub skin: Option<String>,
    /// Skin thickness in voxels.
    #[arg(long, default_value_t = 2.0)]
    pub skin_width: f32,
    /// How much the skin thickness varies, in voxels.
    #[arg(long, default_value_t = 0.0)]
    pub skin_noise: f32,
    /// Seed for the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Build the core parameters from the arguments (reads a skin image if one is named).
pub fn sweep_params(args: &SweepArgs) -> Result<Sweep> {
    let axis: Axis = args.axis.parse()?;
    let depth_axis = args.depth_axis.as_deref().map(str::parse::<Axis>).transpose()?;
    let noise = args
        .noise
        .as_deref()
        .map(|t| {
            let v = parse::numbers("--noise", t, &[2, 3])?;
            Ok::<_, Error>(Noise { amplitude: v[0], frequency: v[1], jitter: v.get(2).copied().unwrap_or(0.0) })
        })
        .transpose()?;
    let skin = args
        .skin
        .as_deref()
        .map(|t| {
            let look = match parse::colour("--skin", t) {
                Ok(c) => SkinLook::Colour(c),
                Err(_) if Path::new(t).exists() => SkinLook::Image(io::read_image(Path::new(t))?),
                Err(e) => return Err(Error::invalid(format!("{e}; or name an image file that exists"))),
            };
            Ok(Skin { look, width: args.skin_width, width_noise: args.skin_noise })
        })
        .transpose()?;
    Ok(Sweep { length: args.length, axis, depth_axis, noise, skin })
}

/// Run `solidtex sweep`.
pub fn run_sweep(args: &SweepArgs) -> Result<()> {
    io::Format::of(&args.output)?;
    io::check_folder(&args.output)?;
    let params = sweep_params(args)?;
    let image = io::read_image(&args.image)?;
    let volume = sweep::sweep(&image, &params, args.seed).map_err(|e| e.in_file(&args.image))?;
    write(&args.output, &volume)
}

fn write(path: &Path, volume: &Volume) -> Result<()> {
    io::write_volume(path, volume)?;
    let [x, y, z] = volume.dims();
    eprintln!("wrote {} ({x}x{y}x{z})", path.display());
    Ok(())
}

fn load(path: &Path) -> Result<Volume> {
    io::read_volume(path, io::budget_from_env()?)
}

/// `solidtex stamp`.
#[derive(Debug, clap::Args)]
pub struct StampArgs {
    /// The volume to stamp into.
    pub volume: PathBuf,
    /// The seed mesh (OBJ, STL, PLY).
    pub mesh: PathBuf,
    /// Voxel position X,Y,Z of the mesh origin.
    #[arg(long)]
    pub at: String,
    /// Rotation AX,AY,AZ,DEG (degrees about the axis).
    #[arg(long)]
    pub rotate: Option<String>,
    /// Voxels per mesh unit: S or SX,SY,SZ.
    #[arg(long, default_value = "1")]
    pub scale: String,
    /// Fill colour R,G,B (0..1) or #rrggbb.
    #[arg(long)]
    pub color: String,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Run `solidtex stamp`.
pub fn run_stamp(args: &StampArgs) -> Result<()> {
    io::Format::of(&args.output)?;
    io::check_folder(&args.output)?;
    let placement = Placement {
        at: parse::point("--at", &args.at)?,
        rotation: args.rotate.as_deref().map(|r| parse::rotation("--rotate", r)).transpose()?.unwrap_or_default(),
        scale: parse::scale("--scale", &args.scale)?,
    };
    let colour = parse::colour("--color", &args.color)?;
    let mesh = read_seed(&args.mesh)?;
    let mut volume = load(&args.volume)?;
    let done = stamp::stamp(&mut volume, &mesh, &placement, colour)?;
    eprintln!("stamped {} voxels ({:.1} voxels of volume)", done.voxels, done.volume);
    write(&args.output, &volume)
}

/// A seed mesh, oriented, with a warning when it is not closed.
pub fn read_seed(path: &Path) -> Result<crate::mesh::Mesh> {
    let mesh = io::mesh_file::read_mesh(path)?;
    let dropped = mesh.dropped_degenerate();
    if dropped > 0 {
        eprintln!(
            "warning: {}: dropped {dropped} degenerate triangle(s) (zero area or a repeated corner)",
            path.display()
        );
    }
    let open = mesh.boundary_edges();
    if open > 0 {
        eprintln!(
            "warning: {}: the mesh has {open} boundary edge(s) (open or non-manifold); inside is decided by winding number",
            path.display()
        );
    }
    Ok(mesh.oriented())
}

/// `solidtex scatter`.
#[derive(Debug, clap::Args)]
pub struct ScatterArgs {
    /// The volume to stamp into.
    pub volume: PathBuf,
    /// The seed mesh (OBJ, STL, PLY).
    pub mesh: PathBuf,
    /// How many seeds.
    #[arg(long)]
    pub count: usize,
    /// Where: `box:X0,Y0,Z0,X1,Y1,Z1` (voxels) or `depth:FROM,TO` (Depth channel values).
    #[arg(long)]
    pub region: Option<String>,
    /// Voxels per mesh unit, drawn uniformly from MIN..MAX.
    #[arg(long, default_value = "1")]
    pub scale: String,
    /// Fill colour R,G,B (0..1) or #rrggbb.
    #[arg(long)]
    pub color: String,
    /// Seed for positions, orientations and scales.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Parse `box:...` or `depth:...`; without one, the whole volume.
pub fn region(text: Option<&str>, dims: [usize; 3]) -> Result<Region> {
    match text {
        Some(t) => io::manifest::region(t).map_err(|e| Error::invalid(format!("--{e}"))),
        None => Ok(Region::Box(glam::Vec3::ZERO, glam::Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32))),
    }
}

/// Run `solidtex scatter`.
pub fn run_scatter(args: &ScatterArgs) -> Result<()> {
    io::Format::of(&args.output)?;
    io::check_folder(&args.output)?;
    let colour = parse::colour("--color", &args.color)?;
    let scale = parse::range("--scale", &args.scale)?;
    let mesh = read_seed(&args.mesh)?;
    let mut volume = load(&args.volume)?;
    let params = Scatter {
        count: args.count,
        region: region(args.region.as_deref(), volume.dims())?,
        scale,
        colour,
        attempts: 200,
    };
    let done = stamp::scatter(&mut volume, &mesh, &params, args.seed)?;
    if done.placed.len() < args.count {
        eprintln!(
            "warning: placed {} of {} seeds: no room for the rest without overlaps",
            done.placed.len(),
            args.count
        );
    }
    eprintln!("placed {} seeds ({} positions rejected)", done.placed.len(), done.rejected);
    write(&args.output, &volume)
}

/// `solidtex blur`.
#[derive(Debug, clap::Args)]
pub struct BlurArgs {
    /// The volume to blur.
    pub volume: PathBuf,
    /// Centre X,Y,Z in voxels.
    #[arg(long)]
    pub at: String,
    /// Radius in voxels.
    #[arg(long)]
    pub radius: f32,
    /// How much at the centre, 0..1.
    #[arg(long, default_value_t = 1.0)]
    pub strength: f32,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Run `solidtex blur`.
pub fn run_blur(args: &BlurArgs) -> Result<()> {
    io::Format::of(&args.output)?;
    io::check_folder(&args.output)?;
    let at = parse::point("--at", &args.at)?;
    let mut volume = load(&args.volume)?;
    let changed = stamp::blur(&mut volume, at, args.radius, args.strength)?;
    eprintln!("blurred {changed} voxels");
    write(&args.output, &volume)
}

/// `solidtex draw`.
#[derive(Debug, clap::Args)]
pub struct DrawArgs {
    /// kiwi, carrot or trunk (a cross-section image), seed (a seed mesh), or a closed shape
    /// to fill: fruit, pipe, log or block.
    pub what: String,
    /// Image size WxH (columns around the object, rows from the outside in).
    #[arg(long, default_value = "64x64")]
    pub size: String,
    /// Seed for the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The PNG (cross-section) or mesh file (.obj, .stl, .ply) to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Run `solidtex draw`.
pub fn run_draw(args: &DrawArgs) -> Result<()> {
    io::check_folder(&args.output)?;
    if args.what == "seed" {
        let mesh = crate::sections::seed_mesh(32, 32)?;
        io::mesh_file::write_mesh(&args.output, &mesh)?;
        eprintln!("wrote {} ({} triangles)", args.output.display(), mesh.triangles.len());
        return Ok(());
    }
    if let Some(mesh) = crate::mesh::shapes::named(&args.what) {
        io::mesh_file::write_mesh(&args.output, &mesh)?;
        eprintln!("wrote {} ({} triangles)", args.output.display(), mesh.triangles.len());
        return Ok(());
    }
    let parts = parse::numbers("--size", &args.size.replace('x', ","), &[2])?;
    let (w, h) = (parts[0] as usize, parts[1] as usize);
    if w < 2 || h < 2 || w > 4096 || h > 4096 {
        return Err(Error::invalid(format!("--size {:?}: each side must be 2..=4096 pixels", args.size)));
    }
    let image = crate::sections::draw(&args.what, w, h, args.seed)
        .map_err(|e| Error::invalid(format!("{e}, or seed, fruit, pipe, log, block")))?;
    io::write_image(&args.output, &image)?;
    eprintln!("wrote {} ({w}x{h})", args.output.display());
    Ok(())
}
