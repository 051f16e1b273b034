//! `solidtex fill`, `cut`, `bake` and `view`: fill a closed mesh with library exemplars and
//! look at the result.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::fill::render::{self, Textures, View};
use crate::fill::view::Shading;
use crate::fill::{self, Job, LstModel, MaskRef, mesher, translucent};
use crate::io::{self, fill_spec, lst_file};
use crate::library;
use crate::library::fill::load_mask;
use crate::progress::Progress;
use crate::volume::{Channel, Volume};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The arguments of `solidtex fill`.
#[derive(Debug, clap::Args)]
pub struct FillArgs {
    /// The closed surface to fill (OBJ, STL or PLY).
    pub mesh: PathBuf,
    /// The fill spec (TOML, see docs/fill.md).
    #[arg(long)]
    pub spec: PathBuf,
    /// The model to write (.lst).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the fill's figures as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Override the spec's target tet count (100 to 200000).
    #[arg(long)]
    pub tets: Option<usize>,
    /// Override the spec's seed (any 64-bit whole number).
    #[arg(long)]
    pub seed: Option<u64>,
}

/// The camera of a 3D picture (`view`, `render`, `cut --stroke`).
#[derive(Debug, clap::Args)]
pub struct CameraArgs {
    /// Degrees around the vertical axis, -360 to 360.
    #[arg(long, default_value_t = 35.0, allow_hyphen_values = true)]
    pub yaw: f32,
    /// Degrees above the horizon, -90 to 90.
    #[arg(long, default_value_t = 25.0, allow_hyphen_values = true)]
    pub pitch: f32,
}

impl CameraArgs {
    /// (yaw, pitch), each checked against its range.
    fn checked(&self) -> Result<(f32, f32)> {
        io::values::within("--yaw", self.yaw, -360.0, 360.0)?;
        io::values::within("--pitch", self.pitch, -90.0, 90.0)?;
        Ok((self.yaw, self.pitch))
    }
}

/// The arguments of `solidtex cut`.
#[derive(Debug, clap::Args)]
pub struct CutArgs {
    /// One or more models (.lst); several are combined, the first listed wins where they
    /// overlap. Or one guided model (.guided, from `solidtex guided`), synthesized on demand.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// The plane as PX,PY,PZ,NX,NY,NZ (a point and a normal, each -1000000 to 1000000, the
    /// normal not zero; default: through the centre, normal z).
    #[arg(long, allow_hyphen_values = true)]
    pub plane: Option<String>,
    /// Picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// Show this channel of the exemplars as grey instead of the colour: R, G, B, A, Depth,
    /// Displacement or a named one (0 black to 1 white).
    #[arg(long, conflicts_with = "stroke")]
    pub channel: Option<String>,
    /// Cut along a stroke instead of a plane: X,Y,Z;X,Y,Z;... (two or more points, `;` or
    /// `/` between them) swept along --extrude; repeat for several cuts. Draws a lit 3D
    /// view of what stays.
    #[arg(long, allow_hyphen_values = true, conflicts_with = "plane")]
    pub stroke: Vec<String>,
    /// The direction strokes are swept along, NX,NY,NZ (needed with --stroke).
    #[arg(long, allow_hyphen_values = true, requires = "stroke", conflicts_with = "plane")]
    pub extrude: Option<String>,
    /// A point on the side of every stroke to keep, X,Y,Z (default: the model's centre).
    #[arg(long, allow_hyphen_values = true, requires = "stroke", conflicts_with = "plane")]
    pub keep: Option<String>,
    /// With --stroke: move the cut faces along their normal by SCALE x (Displacement -
    /// 0.5), the exemplars' Displacement channel sampled inside (model units, at most the
    /// model's size: the diagonal of its box).
    #[arg(long, allow_hyphen_values = true, requires = "stroke", conflicts_with = "plane")]
    pub displacement: Option<f32>,
    /// With --stroke: where the 3D view looks from.
    #[command(flatten)]
    pub camera: StrokeCamera,
    /// The PNG to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The camera of a stroke cut's 3D view: given without `--stroke`, a usage error (a planar
/// cut has no camera).
#[derive(Debug, clap::Args)]
pub struct StrokeCamera {
    /// With --stroke: degrees around the vertical axis, -360 to 360.
    #[arg(long, default_value_t = 35.0, allow_hyphen_values = true, requires = "stroke", conflicts_with = "plane")]
    pub yaw: f32,
    /// With --stroke: degrees above the horizon, -90 to 90.
    #[arg(long, default_value_t = 25.0, allow_hyphen_values = true, requires = "stroke", conflicts_with = "plane")]
    pub pitch: f32,
}

impl StrokeCamera {
    /// (yaw, pitch), each checked against its range.
    fn checked(&self) -> Result<(f32, f32)> {
        CameraArgs { yaw: self.yaw, pitch: self.pitch }.checked()
    }
}

/// The arguments of `solidtex bake`.
#[derive(Debug, clap::Args)]
pub struct BakeArgs {
    /// One or more models (.lst), combined as in `cut`. Or one guided model (.guided): its
    /// whole solid at its own resolution, with its exemplar's channels and alpha.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// Voxels along the longest side, 2 to 512 [default: 128] (not for a guided model,
    /// which bakes at its own resolution).
    #[arg(long)]
    pub res: Option<usize>,
    /// The volume to write: R, G, B, the carried channels (`--carry`), then A (1 inside
    /// the model).
    #[arg(short, long)]
    pub output: PathBuf,
    /// The channels besides R, G, B and A to carry into the volume, comma-separated (e.g.
    /// Depth,Displacement), or `none`; each must be in every exemplar the models use
    /// (default: every such channel).
    #[arg(long)]
    pub carry: Option<String>,
}

/// The arguments of `solidtex view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
    /// One or more models (.lst); each pixel shows the nearest surface. Or one skin (.ply
    /// with vertex colours, as `solidtex surface` writes it), or one guided model
    /// (.guided): its mesh, textured by synthesizing only the voxels under what is seen.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// Where the picture looks from.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// Edges sharper than this many degrees stay sharp in the smooth shading, 0 to 180
    /// (default 60; filled and guided models).
    #[arg(long)]
    pub crease: Option<f32>,
    /// One normal per triangle of the input surface instead of smooth shading (shows its facets).
    #[arg(long)]
    pub flat: bool,
    /// Displacement mapping: move the surface along its normal by SCALE x (the exemplars'
    /// Displacement channel - 0.5), in model units, at most the models' size (the diagonal
    /// of their box).
    #[arg(long, allow_hyphen_values = true)]
    pub displacement: Option<f32>,
    /// A synthesized surface texture (`solidtex surface` on the mesh the model was filled
    /// from, a .ply with vertex colours) drawn on the surface instead of the solid's
    /// depth-0 colour.
    #[arg(long)]
    pub skin: Option<PathBuf>,
    /// The PNG to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Where `render` takes each voxel's density from.
#[derive(Debug, Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum DensityFrom {
    /// The same everywhere inside.
    Uniform,
    /// The exemplars' `Density` channel, or else their alpha.
    Alpha,
    /// Dark colours dense, light ones clear.
    Dark,
    /// Light colours dense, dark ones clear.
    Light,
}

/// The arguments of `solidtex render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// One or more models (.lst), combined as in `cut`. Or one guided model (.guided): its
    /// whole solid is synthesized first.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// Where the picture looks from.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// How opaque full-density material is across a tenth of the longest side of the
    /// models' box, 0 to 0.9999.
    #[arg(long, default_value_t = 0.3)]
    pub opacity: f32,
    /// Where the density comes from (default: alpha when every exemplar has a Density or A
    /// channel, else uniform).
    #[arg(long, value_enum)]
    pub density: Option<DensityFrom>,
    /// The density ramps from 0 at LO to 1 at HI, LO,HI within 0 to 1 (e.g. 0.7,0.9 shows
    /// only the densest material).
    #[arg(long, default_value = "0,1")]
    pub levels: String,
    /// The colour behind the models, R,G,B each 0 to 255 (a light one shows dense dark
    /// material).
    #[arg(long, default_value = "24,24,28")]
    pub background: String,
    /// Slices across the view, 16 to 4096.
    #[arg(long, default_value_t = 200)]
    pub slices: usize,
    /// Take away the material on the normal's side of this plane, PX,PY,PZ,NX,NY,NZ.
    #[arg(long, allow_hyphen_values = true)]
    pub cutaway: Option<String>,
    /// Picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// A synthesized surface texture (`solidtex surface` on the mesh the model was filled
    /// from) laid over the material where the rays enter it.
    #[arg(long)]
    pub skin: Option<PathBuf>,
    /// How much light the skin stops, 0 to 1 (1: only the skin shows where it is).
    #[arg(long, default_value_t = 0.85, requires = "skin")]
    pub skin_opacity: f32,
    /// The PNG to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Run `solidtex fill`.
pub fn run_fill(args: &FillArgs) -> Result<()> {
    if let Some(tets) = args.tets {
        let (lo, hi) = (*fill_spec::TETS.start(), *fill_spec::TETS.end());
        io::values::within("--tets", tets, lo, hi).map_err(usage)?;
    }
    lst_check(&args.output)?;
    io::guard::not_an_input(&args.output, &[&args.mesh, &args.spec])?;
    if let Some(json) = &args.json {
        io::guard::file_output(json, &[&args.mesh, &args.spec, &args.output], &["json"], "the fill's figures as JSON")?;
    }
    let mut spec = fill_spec::read_fill_spec(&args.spec)?;
    spec.tets = args.tets.unwrap_or(spec.tets);
    spec.seed = args.seed.unwrap_or(spec.seed);
    let surface = io::mesh_file::read_mesh(&args.mesh)?.canonical();
    let started = Instant::now();
    if !spec.regions.is_empty() {
        tell!(
            "note: the spec's [[region]] entries choose exemplars for `solidtex guided`; the lapped fill uses \
             exemplar = {:?} throughout",
            spec.exemplar
        );
    }
    let missing = library::fill::missing(&spec, &library::fill::names(&spec)).map_err(|e| e.in_file(&args.spec))?;
    if !missing.is_empty() {
        tell!("building {} into {} first", missing.join(", "), spec.built.display());
        library::fill::build_first(
            &spec,
            missing,
            &super::build::Lines::new(0),
            &super::build::waiting_for(&spec.built),
        )?;
    }
    let resolved = library::fill::resolve(&spec, &args.output).map_err(|e| e.in_file(&args.spec))?;
    // a type that leaves [depth] unused meshes as a spec without it
    let depth = fill::uses_depth(resolved.kind);
    let mesh_started = Instant::now();
    let (tets, refined) = fill::tetrahedralize(&surface, &spec, depth).map_err(|e| e.in_file(&args.mesh))?;
    let meshed = mesh_started.elapsed().as_secs_f64();
    warn_if_far(&args.mesh, tets.tets.len(), spec.tets);
    let mesh_at = |count| {
        fill::tetrahedralize(&surface, &fill::spec::FillSpec { tets: count, ..spec.clone() }, depth).map(|m| m.0)
    };
    let held = mesher::volume_check(&surface, &tets, spec.tets, &mesh_at).map_err(|e| e.in_file(&args.mesh))?;
    warn_if_lost(&args.mesh, &held);
    let distance = mesher::surface_distance(&surface, &tets).map_err(|e| e.in_file(&args.mesh))?;
    let job = Job {
        surface: &surface,
        spec: &spec,
        kind: resolved.kind,
        axes: resolved.axes,
        sources: resolved.sources,
        masks: resolved.masks,
    };
    let bar = Bar::new();
    let (model, report) = fill::fill(&job, tets, &bar).map_err(|e| e.in_file(&args.spec))?;
    bar.0.finish_and_clear();
    let total = started.elapsed().as_secs_f64();
    let encoded = lst_file::to_bytes(&model);
    io::write_bytes(&args.output, &encoded)?;
    let bytes = encoded.len();
    let p = &report.paste;
    tell!(
        "filled {} ({} tets, min dihedral {:.1}°) with {} patches of '{}' (type {}) in {total:.2} s (mesh {meshed:.2} s)",
        args.mesh.display(),
        report.tets,
        report.min_dihedral,
        p.patches,
        spec.exemplar,
        resolved.kind
    );
    tell!(
        "  layers per tet {:.1}, tets per clump {:.0}, field angle mean {:.1}° p95 {:.1}°, uncovered {}",
        p.mean_layers,
        p.mean_clump,
        p.angle_mean,
        p.angle_p95,
        p.forced
    );
    tell_distance(&distance, fill::cover_margin(&spec, depth) > 0.0, &args.output);
    if refined > 0 {
        tell!("  {refined} of the tets from refining near the depth axis, so its core is round");
    }
    if report.raised_scale > 0 {
        let share = report.raised_scale as f64 / report.tets.max(1) as f64 * 100.0;
        tell!(
            "  texture scale raised to {} tet edges in {} tets ({share:.1} %), where the field asked for less",
            crate::fill::MIN_SCALE_EDGES,
            report.raised_scale
        );
    }
    for note in &report.ignored {
        tell!("warning: {}: {note}", args.spec.display());
    }
    if let Some(share) = report.outer_share.filter(|s| *s > crate::fill::model::OUTER_WARNING) {
        tell!(
            "warning: {}: {:.0} % of the volume lies in the outer {:.0} % of depth, so the '{}' exemplar's outer \
             layer (skin, bark) fills most of the model; a depth axis or points along the body's middle give it a core",
            args.spec.display(),
            share * 100.0,
            crate::fill::model::OUTER_DEPTH * 100.0,
            spec.exemplar
        );
    }
    tell!("wrote {} ({:.0} KB)", args.output.display(), bytes as f64 / 1024.0);
    // A figure, not a result: if the volumes cannot be read it is left out.
    let seams = with_volumes(model, &args.output, job.masks).ok().and_then(|loaded| seam_strength(&loaded));
    if let Some(seams) = seams {
        tell!("  seam strength {seams:.2} (colour step across patch borders over within, central cuts)");
    }
    if let Some(path) = &args.json {
        let json = serde_json::json!({ "fill": report, "seconds": total, "mesh_seconds": meshed, "bytes": bytes, "type": resolved.kind.name(), "seam_strength": seams, "refined_tets": refined, "volume_share": held.share, "holding_tets": held.holding, "surface_distance": distance });
        io::write_bytes(path, serde_json::to_string_pretty(&json).expect("serializable").as_bytes())?;
    }
    Ok(())
}

/// How far (in mean tet edges) the tet mesh's boundary may stray from the surface before
/// `fill` says where to look.
const STRAY_EDGES: f32 = 0.5;

/// How far the tets' boundary lies from the surface, and a warning with the cut that shows
/// where the surface strays more than [`STRAY_EDGES`] from what the tets hold. Tets that
/// `cover` the solid reach past the surface on purpose (a margin carrying the texture up to
/// it): only surface points outside every tet count for them.
fn tell_distance(distance: &mesher::SurfaceDistance, cover: bool, output: &Path) {
    let edges = |d: f32| d / distance.mean_edge.max(f32::MIN_POSITIVE);
    let (stray, [x, y, z]) = if cover {
        tell!(
            "  the tets hold the surface but for points up to {:.2} tet edges out (mesh to tets {:.3}, creases \
             included), and reach past it by up to {:.2} (a margin carrying the texture); the model's shape is the \
             surface itself",
            distance.outside_edges(),
            distance.outside,
            edges(distance.from_tets)
        );
        (distance.outside_edges(), distance.outside_at)
    } else {
        let [x, y, z] = distance.at;
        tell!(
            "  tets within {:.2} tet edges of the surface (tets to mesh {:.3}, mesh to tets {:.3}, creases \
             included; farthest at {x:.4}, {y:.4}, {z:.4}); the model's shape is the surface itself",
            distance.in_edges(),
            distance.from_tets,
            distance.from_surface
        );
        (distance.in_edges(), distance.at)
    };
    if stray > STRAY_EDGES {
        tell!(
            "  over half a tet edge at {x:.4}, {y:.4}, {z:.4}: a part or a gap there is thinner than the lattice, \
             and takes its texture from the nearest tets, stretched; `solidtex cut {} --plane \
             {x:.4},{y:.4},{z:.4},0,0,1` shows it",
            output.display()
        );
    }
}

/// Warn when the tet mesh lost part of the volume (a layer or limb thinner than the lattice
/// spacing), with the tet count that keeps it.
fn warn_if_lost(mesh: &Path, held: &mesher::VolumeCheck) {
    if held.share >= mesher::HELD_VOLUME {
        return;
    }
    let lost = (1.0 - held.share) * 100.0;
    let advice = match held.holding {
        Some(n) => format!("--tets {n} (or tets = {n} in the spec) keeps it"),
        None => format!("no tet count up to {} keeps it; thicken the part", held.tried),
    };
    tell!(
        "warning: {}: the tet mesh holds {:.1} % of the mesh's volume: {lost:.1} % is in parts thinner than \
         the lattice spacing and takes its texture stretched from the nearest tets; {advice}",
        mesh.display(),
        held.share * 100.0
    );
}

/// Warn when the tet mesh is more than 15 % off the count asked for.
fn warn_if_far(mesh: &Path, got: usize, asked: usize) {
    if (got as f64 / asked as f64 - 1.0).abs() > 0.15 {
        tell!(
            "warning: {}: {got} tets for the {asked} asked; no lattice spacing comes closer on this shape \
             (a part about as thin as the spacing appears or vanishes as it changes)",
            mesh.display()
        );
    }
}

/// The mean seam strength of the model's three central axis cuts at 256² (see
/// [`render::Cut::seam_strength`]).
fn seam_strength(loaded: &Loaded) -> Option<f64> {
    let models = [(&loaded.model, &loaded.textures)];
    let bounds = render::bounds(&models);
    let centre = (bounds.0 + bounds.1) / 2.0;
    let figures: Vec<f64> = [glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z]
        .iter()
        .filter_map(|&normal| View::framing(bounds, centre, normal, 256).ok())
        .filter_map(|view| render::cut_many(&models, &view).seam_strength())
        .collect();
    (!figures.is_empty()).then(|| figures.iter().sum::<f64>() / figures.len() as f64)
}

/// Refuse a displacement `scale` that would move the surface farther than the models'
/// size (the diagonal of their box): the picture is then noise and its triangles, each
/// spread over the whole picture, take minutes to draw (exit 2).
pub(super) fn within_models(flag: &str, scale: f32, loaded: &[Loaded]) -> Result<()> {
    let (lo, hi) = render::bounds(&pairs(loaded));
    let size = lo.distance(hi);
    if scale.abs() > size {
        return Err(Error::usage(format!(
            "{flag} {scale} is larger than the models' size ({size:.3}, the diagonal of their box); allowed: -{size:.3} \
             to {size:.3} (a scale moves the surface up to half its value; a relief is a few hundredths of the size, \
             e.g. 0.08)"
        )));
    }
    Ok(())
}

/// A PNG picture of `models` (and a skin): none of them.
fn picture_output(output: &Path, models: &[PathBuf], skin: Option<&Path>) -> Result<()> {
    let inputs: Vec<&Path> = models.iter().map(PathBuf::as_path).chain(skin).collect();
    io::guard::png_output(output, &inputs)
}

fn lst_check(path: &Path) -> Result<()> {
    if path.extension().and_then(|e| e.to_str()) != Some("lst") {
        return Err(Error::usage(format!("{}: the model file must end in .lst", path.display())));
    }
    io::check_folder(path)
}

/// A progress bar on stderr.
pub(super) struct Bar(pub(super) ProgressBar);

impl Bar {
    pub(super) fn new() -> Bar {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{elapsed:>4} [{bar:40}] {percent:>3}% (about {eta} left) {msg}")
                .expect("valid template"),
        );
        Bar(bar)
    }
}

impl Progress for Bar {
    fn update(&self, stage: &str, fraction: f32) {
        self.0.set_position((fraction.clamp(0.0, 1.0) * 1000.0) as u64);
        self.0.set_message(stage.to_string());
    }
}

/// A model with its sources' volumes, masks and colour textures.
pub(super) struct Loaded {
    pub(super) model: LstModel,
    pub(super) textures: Textures,
    /// Each source's exemplar volume (every channel).
    volumes: Vec<Volume>,
    /// Where each was read.
    files: Vec<PathBuf>,
    masks: Vec<Volume>,
}

impl Loaded {
    /// The files the model reads besides itself: its sources' volumes and mask files.
    fn sources(&self, model: &Path) -> Vec<PathBuf> {
        let base = io::model_folder(model);
        let masks = self.model.sources.iter().filter_map(|s| match &s.mask {
            MaskRef::File(file) => Some(base.join(file)),
            _ => None,
        });
        self.files.iter().cloned().chain(masks).collect()
    }

    /// Textures sampling the first of `wanted` each source has; `Err` names the volume
    /// file that has none.
    fn channel(&self, wanted: &[Channel]) -> std::result::Result<Textures, &Path> {
        Textures::channel(&self.volumes, &self.masks, wanted).map_err(|i| self.files[i].as_path())
    }
}

/// A guided model (`.guided`) as a loaded filled model: its whole solid synthesized, read
/// through the field's tets (`render` of a guided model).
fn guided_loaded(path: &Path) -> Result<Loaded> {
    let filled = super::guided::filled_from_model(path)?;
    let full = Volume::from_fn([2, 2, 2], vec![Channel::A], |_, _, _, o| o[0] = 1.0)?;
    let textures = Textures::new(std::slice::from_ref(&filled.volume), std::slice::from_ref(&full));
    let (volumes, files, masks) = (vec![filled.volume], vec![path.to_path_buf()], vec![full]);
    Ok(Loaded { model: filled.model, textures, volumes, files, masks })
}

/// The guided model (`.guided`) among `models`, when one is given alone; a usage error
/// when one comes with other models (a guided model combines with none).
fn guided_model(models: &[PathBuf]) -> Result<Option<&Path>> {
    match models.iter().find(|m| io::guided_model::is_guided(m)) {
        None => Ok(None),
        Some(model) if models.len() == 1 => Ok(Some(model)),
        Some(model) => Err(usage(Error::invalid(format!(
            "{} is a guided model; it is drawn alone, not combined with other models",
            model.display()
        )))),
    }
}

fn load_model(path: &Path) -> Result<Loaded> {
    let model = lst_file::read_lst(path)?;
    let base = io::model_folder(path);
    let named = model.sources.iter().flat_map(|s| {
        let mask = match &s.mask {
            MaskRef::File(file) => Some(("mask", Path::new(file))),
            _ => None,
        };
        mask.into_iter().chain([("volume", Path::new(&s.volume))])
    });
    for (field, file) in named {
        io::model_input(path, field, &base.join(file), &base)?;
    }
    let masks = model.sources.iter().map(|s| load_mask(&s.mask, &base)).collect::<Result<Vec<_>>>()?;
    with_volumes(model, path, masks)
}

/// `model` (written to `path`) with its `masks` and its sources' volumes read.
fn with_volumes(model: LstModel, path: &Path, masks: Vec<Volume>) -> Result<Loaded> {
    let base = io::model_folder(path);
    let budget = io::budget_from_env()?;
    let files: Vec<PathBuf> = model.sources.iter().map(|s| base.join(&s.volume)).collect();
    let volumes = files.iter().map(|f| io::read_volume(f, budget)).collect::<Result<Vec<_>>>()?;
    let textures = Textures::new(&volumes, &masks);
    Ok(Loaded { model, textures, volumes, files, masks })
}

/// The channels beyond R, G, B and A that every source of every model has, in the first
/// source's order, and those some source lacks.
fn shared_channels(loaded: &[Loaded]) -> (Vec<Channel>, Vec<Channel>) {
    let colour = [Channel::R, Channel::G, Channel::B, Channel::A];
    let mut all: Vec<Channel> = Vec::new();
    for v in loaded.iter().flat_map(|l| &l.volumes) {
        for c in v.channels() {
            if !colour.contains(c) && !all.contains(c) {
                all.push(c.clone());
            }
        }
    }
    all.into_iter().partition(|c| loaded.iter().flat_map(|l| &l.volumes).all(|v| v.channel_index(c).is_some()))
}

/// The channels `--carry` names (`none`: no channel), each one of `shared` (the channels
/// every exemplar has besides R, G, B, A), in the order given.
fn carried_channels(list: &str, shared: &[Channel]) -> Result<Vec<Channel>> {
    if list.trim() == "none" {
        return Ok(Vec::new());
    }
    let mut out: Vec<Channel> = Vec::new();
    for name in list.split(',').map(str::trim) {
        let c = shared.iter().find(|c| c.name() == name).ok_or_else(|| {
            let allowed: Vec<&str> = shared.iter().map(Channel::name).collect();
            let allowed = if allowed.is_empty() { "none".to_string() } else { allowed.join(", ") + " or none" };
            let why = if ["R", "G", "B", "A"].contains(&name) {
                "R, G, B and A are always baked; --carry adds other channels"
            } else {
                "not a channel every exemplar the models use has"
            };
            usage(Error::invalid(format!("--carry {name}: {why}; allowed: {allowed}")))
        })?;
        if !out.contains(c) {
            out.push(c.clone());
        }
    }
    Ok(out)
}

/// The models at `paths` with what they read, refusing an `output` that is one of the
/// files they read (a source's volume or mask: writing it would change the models).
pub(super) fn load_models(paths: &[PathBuf], output: &Path) -> Result<Vec<Loaded>> {
    if paths.len() > render::MAX_MODELS {
        return Err(usage(Error::invalid(format!(
            "{} models given; at most {} combine in one picture or volume",
            paths.len(),
            render::MAX_MODELS
        ))));
    }
    let loaded: Vec<Loaded> = paths.iter().map(|p| load_model(p)).collect::<Result<_>>()?;
    let sources: Vec<PathBuf> = loaded.iter().zip(paths).flat_map(|(l, p)| l.sources(p)).collect();
    io::guard::not_an_input(output, &sources.iter().map(PathBuf::as_path).collect::<Vec<_>>())?;
    Ok(loaded)
}

fn pairs(loaded: &[Loaded]) -> Vec<(&LstModel, &Textures)> {
    loaded.iter().map(|l| (&l.model, &l.textures)).collect()
}

/// Largest picture side of `cut` and `view`, in pixels.
const MAX_PICTURE: usize = 4096;

/// The plane of `cut` (`None`: the default), every number checked against its range.
fn cut_values(args: &CutArgs) -> Result<Option<(glam::Vec3, glam::Vec3)>> {
    io::values::within("--size", args.size, 8, MAX_PICTURE)?;
    args.camera.checked()?;
    args.plane.as_deref().map(|text| plane("--plane", text)).transpose()
}

/// A plane PX,PY,PZ,NX,NY,NZ of `option`: a point and a normal, each number within the
/// position limit, the normal long enough to have a direction.
pub(super) fn plane(option: &str, text: &str) -> Result<(glam::Vec3, glam::Vec3)> {
    let v = io::values::numbers(option, text, &[6])?;
    io::values::positions(option, text, &v)?;
    let normal = glam::Vec3::new(v[3], v[4], v[5]);
    if normal.try_normalize().is_none() {
        return Err(Error::invalid(format!("{option} {text:?}: the normal NX,NY,NZ is zero or too small")));
    }
    Ok((glam::Vec3::new(v[0], v[1], v[2]), normal))
}

/// A point or direction X,Y,Z of `option`, each within the position limit.
fn vector(option: &str, text: &str) -> Result<glam::Vec3> {
    let v = io::values::numbers(option, text, &[3])?;
    io::values::positions(option, text, &v)?;
    Ok(glam::Vec3::new(v[0], v[1], v[2]))
}

/// The strokes, extrude direction and keep point of a stroke cut, checked.
fn stroke_values(args: &CutArgs) -> Result<(Vec<fill::carve::Stroke>, Option<glam::Vec3>)> {
    io::values::within("--size", args.size, 8, MAX_PICTURE)?;
    args.camera.checked()?;
    if let Some(scale) = args.displacement {
        io::values::within("--displacement", scale, -1000.0, 1000.0)?;
    }
    let polylines = args
        .stroke
        .iter()
        .map(|text| {
            let points = text.split([';', '/']).map(|p| vector("--stroke", p.trim())).collect::<Result<Vec<_>>>()?;
            if points.len() < 2 {
                return Err(Error::invalid(format!(
                    "--stroke {text:?}: give two or more points X,Y,Z;X,Y,Z (or X,Y,Z/X,Y,Z)"
                )));
            }
            Ok(points)
        })
        .collect::<Result<Vec<_>>>()?;
    let Some(text) = &args.extrude else {
        return Err(Error::invalid("--stroke needs --extrude NX,NY,NZ, the direction the stroke is swept along"));
    };
    let extrude = vector("--extrude", text)?;
    if extrude.try_normalize().is_none() {
        return Err(Error::invalid("--extrude: the direction NX,NY,NZ is zero or too small"));
    }
    let strokes = polylines.into_iter().map(|points| fill::carve::Stroke { points, extrude }).collect();
    let keep = args.keep.as_deref().map(|k| vector("--keep", k)).transpose()?;
    Ok((strokes, keep))
}

/// Run `solidtex cut --stroke`: a lit 3D view of the model cut along strokes.
fn run_stroke_cut(args: &CutArgs) -> Result<()> {
    let (strokes, keep) = stroke_values(args).map_err(usage)?;
    if args.models.len() > 1 {
        return Err(usage(Error::invalid("--stroke cuts one model; give one .lst")));
    }
    picture_output(&args.output, &args.models, None)?;
    let loaded = load_model(&args.models[0])?;
    let bounds = render::bounds(&[(&loaded.model, &loaded.textures)]);
    let keep = keep.unwrap_or((bounds.0 + bounds.1) / 2.0);
    let started = Instant::now();
    let camera = (args.camera.yaw, args.camera.pitch);
    if let Some(scale) = args.displacement {
        within_models("--displacement", scale, std::slice::from_ref(&loaded))?;
    }
    let relief = match args.displacement {
        None => None,
        Some(scale) => Some((channel_textures(std::slice::from_ref(&loaded), &Channel::Displacement)?, scale)),
    };
    let relief = relief.as_ref().map(|(t, scale)| fill::view::Displacement { textures: t, scale: *scale });
    let carving = fill::carve::carve(&loaded.model, &loaded.textures, &strokes, keep, camera, args.size, relief)
        .map_err(|e| e.in_file(&args.models[0]))?;
    let ms = started.elapsed().as_secs_f64() * 1000.0;
    io::write_rgb8(&args.output, &carving.picture)?;
    tell!(
        "wrote {} ({size}x{size}, {} stroke cut(s), cut faces on {:.0} % of the picture{}) in {ms:.0} ms",
        args.output.display(),
        strokes.len(),
        carving.cut_share * 100.0,
        args.displacement.map(|s| format!(", displaced by {s} x (Displacement - 0.5)")).unwrap_or_default(),
        size = args.size
    );
    Ok(())
}

/// Run `solidtex cut`.
pub fn run_cut(args: &CutArgs) -> Result<()> {
    if let Some(model) = guided_model(&args.models)? {
        let flag = [("--stroke", !args.stroke.is_empty()), ("--channel", args.channel.is_some())];
        if let Some((flag, _)) = flag.iter().find(|(_, on)| *on) {
            return Err(usage(Error::invalid(format!(
                "{flag} cuts a filled model (.lst); {} is a guided model",
                model.display()
            ))));
        }
        let plane = cut_values(args).map_err(usage)?;
        return super::guided::cut_model(model, plane, args.size, &args.output);
    }
    if !args.stroke.is_empty() {
        return run_stroke_cut(args);
    }
    let plane = cut_values(args).map_err(usage)?;
    let wanted = args.channel.as_deref().map(Channel::parse).transpose().map_err(usage)?;
    picture_output(&args.output, &args.models, None)?;
    let loaded = load_models(&args.models, &args.output)?;
    let channel = match &wanted {
        None => None,
        Some(c) => Some(channel_textures(&loaded, c)?),
    };
    let models = match &channel {
        None => pairs(&loaded),
        Some(textures) => loaded.iter().map(|l| &l.model).zip(textures).collect(),
    };
    let bounds = render::bounds(&models);
    let (point, normal) = plane.unwrap_or(((bounds.0 + bounds.1) / 2.0, glam::Vec3::Z));
    let view = View::framing(bounds, point, normal, args.size)?;
    let started = Instant::now();
    let cut = render::cut_many(&models, &view);
    let ms = started.elapsed().as_secs_f64() * 1000.0;
    io::write_rgb8(&args.output, &cut.picture())?;
    let (shown, size) = (args.output.display(), args.size);
    tell!("wrote {shown} ({size}x{size}, {:.0} % inside) in {ms:.1} ms", cut.inside_share() * 100.0);
    if let Some(c) = &wanted {
        let inside = cut.pixels.iter().filter(|p| p[3] > 0.0).map(|p| p[0]);
        let (lo, hi) = inside.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
        tell!("  channel {c}: {lo:.3} to {hi:.3} inside (shown 0 black to 1 white)");
    } else if let Some(seams) = cut.seam_strength() {
        tell!("  seam strength {seams:.2} (colour step across patch borders over within)");
    }
    Ok(())
}

/// Per model, textures sampling `channel`; the error names the volume that lacks it and
/// the channels it has.
pub(super) fn channel_textures(loaded: &[Loaded], channel: &Channel) -> Result<Vec<Textures>> {
    loaded
        .iter()
        .map(|l| {
            l.channel(std::slice::from_ref(channel)).map_err(|file| {
                let has = l.files.iter().position(|f| f == file).map(|i| l.volumes[i].channels()).unwrap_or_default();
                let names: Vec<&str> = has.iter().map(Channel::name).collect();
                Error::invalid(format!(
                    "{}: the exemplar has no channel {channel}; it has {}",
                    file.display(),
                    names.join(", ")
                ))
            })
        })
        .collect()
}

/// The settings of `render`, every number checked against its range.
fn render_settings(args: &RenderArgs) -> Result<translucent::Settings> {
    io::values::within("--size", args.size, 8, MAX_PICTURE)?;
    args.camera.checked()?;
    io::values::within("--opacity", args.opacity, 0.0, 0.9999)?;
    io::values::within("--slices", args.slices, 16, 4096)?;
    let cutaway = args.cutaway.as_deref().map(|text| plane("--cutaway", text)).transpose()?;
    let v = io::values::numbers("--levels", &args.levels, &[2])?;
    if !(0.0 <= v[0] && v[0] < v[1] && v[1] <= 1.0) {
        return Err(Error::invalid(format!("--levels {:?}: LO,HI must rise within 0 to 1", args.levels)));
    }
    let (yaw, pitch) = (args.camera.yaw, args.camera.pitch);
    let (size, slices, opacity) = (args.size, args.slices, args.opacity);
    let levels = (v[0], v[1]);
    let b = io::values::numbers("--background", &args.background, &[3])?;
    if b.iter().any(|c| !(0.0..=255.0).contains(c)) {
        return Err(Error::invalid(format!("--background {:?}: R,G,B must each be 0 to 255", args.background)));
    }
    let background = [b[0], b[1], b[2]].map(|c| c.round() as u8);
    Ok(translucent::Settings { yaw, pitch, size, slices, opacity, cutaway, levels, background })
}

/// Run `solidtex render`.
pub fn run_render(args: &RenderArgs) -> Result<()> {
    let settings = render_settings(args).map_err(usage)?;
    picture_output(&args.output, &args.models, args.skin.as_deref())?;
    let (needed, budget) = (translucent::memory_needed(settings.size), io::budget_from_env()?);
    if needed > budget {
        return Err(Error::invalid(format!(
            "--size {}: rendering needs about {} MB, more than the budget of {} MB; lower --size or raise the budget \
             with SOLIDTEX_MAX_BYTES",
            settings.size,
            needed >> 20,
            budget >> 20
        )));
    }
    let skin = args.skin.as_deref().map(SkinInput::file).transpose()?;
    let loaded = match guided_model(&args.models)? {
        Some(model) => {
            super::guided::check_picture_of_model(model, &args.output)?;
            if let Some((path, coloured)) = &skin {
                // the guided solid takes long to make: the skin is checked against its mesh first
                let mesh = io::mesh_file::read_mesh(&io::guided_model::read(model)?.mesh)?;
                skin_near(path, &coloured.mesh, mesh.bounds(), None)?;
            }
            vec![guided_loaded(model)?]
        }
        None => load_models(&args.models, &args.output)?,
    };
    let wanted = matches!(args.density, None | Some(DensityFrom::Alpha));
    let channel: std::result::Result<Vec<Textures>, &Path> =
        if wanted { loaded.iter().map(|l| l.channel(&render::density_channels())).collect() } else { Ok(Vec::new()) };
    let from = match (args.density, &channel) {
        (Some(DensityFrom::Alpha), Err(volume)) => {
            return Err(Error::invalid(format!(
                "{}: --density alpha needs a Density or A channel in every exemplar and this one has neither; \
                 allowed instead: uniform, dark, light",
                volume.display()
            )));
        }
        (Some(chosen), _) => chosen,
        (None, Ok(_)) => DensityFrom::Alpha,
        (None, Err(_)) => DensityFrom::Uniform,
    };
    let channel = channel.unwrap_or_default();
    let density = match from {
        DensityFrom::Uniform => translucent::Density::Uniform,
        DensityFrom::Dark => translucent::Density::Dark,
        DensityFrom::Light => translucent::Density::Light,
        DensityFrom::Alpha => translucent::Density::Channel(&channel),
    };
    io::values::within("--skin-opacity", args.skin_opacity, 0.0, 1.0).map_err(usage)?;
    let input = skin.map(|file| SkinInput::read(file, &loaded, None)).transpose()?;
    let lookup = input.as_ref().map(SkinInput::lookup);
    let layer = input
        .as_ref()
        .zip(lookup.as_ref())
        .map(|(input, lookup)| translucent::SkinLayer { skin: input.skin(lookup), opacity: args.skin_opacity });
    let started = Instant::now();
    let bar = Bar::new();
    let rendering = translucent::render_with(&pairs(&loaded), density, &settings, layer, &bar);
    bar.0.finish_and_clear();
    let rendering = rendering?;
    let seconds = started.elapsed().as_secs_f64();
    io::write_rgb8(&args.output, &rendering.picture)?;
    let name = format!("{from:?}").to_lowercase();
    let why = if args.density.is_none() && from == DensityFrom::Uniform {
        " (the exemplars have no Density or A channel; --density dark or light takes it from the colour)"
    } else {
        ""
    };
    tell!(
        "wrote {} ({size}x{size}, {} slices, density {name}{why}) in {seconds:.2} s",
        args.output.display(),
        rendering.slices,
        size = args.size
    );
    if rendering.opacity.iter().all(|o| *o < 0.5 / 255.0) {
        let reason = if args.opacity == 0.0 {
            "--opacity 0 makes them clear"
        } else if args.cutaway.is_some() {
            "the cut-away keeps no part of them in view"
        } else if settings.levels != (0.0, 1.0) {
            "--levels leave none of their material dense"
        } else {
            "their material lets all the light through"
        };
        tell!("warning: the picture shows the background alone: {reason}");
    }
    Ok(())
}

/// Voxels along a bake's longest side when `--res` is not given.
const DEFAULT_BAKE_RES: usize = 128;

/// Run `solidtex bake`.
pub fn run_bake(args: &BakeArgs) -> Result<()> {
    let res = args.res.unwrap_or(DEFAULT_BAKE_RES);
    io::values::within("--res", res, 2, 512).map_err(usage)?;
    if let Some(model) = guided_model(&args.models)? {
        if args.res.is_some() {
            return Err(usage(Error::invalid(format!(
                "--res sets the bake of filled models (.lst); {} is a guided model, baked at the resolution it was \
                 made with (its res)",
                model.display()
            ))));
        }
        if args.carry.is_some() {
            return Err(usage(Error::invalid(format!(
                "--carry chooses the channels of filled models (.lst); {} is a guided model (its solid carries its \
                 exemplar's colours and alpha)",
                model.display()
            ))));
        }
        return super::guided::from_model(model, super::guided::Action::Solid, 256, &args.output);
    }
    let models: Vec<&Path> = args.models.iter().map(PathBuf::as_path).collect();
    io::check_output(&args.output, &models)?;
    let loaded = load_models(&args.models, &args.output)?;
    let (shared, left_out) = shared_channels(&loaded);
    let shared = match args.carry.as_deref() {
        None => {
            for c in &left_out {
                tell!("warning: channel {c} is not in every exemplar the models use; it is left out of the bake");
            }
            shared
        }
        Some(list) => carried_channels(list, &shared)?,
    };
    let textures = shared.iter().map(|c| channel_textures(&loaded, c)).collect::<Result<Vec<_>>>()?;
    let carried: Vec<render::Carried> = shared
        .iter()
        .zip(&textures)
        .map(|(c, t)| render::Carried { channel: c.clone(), textures: t.iter().collect() })
        .collect();
    let started = Instant::now();
    let volume = render::bake(&pairs(&loaded), &carried, res, io::budget_from_env()?)?;
    // the models and their textures are done with: free them before the writer copies the
    // volume into its own layout
    drop(carried);
    drop((textures, loaded));
    super::write_volume(&args.output, &volume)?;
    let [x, y, z] = volume.dims();
    let stored = io::stored_channels(&args.output, &volume);
    let names: Vec<&str> = stored.iter().map(Channel::name).collect();
    tell!(
        "wrote {} ({x}x{y}x{z}, {}) in {:.2} s",
        args.output.display(),
        names.join(", "),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// A skin read to be drawn on models: the coloured mesh, how far from it a surface point
/// may lie, and the models' Depth textures when every exemplar has the channel (else the
/// skin covers the whole surface within reach).
struct SkinInput {
    coloured: io::mesh_file::ColouredMesh,
    within: f32,
    depth: Option<Vec<Textures>>,
}

impl SkinInput {
    /// The skin file `path`, read before any model is loaded or synthesized, so a missing or
    /// broken skin stops the command at once.
    fn file(path: &Path) -> Result<(&Path, io::mesh_file::ColouredMesh)> {
        Ok((path, io::mesh_file::read_coloured_ply(path)?))
    }

    fn read(
        (path, coloured): (&Path, io::mesh_file::ColouredMesh),
        loaded: &[Loaded],
        displacement: Option<f32>,
    ) -> Result<SkinInput> {
        let within = skin_reach(path, &coloured.mesh, &pairs(loaded), displacement)?;
        let depth = channel_textures(loaded, &Channel::Depth).ok();
        Ok(SkinInput { coloured, within, depth })
    }

    fn lookup(&self) -> crate::surface::SkinLookup<'_> {
        crate::surface::SkinLookup::new(&self.coloured.mesh, &self.coloured.colours)
    }

    fn skin<'a>(&'a self, lookup: &'a crate::surface::SkinLookup<'a>) -> crate::fill::view::Skin<'a> {
        crate::fill::view::Skin { lookup, within: self.within, depth: self.depth.as_deref() }
    }
}

/// `solidtex view SKIN.ply`: the skin alone, as `solidtex surface` wrote it.
fn view_skin(args: &ViewArgs, path: &Path) -> Result<()> {
    if args.skin.is_some() || args.displacement.is_some() || args.flat || args.crease.is_some() {
        return Err(Error::usage(format!(
            "{}: a skin is drawn as it is; --skin, --displacement, --flat and --crease apply to filled models (.lst)",
            path.display()
        )));
    }
    let skin = io::mesh_file::read_coloured_ply(path)?;
    let started = Instant::now();
    let camera = (args.camera.yaw, args.camera.pitch);
    let picture = crate::fill::view::skin_picture(&skin.mesh, &skin.colours, camera, args.size);
    io::write_rgb8(&args.output, &picture)?;
    tell!("wrote {} in {:.0} ms", args.output.display(), started.elapsed().as_secs_f64() * 1000.0);
    Ok(())
}

/// How far from the skin a surface point may lie and take its colour: 3 % of the models'
/// box (the tet mesh's faces are chords of the surface the skin was grown on), plus half the
/// displacement. A skin whose box differs from the models' by more than that was grown on
/// another mesh and is refused.
fn skin_reach(
    path: &Path,
    skin: &crate::mesh::Mesh,
    models: &[(&LstModel, &Textures)],
    displacement: Option<f32>,
) -> Result<f32> {
    skin_near(path, skin, render::bounds(models), displacement)
}

/// [`skin_reach`] against the box `(lo, hi)` of the models.
fn skin_near(
    path: &Path,
    skin: &crate::mesh::Mesh,
    (lo, hi): (glam::Vec3, glam::Vec3),
    displacement: Option<f32>,
) -> Result<f32> {
    let within = 0.03 * lo.distance(hi) + displacement.map_or(0.0, |d| d.abs() * crate::fill::view::MIDLEVEL);
    let (slo, shi) = skin.bounds();
    let apart = (slo - lo).abs().max((shi - hi).abs()).max_element();
    if apart > within {
        return Err(Error::file(
            path,
            format!(
                "the skin spans {slo} to {shi} but the models {lo} to {hi}: grow it on the mesh the model was filled from"
            ),
        ));
    }
    Ok(within)
}

/// Run `solidtex view`.
pub fn run_view(args: &ViewArgs) -> Result<()> {
    let checks = || -> Result<()> {
        io::values::within("--size", args.size, 8, MAX_PICTURE)?;
        args.camera.checked()?;
        if let Some(crease) = args.crease {
            io::values::within("--crease", crease, 0.0, 180.0)?;
        }
        if let Some(scale) = args.displacement {
            io::values::within("--displacement", scale, -1000.0, 1000.0)?;
        }
        Ok(())
    };
    checks().map_err(usage)?;
    if let Some(model) = guided_model(&args.models)? {
        let flag = [("--displacement", args.displacement.is_some()), ("--skin", args.skin.is_some())];
        if let Some((flag, _)) = flag.iter().find(|(_, on)| *on) {
            return Err(usage(Error::invalid(format!(
                "{flag} draws on a filled model (.lst); {} is a guided model",
                model.display()
            ))));
        }
        let shading = if args.flat {
            Shading::Flat
        } else {
            Shading::Smooth { crease: args.crease.unwrap_or(crate::fill::view::DEFAULT_CREASE) }
        };
        let view = crate::fill::view::View { camera: (args.camera.yaw, args.camera.pitch), size: args.size, shading };
        return super::guided::from_model(model, super::guided::Action::View(view), args.size, &args.output);
    }
    picture_output(&args.output, &args.models, args.skin.as_deref())?;
    let is_ply = |p: &PathBuf| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    match args.models.as_slice() {
        [one] if is_ply(one) => return view_skin(args, one),
        [_, _, ..] if args.models.iter().any(is_ply) => {
            return Err(usage(Error::invalid(format!(
                "{}: a skin (.ply) is viewed alone; filled models (.lst) are viewed together",
                args.models.iter().find(|p| is_ply(p)).expect("a .ply").display()
            ))));
        }
        _ => {}
    }
    let skin = args.skin.as_deref().map(SkinInput::file).transpose()?;
    let loaded = load_models(&args.models, &args.output)?;
    let started = Instant::now();
    let shading = if args.flat {
        Shading::Flat
    } else {
        Shading::Smooth { crease: args.crease.unwrap_or(crate::fill::view::DEFAULT_CREASE) }
    };
    let camera = (args.camera.yaw, args.camera.pitch);
    if let Some(scale) = args.displacement {
        within_models("--displacement", scale, &loaded)?;
    }
    let relief = match args.displacement {
        None => None,
        Some(scale) => Some((channel_textures(&loaded, &Channel::Displacement)?, scale)),
    };
    let displacement =
        relief.as_ref().map(|(textures, scale)| crate::fill::view::Displacement { textures, scale: *scale });
    let input = skin.map(|file| SkinInput::read(file, &loaded, args.displacement)).transpose()?;
    let lookup = input.as_ref().map(SkinInput::lookup);
    let skin = input.as_ref().zip(lookup.as_ref()).map(|(input, lookup)| input.skin(lookup));
    let bar = Bar::new();
    let view = crate::fill::view::View { camera, size: args.size, shading };
    let drawn = crate::fill::view::surfaces_with(&pairs(&loaded), displacement, skin, view, &bar);
    bar.0.finish_and_clear();
    let (picture, triangles) = drawn?;
    let note = args
        .displacement
        .map(|scale| format!("  displaced by {scale} x (Displacement - 0.5) along the normal, {triangles} triangles"));
    let ms = started.elapsed().as_secs_f64() * 1000.0;
    io::write_rgb8(&args.output, &picture)?;
    tell!("wrote {} in {ms:.0} ms", args.output.display());
    if let Some(note) = note {
        tell!("{note}");
    }
    Ok(())
}
