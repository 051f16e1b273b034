//! `solidtex sweep | stamp | scatter | blur | draw`: the hand-made exemplar steps.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::io;
use crate::io::values as parse;
use crate::stamp::{self, MAX_COUNT, Placement, RADIUS, Region, SCALE, Scatter};
use crate::sweep::{self, SKIN_WIDTH, Skin, SkinLook, Sweep};
use crate::volume::{Axis, Volume};
use std::path::{Path, PathBuf};

/// `solidtex sweep`.
#[derive(Debug, clap::Args)]
pub struct SweepArgs {
    /// The cross-section image (its x runs along the first other axis, its y along the second).
    pub image: PathBuf,
    /// Voxels along the sweep axis: 1 to 512 (and within the voxel budget).
    #[arg(long)]
    pub length: usize,
    /// The axis to sweep along.
    #[arg(long, default_value = "x")]
    pub axis: String,
    /// Add a Depth channel running along this in-plane axis (0 at its first face).
    #[arg(long)]
    pub depth_axis: Option<String>,
    /// Displacement noise: AMPLITUDE,FREQUENCY[,JITTER]: amplitude 0 to 64 voxels, frequency
    /// 0 to 64 noise cells across the longest side (whole numbers tile), colour jitter 0 to 1.
    #[arg(long)]
    pub noise: Option<String>,
    /// Skin at the depth-0 face: a colour (R,G,B or #rrggbb) or an image file.
    #[arg(long, requires = "depth_axis")]
    pub skin: Option<String>,
    /// Skin thickness in voxels, 0 to 64.
    #[arg(long, default_value_t = 2.0)]
    pub skin_width: f32,
    /// How much the skin thickness varies, in voxels, 0 to 64.
    #[arg(long, default_value_t = 0.0)]
    pub skin_noise: f32,
    /// A grey relief image the size of the cross-section, swept into a Displacement channel
    /// (0.5 leaves a surface in place; `view --displacement` uses it).
    #[arg(long)]
    pub displacement: Option<PathBuf>,
    /// Seed for the noise (any 64-bit whole number).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Longest sweep, in voxels, as in a manifest.
const MAX_LENGTH: usize = io::manifest::MAX_SIDE;

/// Build the core parameters from the arguments (reads a skin image if one is named).
/// Values out of range are usage errors.
pub fn sweep_params(args: &SweepArgs) -> Result<Sweep> {
    let (axis, depth_axis, noise) = sweep_values(args).map_err(usage)?;
    let skin = args
        .skin
        .as_deref()
        .map(|t| {
            let look = match io::manifest::skin_source("--skin", t, Path::new("")).map_err(usage)? {
                io::manifest::SkinSource::Colour(c) => SkinLook::Colour(c),
                io::manifest::SkinSource::Image(path) => SkinLook::Image(io::read_image(&path)?),
            };
            Ok(Skin { look, width: args.skin_width, width_noise: args.skin_noise })
        })
        .transpose()?;
    let displacement = args.displacement.as_deref().map(io::read_image).transpose()?;
    Ok(Sweep { length: args.length, axis, depth_axis, noise, skin, displacement })
}

/// The axes and noise of a sweep, every number checked against its range.
fn sweep_values(args: &SweepArgs) -> Result<(Axis, Option<Axis>, Option<sweep::Noise>)> {
    let axis: Axis = args.axis.parse()?;
    let depth_axis = args.depth_axis.as_deref().map(str::parse::<Axis>).transpose()?;
    if depth_axis == Some(axis) {
        return Err(Error::invalid(format!(
            "--depth-axis {axis} is the sweep's --axis; depth must run along one of the cross-section's axes"
        )));
    }
    parse::within("--length", args.length, 1, MAX_LENGTH)?;
    parse::within("--skin-width", args.skin_width, SKIN_WIDTH.0, SKIN_WIDTH.1)?;
    parse::within("--skin-noise", args.skin_noise, SKIN_WIDTH.0, SKIN_WIDTH.1)?;
    let noise = args
        .noise
        .as_deref()
        .map(|t| {
            let v = parse::numbers("--noise", t, &[2, 3])?;
            io::manifest::noise("--noise", v[0], v[1], v.get(2).copied().unwrap_or(0.0))
        })
        .transpose()?;
    Ok((axis, depth_axis, noise))
}

/// Run `solidtex sweep`.
pub fn run_sweep(args: &SweepArgs) -> Result<()> {
    sweep_values(args).map_err(usage)?;
    let skin_file = args.skin.as_deref().map(Path::new).filter(|p| p.is_file());
    let inputs: Vec<&Path> =
        [Some(args.image.as_path()), skin_file, args.displacement.as_deref()].into_iter().flatten().collect();
    io::check_output(&args.output, &inputs)?;
    let params = sweep_params(args)?;
    let image = io::read_image(&args.image)?;
    if let (Some(skin), Some(path)) = (&params.skin, skin_file) {
        sweep::check_skin(&image, skin).map_err(|e| e.in_file(path))?;
    }
    if let (Some(relief), Some(path)) = (&params.displacement, args.displacement.as_deref()) {
        sweep::check_relief(&image, relief).map_err(|e| e.in_file(path))?;
    }
    let (dims, channels) = sweep::swept_shape(&image, &params);
    crate::volume::check_size(dims, channels.len(), io::budget_from_env()?)?;
    let volume = sweep::sweep(&image, &params, args.seed).map_err(|e| e.in_file(&args.image))?;
    write(&args.output, &volume)
}

fn write(path: &Path, volume: &Volume) -> Result<()> {
    super::write_volume(path, volume)?;
    let [x, y, z] = volume.dims();
    tell!("wrote {} ({x}x{y}x{z})", path.display());
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
    /// Voxel position X,Y,Z of the mesh origin, each -1000000 to 1000000.
    #[arg(long, allow_hyphen_values = true)]
    pub at: String,
    /// Rotation AX,AY,AZ,DEG: DEG degrees (-360 to 360) about the axis (not all zero).
    #[arg(long, allow_hyphen_values = true)]
    pub rotate: Option<String>,
    /// Voxels per mesh unit: S or SX,SY,SZ, each 0.001 to 10000.
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
    let (placement, colour) = stamp_values(args).map_err(usage)?;
    io::check_edit_output(&args.output, &args.volume, &[&args.mesh])?;
    let mesh = read_seed(&args.mesh)?;
    let mut volume = load(&args.volume)?;
    let done = stamp::stamp(&mut volume, &mesh, &placement, colour).map_err(|e| about(e, &args.mesh, &args.volume))?;
    tell!("stamped {} voxels ({:.1} voxels of volume)", done.voxels, done.volume);
    write(&args.output, &volume)
}

/// The placement and colour of a stamp, every number checked against its range.
fn stamp_values(args: &StampArgs) -> Result<(Placement, [f32; 3])> {
    let placement = Placement {
        at: parse::point("--at", &args.at)?,
        rotation: args.rotate.as_deref().map(|r| parse::rotation("--rotate", r)).transpose()?.unwrap_or_default(),
        scale: parse::scale("--scale", &args.scale, SCALE.0, SCALE.1)?,
    };
    Ok((placement, parse::colour("--color", &args.color)?))
}

/// An error of stamping `mesh` into the volume read from `volume`, naming both files.
fn about(error: Error, mesh: &Path, volume: &Path) -> Error {
    match error {
        Error::Invalid(message) => Error::file(mesh, format!("{message} (stamping into {})", volume.display())),
        other => other,
    }
}

/// A seed mesh, oriented; its warnings go to stderr.
fn read_seed(path: &Path) -> Result<crate::mesh::Mesh> {
    crate::library::recipe::read_seed(path, &super::Stderr)
}

/// `solidtex scatter`.
#[derive(Debug, clap::Args)]
pub struct ScatterArgs {
    /// The volume to stamp into.
    pub volume: PathBuf,
    /// The seed mesh (OBJ, STL, PLY).
    pub mesh: PathBuf,
    /// How many seeds, 1 to 2000.
    #[arg(long)]
    pub count: usize,
    /// Where: `box:X0,Y0,Z0,X1,Y1,Z1` (voxels, each -1000000 to 1000000) or `depth:FROM,TO`
    /// (Depth channel values, 0 <= FROM <= TO <= 1).
    #[arg(long, allow_hyphen_values = true)]
    pub region: Option<String>,
    /// Voxels per mesh unit, drawn uniformly from MIN..MAX, both 0.001 to 10000.
    #[arg(long, default_value = "1")]
    pub scale: String,
    /// Fill colour R,G,B (0..1) or #rrggbb.
    #[arg(long)]
    pub color: String,
    /// Seed for positions, orientations and scales (any 64-bit whole number).
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
    let (colour, scale) = scatter_values(args).map_err(usage)?;
    io::check_edit_output(&args.output, &args.volume, &[&args.mesh])?;
    let mesh = read_seed(&args.mesh)?;
    let mut volume = load(&args.volume)?;
    let params = Scatter {
        count: args.count,
        region: region(args.region.as_deref(), volume.dims()).map_err(usage)?,
        scale,
        colour,
        attempts: 200,
    };
    stamp::check_region_fits(&volume, params.region).map_err(|e| e.in_file(&args.volume))?;
    let done =
        stamp::scatter(&mut volume, &mesh, &params, args.seed).map_err(|e| about(e, &args.mesh, &args.volume))?;
    tell_scattered(&done, args.count);
    if done.placed.is_empty() {
        let fix = if done.too_small > 0 { "a larger --scale" } else { "a smaller --scale or a larger region" };
        return Err(Error::invalid(format!(
            "placed none of the {} seeds, so {} would be {} unchanged: nothing written ({fix} places them)",
            args.count,
            args.output.display(),
            args.volume.display()
        )));
    }
    write(&args.output, &volume)
}

/// How many seeds a scatter placed, and warnings for those it did not: too small to
/// change a voxel, or no room.
fn tell_scattered(done: &stamp::Scattered, count: usize) {
    let placed = done.placed.len();
    if done.too_small > 0 {
        tell!(
            "warning: {} of {count} seeds were smaller than a voxel and changed nothing; a larger --scale places them",
            done.too_small
        );
    }
    let no_room = count - placed - done.too_small;
    if no_room > 0 {
        tell!("warning: placed {placed} of {count} seeds: no room for {no_room} more without overlaps");
    }
    tell!("placed {placed} seeds ({} positions rejected)", done.rejected);
}

/// The colour and scale range of a scatter, every number checked against its range.
fn scatter_values(args: &ScatterArgs) -> Result<([f32; 3], (f32, f32))> {
    parse::within("--count", args.count, 1, MAX_COUNT)?;
    if let Some(text) = &args.region {
        region(Some(text), [1; 3])?;
    }
    Ok((parse::colour("--color", &args.color)?, parse::range("--scale", &args.scale, SCALE.0, SCALE.1)?))
}

/// `solidtex blur`.
#[derive(Debug, clap::Args)]
pub struct BlurArgs {
    /// The volume to blur.
    pub volume: PathBuf,
    /// Centre X,Y,Z in voxels, each -1000000 to 1000000.
    #[arg(long, allow_hyphen_values = true)]
    pub at: String,
    /// Radius in voxels, 0.1 to 64.
    #[arg(long)]
    pub radius: f32,
    /// How much at the centre, 0 to 1.
    #[arg(long, default_value_t = 1.0)]
    pub strength: f32,
    /// The volume file to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Run `solidtex blur`.
pub fn run_blur(args: &BlurArgs) -> Result<()> {
    let at = blur_values(args).map_err(usage)?;
    io::check_edit_output(&args.output, &args.volume, &[])?;
    let mut volume = load(&args.volume)?;
    let changed = stamp::blur(&mut volume, at, args.radius, args.strength).map_err(|e| e.in_file(&args.volume))?;
    if args.strength == 0.0 {
        tell!("warning: --strength 0 blurs nothing; the volume is written unchanged");
    } else {
        tell!("blurred {changed} voxels");
    }
    write(&args.output, &volume)
}

/// The centre of a blur, with the radius and strength checked against their ranges.
fn blur_values(args: &BlurArgs) -> Result<glam::Vec3> {
    parse::within("--radius", args.radius, RADIUS.0, RADIUS.1)?;
    parse::within("--strength", args.strength, 0.0, 1.0)?;
    parse::point("--at", &args.at)
}

/// `solidtex draw`.
#[derive(Debug, clap::Args)]
pub struct DrawArgs {
    /// kiwi, carrot, trunk or bark (a cross-section or relief image), fuzz or bark-skin (a
    /// skin for `solidtex surface`), seed or bubble (a mesh
    /// to stamp), a closed shape to fill (fruit, pipe, log, block or vase), or cake (a folder of
    /// layer meshes and their fill specs).
    pub what: String,
    /// Image size WxH, each side 2 to 4096 (columns around the object, rows from the outside
    /// in) [default: 64x64]. Only for images: meshes come at their own size.
    #[arg(long)]
    pub size: Option<String>,
    /// Seed for the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The PNG (cross-section) or mesh file (.obj, .stl, .ply) to write; for cake, the
    /// folder to write (made, or replaced if solidtex wrote it).
    #[arg(short, long)]
    pub output: PathBuf,
    /// For cake: the library the fill specs name.
    #[arg(long, default_value = "exemplars/library.toml")]
    pub library: PathBuf,
    /// For cake: the folder the fill specs build the library into.
    #[arg(long, default_value = "out")]
    pub built: PathBuf,
}

/// `solidtex draw cake`: the layer meshes and one fill spec per layer, in a folder.
fn draw_cake(args: &DrawArgs) -> Result<()> {
    io::check_folder_output(&args.output, &[])?;
    let here = std::env::current_dir().map_err(|e| Error::io(Path::new("."), e))?;
    let (library, built) = (here.join(&args.library), here.join(&args.built));
    if !library.is_file() {
        return Err(Error::file(&library, "the library for the cake's fill specs does not exist (--library)"));
    }
    // TOML strings (quoted and escaped as TOML wants); a path that is not UTF-8 cannot be one
    let quoted = |p: &Path| {
        p.to_str()
            .map(|s| toml::Value::String(s.to_string()).to_string())
            .ok_or_else(|| Error::file(p, "is not UTF-8, so a fill spec cannot name it"))
    };
    let (library, built) = (quoted(&library)?, quoted(&built)?);
    let layers = crate::mesh::shapes::cake();
    io::write_folder(&args.output, |dir| {
        for layer in &layers {
            io::mesh_file::write_mesh(&dir.join(format!("{}.obj", layer.name)), &layer.mesh)?;
            let spec = format!(
                "# The cake's {name} layer, written by `solidtex draw cake`. Fill it with\n\
                 #   solidtex fill {name}.obj --spec {name}.toml -o {name}.lst\n\
                 exemplar = \"{exemplar}\"\nlibrary = {library}\nbuilt = {built}\ntype = \"0\"\n\
                 scale = {scale}\ntets = {tets}\nseed = 1\n",
                name = layer.name,
                exemplar = layer.exemplar,
                scale = layer.scale,
                tets = layer.tets,
            );
            io::write_bytes(&dir.join(format!("{}.toml", layer.name)), spec.as_bytes())?;
        }
        Ok(())
    })?;
    let names: Vec<&str> = layers.iter().map(|l| l.name).collect();
    tell!("wrote {} (layers {}, each a mesh and a fill spec)", args.output.display(), names.join(", "));
    let dir = args.output.display();
    tell!(
        "  fill each:  for l in {}; do solidtex fill {dir}/$l.obj --spec {dir}/$l.toml -o {dir}/$l.lst; done",
        names.join(" ")
    );
    let models: Vec<String> = names.iter().map(|n| format!("{dir}/{n}.lst")).collect();
    tell!("  then:       solidtex cut {} --plane 0,0.5,0,0,0,1 -o cake_cut.png", models.join(" "));
    Ok(())
}

/// `WxH` with each side 2 to 4096 pixels.
fn draw_size(text: &str) -> Result<(usize, usize)> {
    let bad = || {
        let what = if text.contains('x') { "is out of range" } else { "is not WxH (two sides, e.g. 64x64)" };
        Error::invalid(format!("--size {text:?} {what}; allowed: WxH, each side 2 to 4096 pixels"))
    };
    let parts: Vec<usize> =
        text.split('x').map(|p| p.trim().parse::<usize>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    match parts.as_slice() {
        [w, h] if (2..=4096).contains(w) && (2..=4096).contains(h) => Ok((*w, *h)),
        _ => Err(bad()),
    }
}

/// Run `solidtex draw`.
pub fn run_draw(args: &DrawArgs) -> Result<()> {
    let mesh_wanted = args.what == "seed" || args.what == "bubble" || crate::mesh::shapes::named(&args.what).is_some();
    if let (true, Some(size)) = (mesh_wanted || args.what == "cake", &args.size) {
        return Err(Error::usage(format!(
            "--size {size} sets an image's size; {} is a mesh, drawn at its own size (scale it where it is used, e.g. \
             stamp --scale)",
            args.what
        )));
    }
    if args.what == "cake" {
        return draw_cake(args);
    }
    if mesh_wanted {
        io::guard::file_output(&args.output, &[], &["obj", "stl", "ply"], "a mesh")?;
    }
    if args.what == "seed" || args.what == "bubble" {
        let mesh = match args.what.as_str() {
            "seed" => crate::sections::seed_mesh(32, 32)?,
            _ => crate::mesh::shapes::ellipsoid(glam::Vec3::ONE, 8, 12),
        };
        io::mesh_file::write_mesh(&args.output, &mesh)?;
        tell!("wrote {} ({} triangles)", args.output.display(), mesh.triangles.len());
        return Ok(());
    }
    if let Some(mesh) = crate::mesh::shapes::named(&args.what) {
        io::mesh_file::write_mesh(&args.output, &mesh)?;
        tell!("wrote {} ({} triangles)", args.output.display(), mesh.triangles.len());
        return Ok(());
    }
    if !crate::sections::NAMES.contains(&args.what.as_str()) {
        let meshes = ["seed", "bubble"].into_iter().chain(crate::mesh::shapes::NAMES).chain(["cake"]);
        return Err(Error::usage(format!(
            "unknown drawing {:?}; allowed: {} (images), or {} (meshes)",
            args.what,
            crate::sections::NAMES.join(", "),
            meshes.collect::<Vec<_>>().join(", ")
        )));
    }
    let (w, h) = draw_size(args.size.as_deref().unwrap_or("64x64")).map_err(usage)?;
    let image = crate::sections::draw(&args.what, w, h, args.seed).map_err(usage)?;
    io::guard::png_output(&args.output, &[])?;
    io::write_image(&args.output, &image)?;
    tell!("wrote {} ({w}x{h})", args.output.display());
    Ok(())
}
