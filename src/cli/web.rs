//! `solidtex web`: volumes, filled models or a skin as one self-contained HTML page with an
//! interactive 3D view (see docs/viewer.md).

use super::commands::usage;
use super::fill::{Loaded, load_models};
use crate::error::{Error, Result};
use crate::fill::LstModel;
use crate::fill::render::Textures;
use crate::io::web::MAX_SIDE;
use crate::io::{self, web};
use crate::volume::Volume;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Largest page for filled models when `--max-mb` is not given, in megabytes.
const MAX_MB: usize = 8;

/// The arguments of `solidtex web`.
#[derive(Debug, clap::Args)]
pub struct WebArgs {
    /// Volumes (.exr, .nrrd, .vol, .png, .dds, .vdb, a PNG folder; a picker chooses among
    /// them), or filled models (.lst, shown together), or one skin (.ply from `solidtex
    /// surface`).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Voxels along the longest side of the 3D texture baked from filled models, 16 to 256
    /// (lowered until the page fits --max-mb) [default: 128]. Only for filled models.
    #[arg(long)]
    pub res: Option<usize>,
    /// Largest page for filled models, in megabytes (1 to 64) [default: 8]. Only for filled
    /// models.
    #[arg(long)]
    pub max_mb: Option<usize>,
    /// The page's title (default: the inputs' names).
    #[arg(long)]
    pub title: Option<String>,
    /// The .html page to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// What the inputs are.
enum Kind {
    Volumes,
    Models,
    Skin,
}

/// Run `solidtex web`.
pub fn run(args: &WebArgs) -> Result<()> {
    let res = io::values::within("--res", args.res.unwrap_or(web::FILL_RES), 16, MAX_SIDE).map_err(usage)?;
    let max_mb = io::values::within("--max-mb", args.max_mb.unwrap_or(MAX_MB), 1, 64).map_err(usage)?;
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    let kind = kind(&inputs)?;
    if let (Kind::Volumes | Kind::Skin, Some(flag)) =
        (&kind, [("--res", args.res), ("--max-mb", args.max_mb)].into_iter().find_map(|(f, v)| v.map(|_| f)))
    {
        return Err(Error::usage(format!(
            "{flag} sets the bake of filled models (.lst); volumes and skins are shown as they are (up to \
             {MAX_SIDE} voxels per side)"
        )));
    }
    super::guided::not_taken_by("web", &inputs, " and open the volume: `solidtex web solid.exr -o page.html`")?;
    io::guard::file_output(&args.output, &inputs, &["html", "htm"], "an HTML page")?;
    let title = args.title.clone().unwrap_or_else(|| names(&inputs).join(", "));
    let started = Instant::now();
    let (page, what) = match kind {
        Kind::Volumes => volumes(&inputs, &title)?,
        Kind::Models => models(args, &title, res, max_mb)?,
        Kind::Skin => skin(inputs[0], &title)?,
    };
    io::write_bytes(&args.output, page.as_bytes())?;
    tell!(
        "wrote {} ({what}; {:.1} MB) in {:.2} s; open it in a browser",
        args.output.display(),
        page.len() as f64 / 1e6,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// What the page calls each input: its file's stem, or its path as given where two stems
/// are alike.
fn names(inputs: &[&Path]) -> Vec<String> {
    let stems: Vec<String> = inputs.iter().map(|p| stem(p)).collect();
    let alike = |s: &String| stems.iter().filter(|t| *t == s).count() > 1;
    stems.iter().zip(inputs).map(|(s, p)| if alike(s) { p.display().to_string() } else { s.clone() }).collect()
}

fn stem(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| path.display().to_string())
}

fn extension(path: &Path) -> String {
    path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default()
}

/// All models, one skin, or all volumes; a mix is a usage error.
fn kind(inputs: &[&Path]) -> Result<Kind> {
    let count = |ext: &str| inputs.iter().filter(|p| extension(p) == ext).count();
    let (lst, ply) = (count("lst"), count("ply"));
    match (lst, ply) {
        (0, 0) => Ok(Kind::Volumes),
        (n, 0) if n == inputs.len() => Ok(Kind::Models),
        (0, 1) if inputs.len() == 1 => Ok(Kind::Skin),
        (0, n) if n == inputs.len() => Err(Error::usage(format!("{n} skins given; a page shows one skin (.ply)"))),
        _ => Err(Error::usage(format!(
            "give volumes, or filled models (.lst), or one skin (.ply), not a mix: {}",
            inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
        ))),
    }
}

fn volumes(inputs: &[&Path], title: &str) -> Result<(String, String)> {
    let budget = io::budget_from_env()?;
    let read: Vec<Volume> = inputs.iter().map(|p| io::read_volume(p, budget)).collect::<Result<_>>()?;
    let mut shown = Vec::with_capacity(read.len());
    for (path, volume) in inputs.iter().zip(&read) {
        let (small, k) = web::within_side(volume, MAX_SIDE)?;
        if k > 1 {
            let [x, y, z] = small.dims();
            tell!(
                "{} is larger than {MAX_SIDE} per side: the page shows one voxel in {k} along each axis ({x}x{y}x{z})",
                path.display()
            );
        }
        shown.push((small, k));
    }
    let named: Vec<web::NamedVolume> = names(inputs)
        .into_iter()
        .zip(&shown)
        .map(|(name, (volume, k))| {
            let name = if *k > 1 { format!("{name} (1 voxel in {k})") } else { name };
            web::NamedVolume { name, volume }
        })
        .collect();
    let page = web::volumes_page(title, &named)?;
    Ok((page, format!("{} volume{}", read.len(), if read.len() == 1 { "" } else { "s" })))
}

/// Filled models: baked at `--res`, lowered until the page fits `--max-mb`.
fn models(args: &WebArgs, title: &str, mut res: usize, max_mb: usize) -> Result<(String, String)> {
    let loaded = load_models(&args.inputs, &args.output)?;
    let cap = max_mb * 1_000_000;
    loop {
        let (page, dims) = models_at(&loaded, &args.inputs, title, res)?;
        if page.len() <= cap {
            return Ok((page, format!("{} model(s), baked {}x{}x{}", loaded.len(), dims[0], dims[1], dims[2])));
        }
        let smaller = ((res as f64) * (cap as f64 / page.len() as f64).cbrt() * 0.95) as usize;
        if smaller < 16 {
            return Err(Error::usage(format!(
                "the page would be {:.1} MB even at --res {res}; allow more with --max-mb",
                page.len() as f64 / 1e6
            )));
        }
        tell!("a bake at --res {res} makes a {:.1} MB page; trying --res {smaller}", page.len() as f64 / 1e6);
        res = smaller;
    }
}

fn models_at(loaded: &[Loaded], paths: &[PathBuf], title: &str, res: usize) -> Result<(String, [usize; 3])> {
    let inputs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
    let names = names(&inputs);
    let models: Vec<(&str, &LstModel, &Textures)> =
        names.iter().zip(loaded).map(|(n, l)| (n.as_str(), &l.model, &l.textures)).collect();
    web::fill_page(title, &models, res, io::budget_from_env()?)
}

fn skin(path: &Path, title: &str) -> Result<(String, String)> {
    let coloured = io::mesh_file::read_coloured_ply(path)?;
    let page = web::skin_page(title, &coloured.mesh, &coloured.colours)?;
    Ok((page, format!("a skin of {} triangles", coloured.mesh.triangles.len())))
}
