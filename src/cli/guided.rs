//! `solidtex field` and `solidtex guided`: the frame field of sketch-guided solid
//! texturing drawn on a cut, and a solid texture synthesized along it (a cut on demand, or
//! the whole solid).

use super::commands::usage;
use crate::error::{Error, Result};
use crate::fill::render::View;
use crate::fill::tets::TetMesh;
use crate::guided::field::{FrameField, sketched_frames, solve, streamlines};
use crate::guided::regions::Regions;
use crate::guided::solid::{self, Domain};
use crate::io::guided_cache::{self, Bricks, Cached};
use crate::io::{self, fill_spec, mesh_file};
use crate::mesh::{Mesh, closest_on_segment};
use crate::synth::coords::{self as synth, Exemplars, Options, Setup, Synthesized};
use crate::synth::cube;
use crate::synth::region::{BRICK, Mask, Sparse};
use crate::volume::{Channel, Image2d};
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The arguments of `solidtex field`.
#[derive(Debug, clap::Args)]
pub struct FieldArgs {
    /// The closed mesh (.obj, .stl, .ply).
    pub mesh: PathBuf,
    /// The fill spec whose [[direction]] strokes and [depth] constraints give the frames
    /// (the same file `solidtex fill` reads).
    #[arg(long)]
    pub spec: PathBuf,
    /// The cut PX,PY,PZ,NX,NY,NZ (a point and a normal; default: through the centre,
    /// normal z).
    #[arg(long, allow_hyphen_values = true)]
    pub plane: Option<String>,
    /// Picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// Override the spec's target tet count (100 to 200000).
    #[arg(long)]
    pub tets: Option<usize>,
    /// The PNG to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// A model's frame field from a fill spec: the surface, its tet mesh, the field, and how
/// many frames the strokes gave and how long the solve took (ms).
struct Guide {
    surface: Mesh,
    tets: TetMesh,
    field: FrameField,
    depth: Vec<(Vec3, f32)>,
    /// The spec's depth axes (polylines at depth 1).
    axes: Vec<Vec<Vec3>>,
    /// The spec's texture axes, when it gives them (`axes`).
    texture_axes: Option<[crate::volume::Axis; 2]>,
    frames: usize,
    solve_ms: f64,
    /// The spec itself (its regions and library).
    spec: crate::fill::spec::FillSpec,
}

fn guide(mesh: &Path, spec: &Path, tets: Option<usize>) -> Result<Guide> {
    let mut fill = fill_spec::read_fill_spec(spec)?;
    fill.tets = tets.unwrap_or(fill.tets);
    let surface = mesh_file::read_mesh(mesh)?.canonical();
    // guided synthesis reads the depth for any exemplar (a layered section follows it)
    let (tet_mesh, _) = crate::fill::tetrahedralize(&surface, &fill, true).map_err(|e| e.in_file(mesh))?;
    let constraints = crate::fill::spec::constraints(&fill, &surface, 1.0).map_err(|e| e.in_file(spec))?;
    let started = Instant::now();
    let frames = sketched_frames(&constraints.directions, &constraints.depth).map_err(|e| e.in_file(spec))?;
    let field = solve(&tet_mesh, &frames)?;
    let solve_ms = started.elapsed().as_secs_f64() * 1000.0;
    let (axes, texture_axes) = (fill.depth.axes.clone(), fill.axes);
    let depth = constraints.depth;
    let frames = frames.len();
    Ok(Guide { surface, tets: tet_mesh, field, depth, axes, texture_axes, frames, solve_ms, spec: fill })
}

fn check_tets(label: &str, tets: Option<usize>) -> Result<()> {
    if let Some(tets) = tets {
        io::values::within(label, tets, *fill_spec::TETS.start(), *fill_spec::TETS.end())?;
    }
    Ok(())
}

/// Run `solidtex field`.
pub fn run(args: &FieldArgs) -> Result<()> {
    let checks = || -> Result<Option<(Vec3, Vec3)>> {
        io::values::within("--size", args.size, 8, 4096)?;
        check_tets("--tets", args.tets)?;
        args.plane.as_deref().map(|text| super::fill::plane("--plane", text)).transpose()
    };
    let plane = checks().map_err(usage)?;
    io::guard::png_output(&args.output, &[&args.mesh, &args.spec])?;
    let g = guide(&args.mesh, &args.spec, args.tets)?;
    let bounds = g.surface.bounds();
    let (point, normal) = plane.unwrap_or(((bounds.0 + bounds.1) / 2.0, Vec3::Z));
    let view = View::framing(bounds, point, normal, args.size)?;
    let inside = crate::fill::render::inside_surface(&g.surface, &view);
    io::write_rgb8(&args.output, &streamlines(&g.tets, &g.field, &view, &inside))?;
    if !inside.iter().any(|i| *i) {
        tell!("warning: the plane misses the model; the picture is black");
    }
    tell!(
        "wrote {} ({} tets, {} sketched frames; the field solved in {:.0} ms)",
        args.output.display(),
        g.tets.tets.len(),
        g.frames,
        g.solve_ms
    );
    let turns = field_turns(&g, (point, normal))?;
    tell!(
        "  as `guided --res {TURN_RES}` reads it, the frames turn by at most {:.1}° between neighbouring voxels of the cut; \
         {} of {} pairs by more than {TURN_LIMIT}° (pairs within two voxels of a depth axis, or of its ridge past its ends, left out)",
        turns.largest,
        turns.over,
        turns.pairs
    );
    Ok(())
}

/// The grid resolution and the largest turn `field` reports the frames' turns at.
const TURN_RES: usize = 256;
const TURN_LIMIT: f32 = 30.0;

/// How sharply the field, sampled as `guided --res 256` samples it, turns between
/// neighbouring voxels of the cut through `plane` (point, normal) inside the model, away
/// from the spec's depth axes: the cut sampled at one point per voxel, whatever the
/// picture's size.
fn field_turns(g: &Guide, (point, normal): (Vec3, Vec3)) -> Result<crate::guided::field::Turns> {
    let domain = Domain::around(g.surface.bounds(), TURN_RES)?;
    let frames = solid::frames_over(&g.tets, &g.field, &domain, &g.depth, &g.axes)?;
    let framed = View::framing(g.surface.bounds(), point, normal, 8)?;
    let side = framed.right.length() * framed.width as f32;
    let per_voxel = ((side / domain.voxel).ceil() as usize).clamp(8, 8192);
    let view = &View::framing(g.surface.bounds(), point, normal, per_voxel)?;
    let inside = crate::fill::render::field_cut(&g.tets, &vec![0.0; g.tets.vertices.len()], view);
    let to_grid = |p: Vec3| (p - domain.origin) / domain.voxel - 0.5;
    let points: Vec<Option<Vec3>> = (0..view.width * view.height)
        .map(|i| inside[i].map(|_| to_grid(view.point(i % view.width, i / view.width))))
        .collect();
    let reach = domain.voxel * domain.dims.iter().sum::<usize>() as f32;
    let ridges: Vec<Vec<Vec3>> = g.axes.iter().map(|line| ridge(line, reach)).collect();
    let near_axis = |p: Vec3| {
        let at = domain.origin + (p + 0.5) * domain.voxel;
        ridges
            .iter()
            .any(|line| line.windows(2).any(|w| at.distance(closest_on_segment(at, w[0], w[1])) <= 2.0 * domain.voxel))
    };
    Ok(crate::guided::field::turns(&frames, &points, view.width, TURN_LIMIT, near_axis))
}

/// A depth axis and the ridge of the depth past its ends: its first and last segments
/// carried on by `reach` (out of the model), where frames turning around the axis go on
/// turning around the ridge.
fn ridge(line: &[Vec3], reach: f32) -> Vec<Vec3> {
    let (Some(&[a, b]), Some(&[c, d])) = (line.first_chunk::<2>(), line.last_chunk::<2>()) else {
        return line.to_vec();
    };
    let before = a + (a - b).normalize_or_zero() * reach;
    let after = d + (d - c).normalize_or_zero() * reach;
    std::iter::once(before).chain(line.iter().copied()).chain(std::iter::once(after)).collect()
}

/// The arguments of `solidtex guided`.
#[derive(Debug, clap::Args)]
pub struct GuidedArgs {
    /// The closed mesh (.obj, .stl, .ply).
    pub mesh: PathBuf,
    /// The fill spec whose strokes and depth give the frame field (as for `solidtex field`).
    #[arg(long)]
    pub spec: PathBuf,
    /// The exemplar: the cross-section orthogonal to the frame's x axis (alone, all three).
    /// Not with a spec whose [[region]] entries choose the exemplars by depth.
    #[arg(long)]
    pub exemplar: Option<PathBuf>,
    /// A solid exemplar instead: a volume (e.g. a built library exemplar) that is a cube
    /// whose side halves evenly to at least 16 voxels, read along the field as it is; with
    /// --layered, a volume with a Depth channel (a built cross-section: its skin, rings,
    /// seeds), whose central slices along its depth are followed as layered exemplars
    #[arg(long, conflicts_with_all = ["exemplar", "mask", "planes", "ey", "ez", "max_exemplar"])]
    pub solid: Option<PathBuf>,
    /// Ey, Ez and shrinking (default: exemplars shrunk to 128 pixels).
    #[command(flatten)]
    pub others: super::synth::OtherExemplars,
    /// A feature mask for the exemplar: a grey image of its size, light on the structures
    /// to keep whole (e.g. the mortar between bricks); matched with the colours, not shown.
    #[arg(long)]
    pub mask: Option<PathBuf>,
    /// The feature mask of --ey (needed when --mask and --ey are given).
    #[arg(long, requires = "mask", requires = "ey")]
    pub ey_mask: Option<PathBuf>,
    /// The feature mask of --ez (needed when --mask and --ez are given).
    #[arg(long, requires = "mask", requires = "ez")]
    pub ez_mask: Option<PathBuf>,
    /// Layered exemplars: their rows run along depth (frame z: the outside in), like the
    /// library's cross-sections; the plane along a layer is left free. The rows are fitted
    /// to the voxels the model's depth spans; levels past √2 times the exemplar's own rows
    /// only magnify it (docs/guided.md).
    #[arg(long)]
    pub layered: bool,
    /// Match the three planes' 2D exemplars directly (Zhang et al.'s coordinate triples)
    /// instead of a solid cube synthesized from them first: softer, but a single grooved
    /// exemplar keeps its grooves longer (docs/guided.md; the way --layered and --mask go)
    #[arg(long)]
    pub planes: bool,
    /// Voxels along the longest side of the grid around the model (16 to 1024); one
    /// exemplar pixel spans one voxel.
    #[arg(long, default_value_t = 128)]
    pub res: usize,
    /// Neighbourhood side at the coarsest level (odd, 3 to 11): 7 or 9 keep long
    /// structures (grooves, grain) longer, a little less sharp (docs/guided.md).
    #[arg(long, default_value_t = DEFAULT_N)]
    pub coarse_n: usize,
    /// Neighbourhood side at the finer levels (odd, 3 to 11): Zhang et al. use 9 with
    /// `--coarse-n 7`, at about three times the time (docs/guided.md).
    #[arg(long, default_value_t = DEFAULT_N)]
    pub n: usize,
    /// Synthesize only the cut PX,PY,PZ,NX,NY,NZ (a point and a normal) and write it as a
    /// PNG; without it, the whole solid is written as a volume.
    #[arg(long, allow_hyphen_values = true)]
    pub cut: Option<String>,
    /// The cut's picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 256, requires = "cut")]
    pub size: usize,
    /// With --cut: a folder keeping what cuts of the same inputs computed (the levels below
    /// the finest over the whole model when they fit in a quarter of --cache-mb, and each
    /// cut's bricks), so that a later cut reads them instead of computing them.
    #[arg(long, requires = "cut")]
    pub cache: Option<PathBuf>,
    /// Most megabytes the cache holds in memory (16 to 65536); the levels below the finest
    /// first, then the bricks of the latest cuts.
    #[arg(long, default_value_t = 256, requires = "cache")]
    pub cache_mb: usize,
    /// Where the solid cube of plain exemplars is kept when `cache` is not given: a guided
    /// model's own folder, so that its commands synthesize the cube once.
    #[arg(skip)]
    pub cube_folder: Option<PathBuf>,
    /// Override the spec's target tet count (100 to 200000).
    #[arg(long)]
    pub tets: Option<usize>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The cut's PNG, or the solid's volume (.exr, .vol, .nrrd, .dds, .vdb, ...), or a
    /// guided model (.guided): the recipe, which `view`, `cut`, `bake` and `render` synthesize from.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// A neighbourhood side given as `flag`: odd, 3 to 11.
fn odd_side(flag: &str, value: usize) -> Result<()> {
    io::values::within(flag, value, 3, 11)?;
    match value.is_multiple_of(2) {
        true => Err(Error::invalid(format!("{flag} {value} must be odd (3, 5, 7, 9 or 11)"))),
        false => Ok(()),
    }
}

/// What `guided` makes of its inputs.
#[derive(Debug, Clone, Copy)]
pub enum Action {
    /// A cut through a point with a normal, as a PNG.
    Cut(Vec3, Vec3),
    /// The whole solid, as a volume with the model's coverage as alpha.
    Solid,
    /// The model's surface seen from a camera, as a PNG.
    View(crate::fill::view::View),
    /// The recipe, as a guided model file (`.guided`) that `view`, `cut`, `bake` and `render` read.
    Model,
    /// The whole solid kept in memory as a filled model (`render` of a guided model).
    Keep,
}

/// A guided solid as a filled model: the field's tets, the input surface, one patch
/// whose texture coordinates are the positions in the solid's grid.
pub struct Filled {
    /// The model.
    pub model: crate::fill::model::LstModel,
    /// The solid (its colours and the model's coverage as alpha).
    pub volume: crate::volume::Volume,
}

/// The settings a guided model keeps (resolution, neighbourhoods, tets, exemplar side)
/// checked against their ranges, each named by `name` of its field (`res`, `coarse_n`, ...):
/// as a flag on the command line, as a field in a `.guided` file.
fn recipe_checked(args: &GuidedArgs, name: &dyn Fn(&str) -> String) -> Result<()> {
    io::values::within(&name("res"), args.res, *solid::RESOLUTION.start(), *solid::RESOLUTION.end())?;
    odd_side(&name("coarse_n"), args.coarse_n)?;
    odd_side(&name("n"), args.n)?;
    check_tets(&name("tets"), args.tets)?;
    let (lo, hi) = crate::synth::SynthParams::EXEMPLAR_SIDE;
    args.others.max_exemplar.map(|m| io::values::within(&name("max_exemplar"), m, lo, hi)).transpose()?;
    Ok(())
}

/// The values of `args` checked against their ranges (usage errors), and its cut.
fn checked(args: &GuidedArgs) -> Result<Option<(Vec3, Vec3)>> {
    let checks = || -> Result<Option<(Vec3, Vec3)>> {
        recipe_checked(args, &|field| format!("--{}", field.replace('_', "-")))?;
        io::values::within("--size", args.size, 8, 4096)?;
        io::values::within("--cache-mb", args.cache_mb, *CACHE_MB.start(), *CACHE_MB.end())?;
        if let Some(folder) = args.cache.as_deref().filter(|f| !f.exists() && f.symlink_metadata().is_ok()) {
            return Err(Error::invalid(format!(
                "--cache {}: is a link to nothing; name a folder for the cache",
                folder.display()
            )));
        }
        if let Some(folder) = args.cache.as_deref().filter(|f| f.exists() && !f.is_dir()) {
            return Err(Error::invalid(format!(
                "--cache {}: is a file; name a folder for the cache",
                folder.display()
            )));
        }
        args.cut.as_deref().map(|text| super::fill::plane("--cut", text)).transpose()
    };
    checks().map_err(usage)
}

/// The input files `args` names.
fn inputs(args: &GuidedArgs) -> Vec<&Path> {
    let others = [&args.exemplar, &args.solid, &args.others.ey, &args.others.ez];
    let masks = [&args.mask, &args.ey_mask, &args.ez_mask];
    let given = others.into_iter().chain(masks).flatten();
    [&args.mesh, &args.spec].into_iter().chain(given).map(|p| p.as_path()).collect()
}

/// Run `solidtex guided`.
pub fn run_guided(args: &GuidedArgs) -> Result<()> {
    let cut = checked(args)?;
    let action = match (cut, io::guided_model::is_guided(&args.output)) {
        (Some(_), true) => {
            return Err(usage(Error::invalid(format!(
                "{}: --cut writes a PNG picture; a .guided output is the model's recipe, which `solidtex cut` cuts \
                 later",
                args.output.display()
            ))));
        }
        (Some((point, normal)), false) => Action::Cut(point, normal),
        (None, true) => Action::Model,
        (None, false) => Action::Solid,
    };
    check_output_of(action, &args.output, args, None)?;
    synthesize(args, action).map(|_| ())
}

/// Refuse an `output` that is not of the kind `action` writes, or that is one of the
/// inputs of `args` (and the guided `model` they come from): the built volumes of the
/// spec's regions included.
fn check_output_of(action: Action, output: &Path, args: &GuidedArgs, model: Option<&Path>) -> Result<()> {
    let fill = fill_spec::read_fill_spec(&args.spec)?;
    let regions: Vec<PathBuf> =
        fill.regions.iter().map(|r| crate::library::files::volume(&fill.built, &r.exemplar)).collect();
    let inputs: Vec<&Path> =
        inputs(args).into_iter().chain(model).chain(regions.iter().map(PathBuf::as_path)).collect();
    let kept = [(&args.cache, "the solid cube and bricks of --cache"), (&args.cube_folder, "the model's solid cube")];
    for (folder, what) in kept.into_iter().filter(|_| !matches!(action, Action::Keep)) {
        folder.as_deref().map(|f| io::guard::outside_folder(output, f, what)).transpose()?;
    }
    match action {
        Action::Cut(..) | Action::View(_) => io::guard::png_output(output, &inputs),
        Action::Solid => io::check_output(output, &inputs),
        Action::Model => io::guard::file_output(output, &inputs, &[io::guided_model::EXTENSION], "a guided model"),
        Action::Keep => Ok(()),
    }
}

/// Do `action` with the inputs of `args` (checked): the field, the exemplars (by regions,
/// at the steps of a scale field, or one set), then the cut, the solid, the view or the
/// model file.
fn synthesize(args: &GuidedArgs, action: Action) -> Result<Option<Filled>> {
    let started = Instant::now();
    let g = guide(&args.mesh, &args.spec, args.tets)?;
    let domain = Domain::around(g.surface.bounds(), args.res)?;
    if !g.spec.regions.is_empty() {
        return by_regions(args, &g, &domain, action, started);
    }
    if !g.spec.scales.is_empty() {
        return by_scales(args, &g, &domain, action, started);
    }
    let depth =
        args.layered.then(|| solid::depth_over(&g.depth, &domain)).transpose().map_err(|e| e.in_file(&args.spec))?;
    let rows = depth
        .as_ref()
        .map(|d| solid::layer_rows(d, args.res))
        .transpose()
        .map_err(|e| Error::file(&args.mesh, format!("--res {}: {e}", args.res)))?;
    let (prepared, options, exemplar) = match &args.solid {
        Some(path) => solid_exemplar(args, path, rows, g.texture_axes).map_err(|e| e.in_file(path))?,
        None => {
            let path = args.exemplar.as_ref().ok_or_else(|| usage(Error::invalid("give --exemplar or --solid")))?;
            plane_exemplars(args, path, rows, 1.0)?
        }
    };
    let frames = solid::frames_over(&g.tets, &g.field, &domain, &g.depth, &g.axes)?;
    let setup = Setup {
        exemplars: &prepared,
        frames: Some(&frames),
        wrap: [false; 3],
        depth: depth.as_ref(),
        dims: domain.dims,
        seed: args.seed,
        options,
    };
    if let Action::View(_) | Action::Model = action {
        return write_blend(args, &g, &domain, action, &[setup], &|_, _| 1.0, started);
    }
    solid::check_memory(&setup, matches!(action, Action::Solid | Action::Keep), args.res, io::budget_from_env()?)?;
    let ready = started.elapsed().as_secs_f64();
    let bar = super::fill::Bar::new();
    let mut kept = None;
    let outcome = match action {
        Action::Cut(point, normal) => write_cut(args, &g, &setup, &domain, (point, normal), &exemplar, &bar),
        _ => solid_of(&g, &setup, &domain, &bar).and_then(|(counts, volume)| {
            kept = deliver(args, action, &g, &domain, volume)?;
            Ok(counts)
        }),
    };
    bar.0.finish_and_clear();
    let (voxels, corrections, full) = outcome?;
    report(args, action, &g, &domain, (started, ready), [voxels, corrections, full, 1]);
    Ok(kept)
}

/// The whole solid `action` asked for: written to the output as a bake (`Solid`:
/// [`solid::baked`]), or kept as a filled model (`Keep`: its colour read up to the surface).
fn deliver(
    args: &GuidedArgs,
    action: Action,
    g: &Guide,
    domain: &Domain,
    volume: crate::volume::Volume,
) -> Result<Option<Filled>> {
    match action {
        Action::Keep => Ok(Some(filled(g, domain, volume))),
        _ => super::write_volume(&args.output, &solid::baked(volume, domain)).map(|_| None),
    }
}

/// The solid over `domain` as a filled model of the guide's tets and surface: one patch
/// whose texture coordinates place each vertex in the solid's grid (a voxel's centre at
/// its texture point, as the fill's sampler reads a volume).
fn filled(g: &Guide, domain: &Domain, volume: crate::volume::Volume) -> Filled {
    use crate::fill::model::{LstModel, MaskRef, Source};
    let extent = Vec3::from_array(domain.dims.map(|d| d as f32)) * domain.voxel;
    let coords = g.tets.vertices.iter().map(|p| (*p - domain.origin) / extent).collect();
    let vertices = (0..g.tets.vertices.len() as u32).collect();
    let patch = crate::fill::patch::Patch { source: 0, vertices, coords };
    let source = Source { exemplar: "guided".into(), volume: String::new(), mask: MaskRef::File(String::new()) };
    let tet_patches = vec![vec![0]; g.tets.tets.len()];
    let model = LstModel::new(g.tets.clone(), g.surface.clone(), vec![source], vec![patch], tet_patches);
    Filled { model, volume }
}

/// The recipe of `args` as a guided model (its paths as given).
fn model_of(args: &GuidedArgs) -> io::guided_model::GuidedModel {
    io::guided_model::GuidedModel {
        mesh: args.mesh.clone(),
        spec: args.spec.clone(),
        exemplar: args.exemplar.clone(),
        solid: args.solid.clone(),
        ey: args.others.ey.clone(),
        ez: args.others.ez.clone(),
        mask: args.mask.clone(),
        ey_mask: args.ey_mask.clone(),
        ez_mask: args.ez_mask.clone(),
        max_exemplar: args.others.max_exemplar,
        layered: args.layered,
        planes: args.planes,
        res: args.res,
        n: args.n,
        coarse_n: args.coarse_n,
        seed: args.seed,
        tets: args.tets,
    }
}

/// The arguments `guided` would take to make `model`, writing `output` (a cut's or view's
/// picture `size` pixels wide, or the solid).
fn args_of(model: io::guided_model::GuidedModel, size: usize, output: &Path) -> GuidedArgs {
    GuidedArgs {
        mesh: model.mesh,
        spec: model.spec,
        exemplar: model.exemplar,
        solid: model.solid,
        others: super::synth::OtherExemplars { ey: model.ey, ez: model.ez, max_exemplar: model.max_exemplar },
        mask: model.mask,
        ey_mask: model.ey_mask,
        ez_mask: model.ez_mask,
        layered: model.layered,
        planes: model.planes,
        res: model.res,
        coarse_n: model.coarse_n,
        n: model.n,
        cut: None,
        size,
        cache: None,
        cache_mb: 256,
        cube_folder: None,
        tets: model.tets,
        seed: model.seed,
        output: output.to_path_buf(),
    }
}

/// `cut` of a guided model (`model`, a `.guided` file) through `plane` (default: through
/// the centre of its mesh's box, normal z), a PNG `size` pixels wide.
pub fn cut_model(model: &Path, plane: Option<(Vec3, Vec3)>, size: usize, output: &Path) -> Result<()> {
    let (point, normal) = match plane {
        Some(plane) => plane,
        None => {
            let (lo, hi) = mesh_file::read_mesh(&io::guided_model::read(model)?.mesh)?.bounds();
            ((lo + hi) / 2.0, Vec3::Z)
        }
    };
    from_model(model, Action::Cut(point, normal), size, output)
}

/// The arguments of the guided model at `path` (a picture `size` pixels wide into
/// `output`), its settings checked against their ranges and named as the file names them
/// (an error in the file, not a usage error).
fn model_args(path: &Path, size: usize, output: &Path) -> Result<GuidedArgs> {
    let model = io::guided_model::read(path)?;
    if model.exemplar.is_none() && model.solid.is_none() && fill_spec::read_fill_spec(&model.spec)?.regions.is_empty() {
        return Err(Error::file(
            path,
            "gives neither exemplar nor solid, and its spec has no [[region]]; a guided model takes one of them",
        ));
    }
    let mut args = args_of(model, size, output);
    args.cube_folder = Some(io::model_folder(path).join(MODEL_CACHE));
    recipe_checked(&args, &|field| format!("{field} =")).map_err(|e| e.in_file(path))?;
    Ok(args)
}

/// `view`, `cut` or `bake` of a guided model (`model`, a `.guided` file): `action` with
/// the model's recipe, writing `output` (`size`: a picture's side).
pub fn from_model(model: &Path, action: Action, size: usize, output: &Path) -> Result<()> {
    let args = model_args(model, size, output)?;
    checked(&args).map_err(|e| e.in_file(model))?;
    check_output_of(action, output, &args, Some(model))?;
    synthesize(&args, action).map(|_| ())
}

/// Refuse a picture `output` that is a guided model (`model`) or one of its inputs.
pub fn check_picture_of_model(model: &Path, output: &Path) -> Result<()> {
    let recipe = io::guided_model::read(model)?;
    let inputs: Vec<&Path> = recipe.inputs().into_iter().chain([model]).collect();
    io::guard::png_output(output, &inputs)
}

/// `render` of a guided model (`model`, a `.guided` file): its whole solid synthesized and
/// kept as a filled model.
pub fn filled_from_model(model: &Path) -> Result<Filled> {
    let args = model_args(model, 256, model)?;
    checked(&args).map_err(|e| e.in_file(model))?;
    synthesize(&args, Action::Keep)?.ok_or_else(|| Error::invalid("the guided solid was not kept"))
}

/// Say what was written, how long it took and how much of the whole solid it synthesized.
fn report(
    args: &GuidedArgs,
    action: Action,
    g: &Guide,
    domain: &Domain,
    (started, ready): (Instant, f64),
    counts: [usize; 4],
) {
    let [voxels, corrections, full, solids] = counts;
    let whole = if solids == 1 { "a whole solid needs".to_string() } else { format!("{solids} whole solids need") };
    let what = match action {
        Action::Keep => "synthesized the whole solid".to_string(),
        _ => format!("wrote {}", args.output.display()),
    };
    tell!(
        "{what}: {}x{}x{} grid, {} tets, field solved in {:.0} ms, set up in {ready:.2} s, synthesized in {:.2} s",
        domain.dims[0],
        domain.dims[1],
        domain.dims[2],
        g.tets.tets.len(),
        g.solve_ms,
        started.elapsed().as_secs_f64() - ready
    );
    tell!(
        "voxels synthesized: {voxels} of the {full} {whole} over all its pyramid levels ({:.1} %), {corrections} \
         corrections",
        100.0 * voxels as f64 / full.max(1) as f64
    );
}

/// `guided` with the spec's `[[region]]` entries: each depth range synthesized from its
/// own library exemplar (built first when it is not) and blended across the band.
fn by_regions(
    args: &GuidedArgs,
    g: &Guide,
    domain: &Domain,
    action: Action,
    started: Instant,
) -> Result<Option<Filled>> {
    let given = [
        ("--exemplar", args.exemplar.is_some()),
        ("--solid", args.solid.is_some()),
        ("--ey", args.others.ey.is_some()),
        ("--ez", args.others.ez.is_some()),
        ("--mask", args.mask.is_some()),
        ("--layered", args.layered),
        ("--planes", args.planes),
        ("--cache", args.cache.is_some()),
    ];
    if let Some((flag, _)) = given.iter().find(|(_, on)| *on) {
        return Err(usage(Error::invalid(format!(
            "{flag}: the spec {} chooses its exemplars by depth ([[region]] entries; a built exemplar with layers \
             follows them), so leave out {flag}",
            args.spec.display()
        ))));
    }
    for (flag, value) in [("--n", args.n), ("--coarse-n", args.coarse_n)] {
        if value != DEFAULT_N {
            return Err(usage(Error::invalid(format!(
                "{flag} {value}: the spec {} synthesizes each [[region]] with its exemplar's own neighbourhoods \
                 ({DEFAULT_N}); leave out {flag}",
                args.spec.display()
            ))));
        }
    }
    let spec = &g.spec;
    if !spec.scales.is_empty() {
        tell!(
            "note: the spec's [[scale_at]] points are not used with its [[region]] entries; each region's exemplar keeps its size"
        );
    }
    let names = crate::library::fill::region_names(spec);
    let missing = crate::library::fill::missing(spec, &names).map_err(|e| e.in_file(&args.spec))?;
    if !missing.is_empty() {
        tell!("building {} into {} first", missing.join(", "), spec.built.display());
        crate::library::fill::build_first(
            spec,
            missing,
            &super::build::Lines::new(0),
            &super::build::waiting_for(&spec.built),
        )?;
    }
    let depth = solid::depth_over(&g.depth, domain).map_err(|e| e.in_file(&args.spec))?;
    let made = crate::library::guided::region_exemplars(spec, &g.depth, domain).map_err(|e| e.in_file(&args.spec))?;
    let frames = solid::frames_over(&g.tets, &g.field, domain, &g.depth, &g.axes)?;
    let parts = crate::library::guided::region_setups(&made, &frames, domain.dims, args.seed);
    let regions = crate::library::guided::region_blend(spec);
    let weight = |k: usize, v: [usize; 3]| regions.weight(k, solid::grid_at(&depth, v));
    let kept = write_blend(args, g, domain, action, &parts, &weight, started)?;
    for ((region, name), (_, options, _)) in spec.regions.iter().zip(&names).zip(&made) {
        tell!("  depth {} to {}: {name}", region.depth[0], region.depth[1]);
        say_magnified(options);
    }
    Ok(kept)
}

/// Do `action` with blended parts ([`solid::cut_blend`]): the cut or the view as a PNG,
/// the whole solid with the model's coverage as alpha, or the model file; then say what
/// was done.
fn write_blend(
    args: &GuidedArgs,
    g: &Guide,
    domain: &Domain,
    action: Action,
    parts: &[Setup],
    weight: &solid::Weight,
    started: Instant,
) -> Result<Option<Filled>> {
    if let Action::Model = action {
        io::guided_model::write(&args.output, &model_of(args))?;
        tell!(
            "wrote {}: a guided model ({}x{}x{} grid); `solidtex view`, `cut`, `bake` and `render` synthesize what they show from it",
            args.output.display(),
            domain.dims[0],
            domain.dims[1],
            domain.dims[2]
        );
        return Ok(None);
    }
    for setup in parts {
        let whole = matches!(action, Action::Solid | Action::Keep);
        solid::check_memory(setup, whole, args.res, io::budget_from_env()?)?;
    }
    let mut kept = None;
    let ready = started.elapsed().as_secs_f64();
    let bar = super::fill::Bar::new();
    let outcome = match action {
        Action::Cut(point, normal) => {
            let view = View::framing(g.surface.bounds(), point, normal, args.size)?;
            solid::cut_blend(parts, weight, domain, &g.surface, &view, &bar).and_then(|(picture, counts)| {
                io::write_rgb8(&args.output, &solid::cut_picture(&picture)).map(|_| counts)
            })
        }
        Action::View(view) => solid::view_blend(parts, weight, domain, &g.surface, view, &bar)
            .and_then(|(picture, counts)| io::write_rgb8(&args.output, &picture).map(|_| counts)),
        Action::Solid | Action::Keep | Action::Model => {
            crate::volume::check_size(domain.dims, solid::RGBA.len(), io::budget_from_env()?).and_then(|_| {
                let alpha = coverage(&g.surface, domain);
                let (volume, counts) = solid::solid_blend(parts, weight, &alpha, &bar)?;
                kept = deliver(args, action, g, domain, volume)?;
                Ok(counts)
            })
        }
    };
    bar.0.finish_and_clear();
    let [voxels, corrections] = outcome?;
    let full = parts.iter().map(whole).sum();
    report(args, action, g, domain, (started, ready), [voxels, corrections, full, parts.len()]);
    Ok(kept)
}

/// Width in octaves of the band two neighbouring scale steps blend across.
const SCALE_BAND: f32 = 0.25;

/// `guided --exemplar` with the spec's `[[scale_at]]` points: the exemplars synthesized at
/// half-octave steps of their size (shrunk or enlarged, each plain photo's solid cube made
/// at that size) and each voxel blending the two steps nearest its scale.
fn by_scales(
    args: &GuidedArgs,
    g: &Guide,
    domain: &Domain,
    action: Action,
    started: Instant,
) -> Result<Option<Filled>> {
    let path = match (&args.exemplar, &args.solid, args.layered) {
        (Some(path), None, false) => path,
        _ => {
            return Err(usage(Error::invalid(format!(
                "the spec {} gives [[scale_at]] points: a scale field takes plain exemplars (--exemplar without \
                 --layered); a layered exemplar's scale follows the depth, and a --solid volume keeps its own",
                args.spec.display()
            ))));
        }
    };
    let side = load_exemplars(args, path, None, 1.0)?.0[0].width();
    let scale = solid::scale_over(&g.tets, &g.spec.scales, side, domain).map_err(|e| e.in_file(&args.spec))?;
    let steps = solid::scale_steps(&scale).map_err(|e| e.in_file(&args.spec))?;
    let made: Vec<(Exemplars, Options)> = steps
        .iter()
        .map(|step| plane_exemplars(args, path, None, step.exp2()).map(|(e, o, _)| (e, o)))
        .collect::<Result<_>>()?;
    let frames = solid::frames_over(&g.tets, &g.field, domain, &g.depth, &g.axes)?;
    let parts: Vec<Setup> = made
        .iter()
        .map(|(exemplars, options)| Setup {
            exemplars,
            frames: Some(&frames),
            wrap: [false; 3],
            depth: None,
            dims: domain.dims,
            seed: args.seed,
            options: *options,
        })
        .collect();
    let borders = steps.windows(2).map(|w| (w[0] + w[1]) / 2.0).collect();
    let blend = Regions::with_borders(borders, SCALE_BAND);
    let weight = |k: usize, v: [usize; 3]| blend.weight(k, solid::grid_at(&scale, v));
    let kept = write_blend(args, g, domain, action, &parts, &weight, started)?;
    let sizes: Vec<String> = steps.iter().map(|s| format!("{:.2}", s.exp2())).collect();
    tell!("  the exemplar synthesized with pixels {} voxels wide, blended by the spec's scale", sizes.join(", "));
    Ok(kept)
}

/// The exemplars per plane, alpha dropped (the solid's alpha is the model's coverage),
/// with their feature masks and (layered, `rows`) scaled so that their rows span the
/// model's depth in voxels, with a Depth channel; and the most rows any has as loaded
/// (before fitting).
fn load_exemplars(
    args: &GuidedArgs,
    exemplar: &Path,
    rows: Option<usize>,
    factor: f32,
) -> Result<([Image2d; 3], usize)> {
    let shrink = super::synth::OtherExemplars {
        ey: None,
        ez: None,
        max_exemplar: Some(args.others.max_exemplar.unwrap_or(DEFAULT_EXEMPLAR)),
    };
    for (flag, given, mask) in [("--ey", &args.others.ey, &args.ey_mask), ("--ez", &args.others.ez, &args.ez_mask)] {
        if let (Some(_), Some(path), None) = (&args.mask, given, mask) {
            return Err(usage(Error::invalid(format!(
                "{flag} {} needs its feature mask ({flag}-mask) when --mask is given",
                path.display()
            ))));
        }
    }
    // each image with its rows as loaded, before fitting
    let load = |path: &Path, mask: Option<&PathBuf>, what: &str| -> Result<(Image2d, usize)> {
        let image = resized_by(without_alpha(shrink.load(path, what)?)?, factor).map_err(|e| e.in_file(path))?;
        let image = match mask {
            Some(m) => with_mask(image, &resized_by(shrink.load(m, "feature mask")?, factor)?, path, m)?,
            None => image,
        };
        let source = image.height();
        match rows {
            Some(rows) => {
                if let Some(warning) = crate::synth::layering_warning(&image) {
                    tell!(
                        "warning: {}: {warning}. Turn the image so its rows run from the surface inward",
                        path.display()
                    );
                }
                Ok((with_depth(fitted(image, rows, path)?).map_err(|e| e.in_file(path))?, source))
            }
            None => Ok((image, source)),
        }
    };
    let (ex, rows_x) = load(exemplar, args.mask.as_ref(), "exemplar")?;
    let ey = args.others.ey.as_deref().map(|p| load(p, args.ey_mask.as_ref(), "Ey exemplar")).transpose()?;
    let ez = args.others.ez.as_deref().map(|p| load(p, args.ez_mask.as_ref(), "Ez exemplar")).transpose()?;
    let most_rows = [Some(rows_x), ey.as_ref().map(|e| e.1), ez.as_ref().map(|e| e.1)].into_iter().flatten().max();
    let ey = ey.map_or_else(|| ex.clone(), |e| e.0);
    let ez = ez.map_or_else(|| ey.clone(), |e| e.0);
    Ok(([ex, ey, ez], most_rows.unwrap_or(rows_x)))
}

/// The longest side a scale field may resize an exemplar to: preparing it keeps every
/// pixel's neighbourhood (n² x channels numbers), about 400 MB at 1024².
const MOST_SCALED_SIDE: usize = 1024;

/// `image` resized by `factor` (1: as it is); an error naming the size when it would fall
/// below 8 pixels on a side or grow past [`MOST_SCALED_SIDE`].
fn resized_by(image: Image2d, factor: f32) -> Result<Image2d> {
    if factor == 1.0 {
        return Ok(image);
    }
    let size = |s: usize| (s as f64 * f64::from(factor)).round();
    let (w, h) = (size(image.width()), size(image.height()));
    let (name, most) = (format!("{}x{}", image.width(), image.height()), MOST_SCALED_SIDE);
    if w.is_nan() || h.is_nan() || w.min(h) < 8.0 {
        return Err(Error::invalid(format!(
            "the [[scale_at]] scales shrink the {name} exemplar to {w}x{h} pixels, under 8; ask for larger scales"
        )));
    }
    if w.max(h) > most as f64 {
        return Err(Error::invalid(format!(
            "the [[scale_at]] scales grow the {name} exemplar to {w:.0}x{h:.0} pixels, over {most}; ask for smaller scales"
        )));
    }
    image.resized(w as usize, h as usize)
}

/// The image with a feature channel: the mask's grey (the mean of its colour channels).
fn with_mask(image: Image2d, mask: &Image2d, path: &Path, mask_path: &Path) -> Result<Image2d> {
    if (mask.width(), mask.height()) != (image.width(), image.height()) {
        return Err(Error::file(
            mask_path,
            format!(
                "the feature mask is {}x{} pixels and its exemplar {} {}x{} (both as loaded); a mask needs its \
                 exemplar's size",
                mask.width(),
                mask.height(),
                path.display(),
                image.width(),
                image.height()
            ),
        ));
    }
    let colours: Vec<usize> = (0..mask.channel_count()).filter(|&c| mask.channels()[c] != Channel::A).collect();
    let grey = |px: &[f32]| colours.iter().map(|&c| px[c]).sum::<f32>() / colours.len().max(1) as f32;
    let (c, m) = (image.channel_count(), mask.channel_count());
    let data = image
        .data()
        .chunks_exact(c)
        .zip(mask.data().chunks_exact(m))
        .flat_map(|(px, mx)| px.iter().copied().chain([grey(mx)]))
        .collect();
    let names = image.channels().iter().cloned().chain([Channel::Named(synth::FEATURE.into())]).collect();
    Image2d::from_data(image.width(), image.height(), names, data)
}

/// The neighbourhood side at every level unless `--n` and `--coarse-n` say.
const DEFAULT_N: usize = 5;

/// Exemplars are shrunk to this many pixels on their longer side unless `--max-exemplar` says.
const DEFAULT_EXEMPLAR: usize = 128;

/// The widest a layered exemplar may become when fitted to the model's depth.
const MOST_FITTED_WIDTH: usize = 2048;

/// A layered exemplar scaled (both sides alike) to `rows` rows: one voxel takes one pixel,
/// so rows that do not match the voxels the model's depth runs over are skipped or
/// repeated, and layers (a log's rings) break into dashes.
fn fitted(image: Image2d, rows: usize, path: &Path) -> Result<Image2d> {
    if image.height() == rows {
        return Ok(image);
    }
    let width = (image.width() as f64 * rows as f64 / image.height() as f64).round().max(1.0) as usize;
    if width > MOST_FITTED_WIDTH {
        return Err(Error::file(
            path,
            format!(
                "fitting its {} rows to the model's depth ({rows} voxels at this --res) would make it {width} pixels \
                 wide, more than {MOST_FITTED_WIDTH}; lower --res or crop the exemplar",
                image.height()
            ),
        ));
    }
    tell!(
        "layered: {} scaled from {}x{} to {width}x{rows} pixels, so that its rows span the model's depth \
         ({rows} voxels at this --res)",
        path.display(),
        image.width(),
        image.height()
    );
    image.resized(width, rows)
}

/// The image with a Depth channel: its row coordinate, 0 at the top (the outside).
fn with_depth(image: Image2d) -> Result<Image2d> {
    if image.channels().contains(&Channel::Depth) {
        return Err(Error::invalid(
            "the exemplar already has a Depth channel; --layered adds one from the rows (give an image without it)",
        ));
    }
    let (w, h, c) = (image.width(), image.height(), image.channel_count());
    let data = image
        .data()
        .chunks_exact(c)
        .enumerate()
        .flat_map(|(i, px)| px.iter().copied().chain([(i / w) as f32 / (h - 1).max(1) as f32]))
        .collect();
    let names = image.channels().iter().cloned().chain([Channel::Depth]).collect();
    Image2d::from_data(w, h, names, data)
}

fn without_alpha(image: Image2d) -> Result<Image2d> {
    let keep: Vec<usize> = (0..image.channel_count()).filter(|&c| image.channels()[c] != Channel::A).collect();
    if keep.len() == image.channel_count() {
        return Ok(image);
    }
    let data = image.data().chunks_exact(image.channel_count()).flat_map(|px| keep.iter().map(|&c| px[c])).collect();
    let names = keep.iter().map(|&c| image.channels()[c].clone()).collect();
    Image2d::from_data(image.width(), image.height(), names, data)
}

/// The prepared exemplars of `--exemplar` (and `--ey`, `--ez`, masks), their settings and
/// the exemplar a cut's sharpness is measured against: plain exemplars through their solid
/// cube, or (layered, masked, `--planes`) as planes.
fn plane_exemplars(
    args: &GuidedArgs,
    path: &Path,
    rows: Option<usize>,
    factor: f32,
) -> Result<(Exemplars, Options, Image2d)> {
    let (exemplars, source_rows) = load_exemplars(args, path, rows, factor)?;
    let through_cube = !args.layered && args.mask.is_none() && !args.planes;
    let side =
        if through_cube { cube::SIDE } else { exemplars.iter().map(|e| e.width().min(e.height())).min().unwrap_or(0) };
    let options = Options { layered: args.layered, coarse_n: args.coarse_n, n: args.n, ..Options::for_exemplar(side) };
    let options = match rows {
        Some(rows) => options.magnifying(source_rows, rows),
        None => options,
    };
    say_magnified(&options);
    let prepared = if through_cube {
        cube_volume(args, &exemplars).and_then(|cube| Exemplars::of_volume(&cube, &options))
    } else {
        Exemplars::prepare([&exemplars[0], &exemplars[1], &exemplars[2]], &options)
            .and_then(|prepared| prepared.refuse_alpha().map(|_| prepared))
    }
    .map_err(|e| args.others.in_file(e, path))?;
    let [first, ..] = exemplars;
    Ok((prepared, options, first))
}

/// Tell which levels only magnify a layered exemplar fitted up to the model's depth.
fn say_magnified(options: &Options) {
    if options.magnified > 0 {
        tell!(
            "layered: the finest {} of {} levels magnify the level below (the exemplar holds no finer detail): their \
             rows follow the model's depth, nothing is matched there",
            options.magnified,
            options.levels
        );
    }
}

/// The prepared solid exemplar of `--solid`, its settings, and its central slice across x
/// (alpha left out) for a cut's sharpness. Layered (`rows`: how many voxels the model's
/// depth spans), a volume with a Depth channel gives its two central slices along its
/// depth axis as layered planes, as the library's fill preview takes them.
fn solid_exemplar(
    args: &GuidedArgs,
    path: &Path,
    rows: Option<usize>,
    given: Option<[crate::volume::Axis; 2]>,
) -> Result<(Exemplars, Options, Image2d)> {
    let volume = io::read_volume(path, io::budget_from_env()?)?;
    if let Some(rows) = rows {
        let planes = crate::library::guided::layered_planes(&volume, given, rows)?.ok_or_else(|| {
            usage(Error::invalid(format!(
                "{}: --layered with --solid needs a volume with layers, a Depth channel (a library \
                 cross-section's build); it has {}",
                path.display(),
                volume.channels().iter().map(|c| c.name()).collect::<Vec<_>>().join(", ")
            )))
        })?;
        let options =
            Options { coarse_n: args.coarse_n, n: args.n, ..crate::library::guided::section_options(&planes, &volume) };
        say_magnified(&options);
        let prepared = Exemplars::prepare([&planes[0], &planes[1], &planes[2]], &options)?;
        let [first, ..] = planes;
        return Ok((prepared, options, first));
    }
    if volume.channel_index(&crate::volume::Channel::Depth).is_some() {
        return Err(Error::invalid(
            "a solid exemplar shows colours only, and this volume has a Depth channel (a built \
             cross-section): follow it in layers, add --layered",
        ));
    }
    let options = Options { coarse_n: args.coarse_n, n: args.n, ..Options::for_exemplar(volume.dims()[0]) };
    let prepared = Exemplars::of_volume(&volume, &options)?;
    let slice = without_alpha(volume.slice(crate::volume::Axis::X, volume.dims()[0] / 2)?)?;
    Ok((prepared, options, slice))
}

/// The name of the folder beside a guided model that keeps its solid cube.
pub const MODEL_CACHE: &str = ".solidtex-cache";

/// The solid cube of plain exemplars: synthesized, or read from the cache folder (and
/// kept there when it was not, or was damaged). Without `--cache`, a guided model's
/// commands keep it beside the model; a folder there that cannot be written only costs
/// the next command the cube's time again (a warning says so).
fn cube_volume(args: &GuidedArgs, images: &[Image2d; 3]) -> Result<crate::volume::Volume> {
    let Some(folder) = args.cache.as_ref().or(args.cube_folder.as_ref()) else {
        return cube::synthesize(images, args.seed);
    };
    let key = cube::key(images, args.seed);
    let path = guided_cache::cube_path(folder, key);
    let channels = images[0].channel_count();
    let hint = if args.cache.is_some() { guided_cache::CACHE_HINT } else { "move it away to keep the cube there" };
    let read = guided_cache::read_cube(&path, key, (cube::SIDE, channels), cube::colour_range(images), hint);
    let stale = match read {
        Ok(Cached::Good(colours)) => {
            guided_cache::mark_used(&path);
            return crate::volume::Volume::from_data([cube::SIDE; 3], images[0].channels().to_vec(), colours);
        }
        Ok(Cached::Stale(why)) => Some(why),
        Ok(Cached::Missing) => None,
        Err(e) if args.cache.is_none() => {
            tell_not_kept(&e);
            return cube::synthesize(images, args.seed);
        }
        Err(e) => return Err(e),
    };
    let volume = cube::synthesize(images, args.seed)?;
    let kept = std::fs::create_dir_all(folder)
        .map_err(|e| Error::io(folder, e))
        .and_then(|_| guided_cache::write_cube(&path, key, cube::SIDE, channels, volume.data()));
    if kept.is_ok() {
        let removed = guided_cache::prune(folder, &path, &guided_cache::CUBES);
        if !removed.is_empty() {
            tell!(
                "removed {} solid cube(s) of earlier exemplars from {} (it keeps the {} used last)",
                removed.len(),
                folder.display(),
                guided_cache::CUBES_KEPT
            );
        }
    }
    match kept {
        Ok(()) if args.cache.is_none() && stale.is_none() => {
            tell!("kept the solid cube in {} for the next commands on this model", path.display())
        }
        Ok(()) => warn_rebuilt(&path, stale),
        Err(e) if args.cache.is_none() => tell_not_kept(&e),
        Err(e) => return Err(e),
    }
    Ok(volume)
}

/// Say that the cube beside a guided model was not kept there, and `why`.
fn tell_not_kept(why: &Error) {
    tell!("warning: the solid cube was not kept ({why})");
}

/// Megabytes the cache may hold in memory.
const CACHE_MB: std::ops::RangeInclusive<usize> = 16..=65536;

/// Bytes a kept brick takes in memory.
const BRICK_BYTES: usize = BRICK * BRICK * BRICK * std::mem::size_of::<synth::Held>();

/// Megabytes `bricks` kept bricks take, rounded up.
fn brick_mb(bricks: usize) -> usize {
    (bricks * BRICK_BYTES).div_ceil(1 << 20)
}

/// Compute the coarse levels ([`synth::Options::coarse_levels`]) over the model
/// ([`solid::interior_plan`]) into `levels` (the cache's, coarsest first) unless the cache
/// holds them already or they would take more than a quarter of its `most` bricks: later
/// cuts then compute only the levels above them. Whether it computed them.
fn whole_coarse_levels(
    setup: &Setup,
    (domain, surface): (&Domain, &Mesh),
    cached: &mut Bricks,
    most: usize,
    bar: &super::fill::Bar,
) -> Result<bool> {
    if cached.whole {
        return Ok(false);
    }
    let plan = solid::interior_plan(setup, domain, surface);
    if plan.is_empty() {
        return Ok(false);
    }
    let finals: Vec<&Mask> = plan.iter().filter_map(|versions| versions.last()).collect();
    let bricks: usize = finals.iter().map(|m| m.bricks().count()).sum();
    if 4 * bricks > most {
        tell!(
            "the levels below the finest take about {} MB, more than a quarter of --cache-mb {}: each cut computes \
             them around its plane; a cut with --cache-mb {} keeps them over the whole model (it takes longer; later \
             cuts of any plane then compute only the finer levels)",
            brick_mb(bricks),
            brick_mb(most),
            brick_mb(4 * bricks).next_multiple_of(256)
        );
        return Ok(false);
    }
    let voxels: usize = finals.iter().map(|m| m.count()).sum();
    let grid: usize = setup.level_dims()[..plan.len()].iter().map(|d| d.iter().product::<usize>()).sum();
    tell!(
        "computing the levels below the finest over the model for the cache: {voxels} voxels, {:.0} % of their \
         grids; later cuts compute only the levels above them",
        100.0 * voxels as f64 / grid as f64
    );
    let finer: Vec<Sparse<synth::Held>> = cached.levels.drain(..).skip(plan.len()).collect();
    cached.levels = solid::coarse_levels(setup, &plan, bar)?.into_iter().chain(finer).collect();
    cached.whole = true;
    Ok(true)
}

/// Where a cache file is and the key it is kept under.
struct Kept {
    path: PathBuf,
    key: u64,
}

/// The bricks earlier cuts kept in the cache folder, one store per level (none when there
/// is no cache yet), and where they are; a damaged file is said and dropped. `None` when
/// the file holds more than `most` bricks allow (kept under a larger `--cache-mb`): it is
/// left as it is, neither read nor written, and the run says what would read it. A link at
/// the file's name is refused before any synthesis.
fn kept_bricks(folder: &Path, setup: &Setup, most: usize) -> Result<Option<(Kept, Bricks)>> {
    let key = synth::fingerprint(setup);
    let path = guided_cache::path(folder, key);
    match std::fs::symlink_metadata(&path) {
        Ok(meta) if meta.file_type().is_symlink() => {
            return Err(Error::usage(format!(
                "{}: is a link; solidtex writes its cache files there itself and does not write through links: \
                 remove the link or give another --cache folder",
                path.display()
            )));
        }
        Ok(meta) if meta.len() > guided_cache::file_bytes(most) => {
            let bricks = meta.len().div_ceil(guided_cache::file_bytes(1) - guided_cache::file_bytes(0));
            tell!(
                "warning: {} holds {} MB of bricks, more than --cache-mb {} lets a run read; not used and kept as it \
                 is (--cache-mb {} or more reads it)",
                path.display(),
                meta.len().div_ceil(1 << 20),
                brick_mb(most),
                brick_mb(bricks as usize) + 1
            );
            return Ok(None);
        }
        _ => {}
    }
    let dims = setup.level_dims();
    let slots: Vec<[usize; 3]> = (0..dims.len()).map(|l| setup.exemplars.slot_counts(l)).collect();
    match guided_cache::read(&path, key, &dims, &slots, guided_cache::file_bytes(most))? {
        Cached::Good(bricks) => {
            guided_cache::mark_used(&path);
            Ok(Some((Kept { path, key }, bricks)))
        }
        Cached::Stale(why) => {
            warn_rebuilt(&path, Some(why));
            Ok(Some((Kept { path, key }, Bricks { levels: Vec::new(), whole: false })))
        }
        Cached::Missing => Ok(Some((Kept { path, key }, Bricks { levels: Vec::new(), whole: false }))),
    }
}

/// Keep what the cut computed (`made`, coarsest first) over what the cache held (`kept`),
/// at most `most` bricks, coarser levels first. A level that only magnifies is not kept: a
/// cut computes it again in about the time reading it would take.
fn keep_bricks(
    folder: &Path,
    file: &Kept,
    setup: &Setup,
    made: &Synthesized,
    kept: &Bricks,
    most: usize,
) -> Result<()> {
    let mut left = most;
    let mut levels = Vec::new();
    // the coarse levels stay whole unless the cap leaves some of their bricks out
    let mut whole = kept.whole;
    for (level, new) in made.levels().enumerate() {
        let none = Sparse::from_bricks(new.dims, []);
        if setup.options.magnifies(level) {
            levels.push(none);
            continue;
        }
        let old = kept.levels.get(level).unwrap_or(&none);
        let merged = new.map(synth::Held::from).over(old, left);
        whole &= level >= setup.options.coarse_levels() || merged.brick_count() >= old.brick_count();
        left -= merged.brick_count();
        levels.push(merged);
    }
    std::fs::create_dir_all(folder).map_err(|e| Error::io(folder, e))?;
    guided_cache::write(&file.path, file.key, &levels, whole)?;
    let removed = guided_cache::prune(folder, &file.path, &guided_cache::BRICK_CACHES);
    if !removed.is_empty() {
        tell!(
            "removed {} cache file(s) of earlier models, exemplars or settings from {} (it keeps the {} used last)",
            removed.len(),
            folder.display(),
            guided_cache::BRICKS_KEPT
        );
    }
    Ok(())
}

/// Tell that a cache file solidtex wrote, found unusable (`stale`: what was wrong), was
/// written anew.
fn warn_rebuilt(path: &Path, stale: Option<String>) {
    if let Some(why) = stale {
        tell!("warning: {} is {why}; rebuilt", path.display());
    }
}

/// The voxel count of every level of the whole solid.
fn whole(setup: &Setup) -> usize {
    setup.level_dims().iter().map(|d| d.iter().product::<usize>()).sum()
}

fn write_cut(
    args: &GuidedArgs,
    g: &Guide,
    setup: &Setup,
    domain: &Domain,
    (point, normal): (Vec3, Vec3),
    exemplar: &Image2d,
    bar: &super::fill::Bar,
) -> Result<(usize, usize, usize)> {
    let view = View::framing(g.surface.bounds(), point, normal, args.size)?;
    let most = (args.cache_mb << 20) / BRICK_BYTES;
    let mut cached = args.cache.as_deref().map(|folder| kept_bricks(folder, setup, most)).transpose()?.flatten();
    let coarse_made = match cached.as_mut() {
        Some((_, levels)) => whole_coarse_levels(setup, (domain, &g.surface), levels, most, bar)?,
        None => false,
    };
    let kept: Vec<Option<&Sparse<synth::Held>>> =
        cached.as_ref().map_or(Vec::new(), |(_, bricks)| bricks.levels.iter().map(Some).collect());
    let (picture, out) = solid::cut(setup, domain, &g.surface, &view, &kept, bar)?;
    io::write_rgb8(&args.output, &solid::cut_picture(&picture))?;
    let alpha = picture.channel_count() - 1;
    let shown = picture.data().chunks_exact(alpha + 1).any(|p| p[alpha] > 0.5);
    if !shown {
        tell!("warning: the cut misses the model; the picture shows only the background");
    }
    if let (Some(folder), Some((file, levels))) = (&args.cache, &cached)
        && (coarse_made || out.levels().enumerate().any(|(l, m)| !setup.options.magnifies(l) && m.brick_count() > 0))
    {
        // the cut is written: a cache that cannot be updated (a folder without write
        // permission, a full disk) costs later cuts time, not this one's picture
        if let Err(e) = keep_bricks(folder, file, setup, &out, levels, most) {
            tell!("warning: the cache was not updated ({e}); later cuts compute what it would have held");
        }
    }
    let scale = view.right.length() / domain.voxel;
    if shown && (0.8..=1.25).contains(&scale) {
        let (s, lines) = solid::cut_figures(&picture, exemplar)?;
        let (g, l) = (crate::sharpness::GRADIENT_RANGE, crate::sharpness::LENGTH_RANGE);
        tell!(
            "sharpness against the exemplar: gradient ratio {:.2}, length ratio {:.2} (targets {}-{} and {}-{})",
            s.gradient_ratio,
            s.length_ratio,
            g.0,
            g.1,
            l.0,
            l.1
        );
        say_lines(&lines);
    } else if shown {
        tell!(
            "sharpness against the exemplar: not measured, a pixel spans {scale:.2} voxels (--size {} gives about one)",
            (args.size as f32 * scale).round()
        );
    }
    Ok((out.voxels, out.corrections, whole(setup)))
}

/// Tell a cut's line figures against its exemplar, or that its exemplar's lines form no
/// long pieces for them to apply.
fn say_lines(lines: &crate::lines::Lines) {
    let p = &lines.lines;
    if !lines.applies {
        tell!(
            "line structure: the exemplar's {} lines form no long pieces (top-3 share {:.2}, under {}); not measured",
            p.name,
            p.exemplar.top3_share,
            crate::lines::APPLIES
        );
        return;
    }
    let (pieces, share) = (crate::lines::PIECES_BAND, crate::lines::SHARE_BAND);
    tell!(
        "line structure against the exemplar ({} lines): pieces ratio {:.2}, top-3 share ratio {:.2}, line share \
         ratio {:.2} (targets {}-{}, at least {}, {}-{})",
        p.name,
        p.pieces_ratio,
        p.top3_ratio,
        p.share_ratio,
        pieces.0,
        pieces.1,
        crate::lines::TOP3_LEAST,
        share.0,
        share.1
    );
}

/// The whole solid of one exemplar set: its channels and the model's coverage as alpha;
/// also the voxels, corrections and the whole solid's voxel count.
fn solid_of(
    g: &Guide,
    setup: &Setup,
    domain: &Domain,
    bar: &super::fill::Bar,
) -> Result<((usize, usize, usize), crate::volume::Volume)> {
    crate::volume::check_size(domain.dims, setup.exemplars.channels() + 1, io::budget_from_env()?)?;
    let out = synth::run(setup, &synth::plan(setup, &Mask::full(domain.dims), &[]), &[], bar)?;
    let alpha = coverage(&g.surface, domain);
    Ok(((out.voxels, out.corrections, whole(setup)), solid::solid_volume(setup, &out, &alpha)?))
}

/// The model's coverage of every voxel of the grid.
fn coverage(surface: &Mesh, domain: &Domain) -> Vec<f32> {
    let to_voxels = glam::Affine3A::from_scale_rotation_translation(
        Vec3::splat(1.0 / domain.voxel),
        glam::Quat::IDENTITY,
        -domain.origin / domain.voxel,
    );
    let covered = crate::mesh::voxelize::voxelize(&surface.transformed(to_voxels), domain.dims, 2);
    let mut alpha = Vec::with_capacity(domain.dims.iter().product());
    for z in 0..domain.dims[2] {
        for y in 0..domain.dims[1] {
            for x in 0..domain.dims[0] {
                alpha.push(covered.at(x, y, z));
            }
        }
    }
    alpha
}

/// A usage error when one of `inputs` is a guided model, which `command` does not take:
/// its colours are synthesized on demand, so it is baked to a volume first.
pub fn not_taken_by(command: &str, inputs: &[&Path], instead: &str) -> Result<()> {
    match inputs.iter().find(|p| io::guided_model::is_guided(p)) {
        None => Ok(()),
        Some(model) => Err(Error::usage(format!(
            "{}: `solidtex {command}` does not take guided models (their solid is synthesized on demand); bake it \
             first (`solidtex bake {} -o solid.exr`){instead}",
            model.display(),
            model.display()
        ))),
    }
}
