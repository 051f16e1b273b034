//! `solidtex surface`: grow a 2D exemplar over a mesh's surface (a skin).

use crate::error::{Error, Result};
use crate::fill::spec::{size_of, stroke_samples};
use crate::io::{self, fill_spec, mesh_file};
use crate::surface::{self, Guide, Options};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The arguments of `solidtex surface`.
#[derive(Debug, clap::Args)]
pub struct SurfaceArgs {
    /// The mesh (.obj, .stl, .ply); closed or open, any genus.
    pub mesh: PathBuf,
    /// The exemplar photo (PNG, JPEG, TIFF, EXR, HDR), at least 16x16 pixels.
    #[arg(long)]
    pub exemplar: PathBuf,
    /// About how many points (vertices) the skin gets, 100 to 500000.
    #[arg(long, default_value_t = 20_000)]
    pub points: usize,
    /// Take the texture's "up" from a fill spec's direction strokes (docs/fill.md).
    #[arg(long, conflicts_with = "direction")]
    pub spec: Option<PathBuf>,
    /// The texture's "up" as X,Y,Z, projected onto the surface (default 0,1,0).
    #[arg(long, allow_hyphen_values = true)]
    pub direction: Option<String>,
    /// Model units one exemplar pixel covers (default: two point spacings, four points per
    /// pixel); larger makes the texture's features larger on the model.
    #[arg(long, allow_hyphen_values = true)]
    pub texel: Option<f32>,
    /// Seed of the random start (any 64-bit whole number).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The skin to write: a .ply with per-vertex red, green, blue.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Most exemplar pixels a model may span along its box's diagonal at the `--texel` given:
/// past it the photo's features are far smaller than the points (500,000 points on a
/// sphere are about 400 apart across it).
const MOST_PIXELS_ACROSS: f32 = 1.0e6;

/// Run `solidtex surface`.
pub fn run(args: &SurfaceArgs) -> Result<()> {
    let (lo, hi) = (*surface::POINTS.start(), *surface::POINTS.end());
    io::values::within("--points", args.points, lo, hi).map_err(super::commands::usage)?;
    if let Some(texel) = args.texel.filter(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(Error::usage(format!("--texel {texel} must be a length greater than 0")));
    }
    check_output(&args.output, &[&args.mesh, &args.exemplar])?;
    let mesh = mesh_file::read_mesh(&args.mesh)?;
    let (lo, hi) = mesh.bounds();
    let across = lo.distance(hi);
    if let Some(texel) = args.texel.filter(|t| *t > across) {
        return Err(Error::usage(format!(
            "--texel {texel}: one exemplar pixel would cover all of {} ({} units across); give at most that",
            args.mesh.display(),
            surface::four_digits(across)
        )));
    }
    if let Some(texel) = args.texel.filter(|t| *t < across * MOST_PIXELS_ACROSS.recip()) {
        return Err(Error::usage(format!(
            "--texel {texel:e}: {} ({} units across) would be over {MOST_PIXELS_ACROSS} exemplar pixels across; \
             give at least {}",
            args.mesh.display(),
            surface::four_digits(across),
            surface::four_digits(across / MOST_PIXELS_ACROSS)
        )));
    }
    let guide = guide(args, &mesh)?;
    let exemplar = io::read_image(&args.exemplar)?;
    surface::check_exemplar(&exemplar).map_err(|e| e.in_file(&args.exemplar))?;
    let options = Options { points: args.points, seed: args.seed, texel: args.texel, guide };
    let started = Instant::now();
    let bar = super::fill::Bar::new();
    let skin = surface::synthesize(&mesh, &exemplar, &options, &bar).map_err(|e| e.in_file(&args.mesh));
    bar.0.finish_and_clear();
    let skin = skin?;
    let seconds = started.elapsed().as_secs_f64();
    let coloured = mesh_file::ColouredMesh { mesh: skin.mesh.clone(), colours: skin.colours.clone() };
    mesh_file::write_coloured_ply(&args.output, &coloured)?;
    let hist = surface::histogram_distances(&skin.colours, &exemplar)?;
    let mesh_note = if mesh.boundary_edges() > 0 { " (open: its borders stay)" } else { "" };
    tell!(
        "wrote {}: {} points, {} triangles{mesh_note}, spacing {}, {} units per exemplar pixel, {} level{}, in \
         {seconds:.2} s",
        args.output.display(),
        skin.mesh.vertices.len(),
        skin.mesh.triangles.len(),
        surface::four_digits(skin.spacing),
        surface::four_digits(skin.texel),
        skin.levels,
        if skin.levels == 1 { "" } else { "s" }
    );
    let scale = surface::Scale {
        across: (skin.mesh.bounds().1 - skin.mesh.bounds().0).max_element(),
        texel: skin.texel,
        texel_given: args.texel.is_some(),
        spacing: skin.spacing,
        points: args.points,
        photo_side: exemplar.width().min(exemplar.height()),
    };
    if let Some(note) = surface::scale_note(&scale) {
        tell!("note: {note}");
    }
    tell!(
        "histogram distance to the exemplar: R {:.3}  G {:.3}  B {:.3} (0 = equal, 2 = disjoint)",
        hist[0],
        hist[1],
        hist[2]
    );
    Ok(())
}

/// The direction guide the options ask for, checked.
fn guide(args: &SurfaceArgs, mesh: &crate::mesh::Mesh) -> Result<Guide> {
    if let Some(path) = &args.spec {
        let spec = fill_spec::read_fill_spec(path)?;
        let size = size_of(mesh);
        let samples: Vec<_> = spec.directions.iter().flat_map(|s| stroke_samples(s, size)).collect();
        if samples.is_empty() {
            return Err(Error::file(
                path,
                "has no direction strokes ([[direction]] with two or more points) to orient the texture",
            ));
        }
        return Ok(Guide::Strokes(samples));
    }
    match &args.direction {
        Some(text) => {
            let d = io::values::point("--direction", text).map_err(super::commands::usage)?;
            if !(d.is_finite() && d.length() > 1e-6) {
                return Err(Error::usage(format!("--direction {text} must be a non-zero vector")));
            }
            Ok(Guide::Along(d))
        }
        None => Ok(Guide::Along(glam::Vec3::Y)),
    }
}

/// The output must be a `.ply` in a folder solidtex may write, and none of the inputs.
fn check_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    io::guard::file_output(output, inputs, &["ply"], "the skin as a .ply")
}
