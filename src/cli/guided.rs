//! `solidtex field`: the frame field of sketch-guided solid texturing, drawn on a cut.

use super::commands::usage;
use crate::error::Result;
use crate::fill::render::View;
use crate::guided::field::{sketched_frames, solve, streamlines};
use crate::io::{self, fill_spec, mesh_file};
use std::path::PathBuf;
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

/// Run `solidtex field`.
pub fn run(args: &FieldArgs) -> Result<()> {
    let checks = || -> Result<Option<(glam::Vec3, glam::Vec3)>> {
        io::values::within("--size", args.size, 8, 4096)?;
        if let Some(tets) = args.tets {
            io::values::within("--tets", tets, *fill_spec::TETS.start(), *fill_spec::TETS.end())?;
        }
        args.plane.as_deref().map(|text| super::fill::plane("--plane", text)).transpose()
    };
    let plane = checks().map_err(usage)?;
    io::check_folder(&args.output)?;
    let mut spec = fill_spec::read_fill_spec(&args.spec)?;
    spec.tets = args.tets.unwrap_or(spec.tets);
    let surface = mesh_file::read_mesh(&args.mesh)?.canonical();
    let (tets, _) = crate::fill::tetrahedralize(&surface, &spec).map_err(|e| e.in_file(&args.mesh))?;
    let constraints = crate::fill::spec::constraints(&spec, &surface, 1.0).map_err(|e| e.in_file(&args.spec))?;
    let started = Instant::now();
    let frames = sketched_frames(&constraints.directions, &constraints.depth).map_err(|e| e.in_file(&args.spec))?;
    let field = solve(&tets, &frames)?;
    let solved = started.elapsed().as_secs_f64() * 1000.0;
    let bounds = surface.bounds();
    let (point, normal) = plane.unwrap_or(((bounds.0 + bounds.1) / 2.0, glam::Vec3::Z));
    let view = View::framing(bounds, point, normal, args.size)?;
    io::write_rgb8(&args.output, &streamlines(&tets, &field, &view))?;
    eprintln!(
        "wrote {} ({} tets, {} sketched frames; the field solved in {solved:.0} ms)",
        args.output.display(),
        tets.tets.len(),
        frames.len()
    );
    Ok(())
}
