//! `solidtex fill`, `cut`, `bake` and `view`: fill a closed mesh with library exemplars and
//! look at the result.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::fill::render::{self, Textures, View};
use crate::fill::spec::{self, FillSpec};
use crate::fill::{self, Job, LstModel, MaskRef, Source, mesher};
use crate::io::{self, fill_spec, lst_file, manifest};
use crate::mask::Layer;
use crate::progress::Progress;
use crate::volume::{Axis, Volume};
use crate::{TextureType, cli::build};
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

/// The arguments of `solidtex cut`.
#[derive(Debug, clap::Args)]
pub struct CutArgs {
    /// One or more models (.lst); several are combined, the first listed wins where they overlap.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// The plane as PX,PY,PZ,NX,NY,NZ (a point and a normal, each -1000000 to 1000000, the
    /// normal not zero; default: through the centre, normal z).
    #[arg(long, allow_hyphen_values = true)]
    pub plane: Option<String>,
    /// Picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 512)]
    pub size: usize,
    /// The PNG to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The arguments of `solidtex bake`.
#[derive(Debug, clap::Args)]
pub struct BakeArgs {
    /// One or more models (.lst), combined as in `cut`.
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// Voxels along the longest side, 2 to 512.
    #[arg(long, default_value_t = 128)]
    pub res: usize,
    /// The volume to write (RGBA; alpha 1 inside the model).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The arguments of `solidtex view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
    /// The model (.lst).
    pub model: PathBuf,
    /// Degrees around the vertical axis, -360 to 360.
    #[arg(long, default_value_t = 35.0, allow_hyphen_values = true)]
    pub yaw: f32,
    /// Degrees above the horizon, -90 to 90.
    #[arg(long, default_value_t = 25.0, allow_hyphen_values = true)]
    pub pitch: f32,
    /// Picture size in pixels, 8 to 4096.
    #[arg(long, default_value_t = 512)]
    pub size: usize,
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
    let mut spec = fill_spec::read_fill_spec(&args.spec)?;
    spec.tets = args.tets.unwrap_or(spec.tets);
    spec.seed = args.seed.unwrap_or(spec.seed);
    let surface = io::mesh_file::read_mesh(&args.mesh)?.canonical();
    let started = Instant::now();
    let tets = mesher::tetrahedralize(&surface, spec.tets).map_err(|e| e.in_file(&args.mesh))?;
    let meshed = started.elapsed().as_secs_f64();
    let resolved = resolve(&spec, &args.output)?;
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
    lst_file::write_lst(&args.output, &model)?;
    let bytes = lst_file::to_bytes(&model).len();
    let p = &report.paste;
    eprintln!(
        "filled {} ({} tets, min dihedral {:.1}°) with {} patches of '{}' (type {}) in {total:.2} s (mesh {meshed:.2} s)",
        args.mesh.display(),
        report.tets,
        report.min_dihedral,
        p.patches,
        spec.exemplar,
        resolved.kind
    );
    eprintln!(
        "  layers per tet {:.1}, tets per clump {:.0}, field angle mean {:.1}° p95 {:.1}°, uncovered {}",
        p.mean_layers, p.mean_clump, p.angle_mean, p.angle_p95, p.forced
    );
    eprintln!("wrote {} ({:.0} KB)", args.output.display(), bytes as f64 / 1024.0);
    if let Some(path) = &args.json {
        let json = serde_json::json!({ "fill": report, "seconds": total, "mesh_seconds": meshed, "bytes": bytes, "type": resolved.kind.name() });
        io::write_bytes(path, serde_json::to_string_pretty(&json).expect("serializable").as_bytes())?;
    }
    Ok(())
}

fn lst_check(path: &Path) -> Result<()> {
    if path.extension().and_then(|e| e.to_str()) != Some("lst") {
        return Err(Error::usage(format!("{}: the model file must end in .lst", path.display())));
    }
    io::check_folder(path)
}

struct Bar(ProgressBar);

impl Bar {
    fn new() -> Bar {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{elapsed:>4} [{bar:40}] {percent:>3}% {msg}").expect("valid template"),
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

/// The spec's exemplars turned into a type, texture axes, sources and masks.
struct Resolved {
    kind: TextureType,
    axes: [usize; 3],
    sources: Vec<Source>,
    masks: Vec<Volume>,
}

fn resolve(spec: &FillSpec, model_path: &Path) -> Result<Resolved> {
    let plan = manifest::read_plan(&spec.library)?;
    let mut names = vec![spec.exemplar.clone()];
    names.extend(spec.pastes.iter().map(|p| p.exemplar.clone()));
    for name in &names {
        if !plan.entries.iter().any(|e| &e.name == name) {
            let known: Vec<&str> = plan.entries.iter().map(|e| e.name.as_str()).collect();
            return Err(Error::invalid(format!(
                "exemplar '{name}' is not in the library {}; it has: {}",
                spec.library.display(),
                known.join(", ")
            )));
        }
    }
    ensure_built(spec, &names)?;
    let entry = plan.entries.iter().find(|e| e.name == spec.exemplar).expect("checked above");
    let volume = load_built(spec, &spec.exemplar)?;
    let declared = entry.texture_type.or(volume.meta.texture_type);
    let kind = match (spec.texture_type, declared) {
        (Some(t), _) | (None, Some(t)) => t,
        (None, None) => crate::classify::classify(&volume)?.texture_type,
    };
    let axes = spec::texture_axes(&volume, kind, spec.axes)?;
    let size = *volume.dims().iter().max().expect("three dims");
    let base = model_path.parent().unwrap_or(Path::new("."));
    let mut sources = Vec::new();
    let layered = matches!(kind, TextureType::T1b | TextureType::T2b);
    let layers: &[Option<Layer>] =
        if layered { &[Some(Layer::Outer), Some(Layer::Middle), Some(Layer::Inner)] } else { &[None] };
    for layer in layers {
        sources.push(source(spec, &spec.exemplar, *layer, Axis::ALL[axes[0]], size, base));
    }
    for p in &spec.pastes {
        let v = load_built(spec, &p.exemplar)?;
        sources.push(source(spec, &p.exemplar, None, Axis::Z, *v.dims().iter().max().expect("dims"), base));
    }
    let masks = sources.iter().map(|s| load_mask(&s.mask, base)).collect::<Result<Vec<_>>>()?;
    Ok(Resolved { kind, axes, sources, masks })
}

/// Builds (cached) the exemplars the fill needs when their volumes are missing.
fn ensure_built(spec: &FillSpec, names: &[String]) -> Result<()> {
    let missing: Vec<String> = names.iter().filter(|n| !built_path(spec, n).exists()).cloned().collect();
    if missing.is_empty() {
        return Ok(());
    }
    eprintln!("building {} into {} first", missing.join(", "), spec.built.display());
    build::run(&build::BuildArgs {
        manifest: spec.library.clone(),
        output: spec.built.clone(),
        force: false,
        only: missing,
        shard: None,
        merge: Vec::new(),
        progress_lines: false,
    })
}

fn built_path(spec: &FillSpec, name: &str) -> PathBuf {
    spec.built.join(format!("{name}.exr"))
}

fn load_built(spec: &FillSpec, name: &str) -> Result<Volume> {
    io::read_volume(&built_path(spec, name), io::budget_from_env()?)
}

fn source(spec: &FillSpec, name: &str, layer: Option<Layer>, depth: Axis, size: usize, base: &Path) -> Source {
    let file = match layer {
        Some(l) => spec.built.join(format!("{name}.masks")).join(format!("{}.exr", l.name())),
        None => spec.built.join(format!("{name}.mask.exr")),
    };
    let (falloff, seed) = (spec.mask_falloff, spec.seed);
    let mask = match layer {
        _ if file.exists() => MaskRef::File(relative(&file, base)),
        Some(layer) => MaskRef::Layered { layer, depth, size, falloff, seed },
        None => MaskRef::Splotch { size, falloff, seed },
    };
    Source { exemplar: name.to_string(), volume: relative(&built_path(spec, name), base), mask }
}

fn load_mask(mask: &MaskRef, base: &Path) -> Result<Volume> {
    match (mask.generate(), mask) {
        (Some(generated), _) => generated,
        (None, MaskRef::File(path)) => io::read_volume(&base.join(path), io::budget_from_env()?),
        (None, _) => unreachable!("only files are not generated"),
    }
}

/// `target` relative to the folder `base` (both resolved), or absolute if that fails.
fn relative(target: &Path, base: &Path) -> String {
    let absolute = |p: &Path| std::path::absolute(p).ok();
    let (Some(t), Some(b)) = (absolute(target), absolute(base)) else {
        return target.to_string_lossy().into_owned();
    };
    let (t, b): (Vec<_>, Vec<_>) = (t.components().collect(), b.components().collect());
    let common = t.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut out = PathBuf::new();
    (common..b.len()).for_each(|_| out.push(".."));
    t[common..].iter().for_each(|c| out.push(c));
    out.to_string_lossy().into_owned()
}

/// A model with the textures of its sources.
struct Loaded {
    model: LstModel,
    textures: Textures,
}

fn load_model(path: &Path) -> Result<Loaded> {
    let model = lst_file::read_lst(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let budget = io::budget_from_env()?;
    let colour =
        model.sources.iter().map(|s| io::read_volume(&base.join(&s.volume), budget)).collect::<Result<Vec<_>>>()?;
    let masks = model.sources.iter().map(|s| load_mask(&s.mask, base)).collect::<Result<Vec<_>>>()?;
    let textures = Textures::new(&colour, &masks);
    Ok(Loaded { model, textures })
}

fn load_models(paths: &[PathBuf]) -> Result<Vec<Loaded>> {
    paths.iter().map(|p| load_model(p)).collect()
}

fn pairs(loaded: &[Loaded]) -> Vec<(&LstModel, &Textures)> {
    loaded.iter().map(|l| (&l.model, &l.textures)).collect()
}

/// Largest picture side of `cut` and `view`, in pixels.
const MAX_PICTURE: usize = 4096;

/// The plane of `cut` (`None`: the default), every number checked against its range.
fn cut_values(args: &CutArgs) -> Result<Option<(glam::Vec3, glam::Vec3)>> {
    io::values::within("--size", args.size, 8, MAX_PICTURE)?;
    let Some(text) = &args.plane else { return Ok(None) };
    let v = io::values::numbers("--plane", text, &[6])?;
    io::values::positions("--plane", text, &v)?;
    let normal = glam::Vec3::new(v[3], v[4], v[5]);
    if normal == glam::Vec3::ZERO {
        return Err(Error::invalid(format!("--plane {text:?}: the normal NX,NY,NZ is zero")));
    }
    Ok(Some((glam::Vec3::new(v[0], v[1], v[2]), normal)))
}

/// Run `solidtex cut`.
pub fn run_cut(args: &CutArgs) -> Result<()> {
    let plane = cut_values(args).map_err(usage)?;
    io::check_folder(&args.output)?;
    let loaded = load_models(&args.models)?;
    let models = pairs(&loaded);
    let bounds = render::bounds(&models);
    let (point, normal) = plane.unwrap_or(((bounds.0 + bounds.1) / 2.0, glam::Vec3::Z));
    let view = View::framing(bounds, point, normal, args.size)?;
    let started = Instant::now();
    let cut = render::cut_many(&models, &view);
    let ms = started.elapsed().as_secs_f64() * 1000.0;
    io::write_rgb8(&args.output, &cut.picture())?;
    let (shown, size) = (args.output.display(), args.size);
    eprintln!("wrote {shown} ({size}x{size}, {:.0} % inside) in {ms:.1} ms", cut.inside_share() * 100.0);
    Ok(())
}

/// Run `solidtex bake`.
pub fn run_bake(args: &BakeArgs) -> Result<()> {
    io::values::within("--res", args.res, 2, 512).map_err(usage)?;
    let models: Vec<&Path> = args.models.iter().map(PathBuf::as_path).collect();
    io::check_output(&args.output, &models)?;
    let loaded = load_models(&args.models)?;
    let started = Instant::now();
    let volume = render::bake(&pairs(&loaded), args.res, io::budget_from_env()?)?;
    io::write_volume(&args.output, &volume)?;
    let [x, y, z] = volume.dims();
    eprintln!("wrote {} ({x}x{y}x{z}) in {:.2} s", args.output.display(), started.elapsed().as_secs_f64());
    Ok(())
}

/// Run `solidtex view`.
pub fn run_view(args: &ViewArgs) -> Result<()> {
    let checks = || -> Result<()> {
        io::values::within("--size", args.size, 8, MAX_PICTURE)?;
        io::values::within("--yaw", args.yaw, -360.0, 360.0)?;
        io::values::within("--pitch", args.pitch, -90.0, 90.0)?;
        Ok(())
    };
    checks().map_err(usage)?;
    io::check_folder(&args.output)?;
    let loaded = load_model(&args.model)?;
    let started = Instant::now();
    let picture = crate::fill::view::surface(&loaded.model, &loaded.textures, args.yaw, args.pitch, args.size);
    let ms = started.elapsed().as_secs_f64() * 1000.0;
    io::write_rgb8(&args.output, &picture)?;
    eprintln!("wrote {} in {ms:.0} ms", args.output.display());
    Ok(())
}

/// The fill preview of the terminal UI: a drawn shape filled with library exemplar `name`
/// (built into `output` first if needed) — a fruit with its axis as the innermost part for
/// the depth-varying types and strokes along it, a block with strokes along x for 1-a, a
/// fruit for type 0 — at 2,500 tets, with the textures to cut it.
pub fn preview_fill(manifest: &Path, output: &Path, name: &str) -> Result<crate::fill::FillPreview> {
    let started = Instant::now();
    let mut spec = FillSpec::new(name);
    spec.library = manifest.to_path_buf();
    spec.built = output.to_path_buf();
    spec.tets = 2500;
    let probe = resolve(&spec, &output.join("preview.lst"))?;
    let (shape, axis) = match probe.kind {
        TextureType::T1a => ("block", vec![glam::Vec3::new(-0.9, 0.0, 0.0), glam::Vec3::new(0.9, 0.0, 0.0)]),
        _ => ("fruit", vec![glam::Vec3::new(-0.75, 0.0, 0.0), glam::Vec3::new(0.75, 0.0, 0.0)]),
    };
    if matches!(probe.kind, TextureType::T1b | TextureType::T2a | TextureType::T2b) {
        spec.depth.axes = vec![axis.clone()];
    }
    spec.directions = vec![axis];
    let surface = crate::mesh::shapes::named(shape).expect("a drawn shape").canonical();
    let tets = mesher::tetrahedralize(&surface, spec.tets)?;
    let job = Job {
        surface: &surface,
        spec: &spec,
        kind: probe.kind,
        axes: probe.axes,
        sources: probe.sources.clone(),
        masks: probe.masks.clone(),
    };
    let (model, report) = fill::fill(&job, tets, &crate::progress::NoProgress)?;
    let colour = probe.sources.iter().map(|s| load_built(&spec, &s.exemplar)).collect::<Result<Vec<_>>>()?;
    let textures = Textures::new(&colour, &probe.masks);
    let summary = format!(
        "{name} (type {}) in a {shape}: {} tets, {} patches, {:.2} s",
        probe.kind,
        report.tets,
        report.paste.patches,
        started.elapsed().as_secs_f64()
    );
    Ok(crate::fill::FillPreview { model, textures, summary })
}
