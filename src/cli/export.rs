//! `solidtex export`: filled models (or a surface skin) as a glTF 2.0 binary.

use super::fill::{Bar, Loaded, channel_textures, load_models, within_models};
use crate::error::{Error, Result};
use crate::fill::export::{self, Exported, Options, Relief};
use crate::fill::view::DEFAULT_CREASE;
use crate::io::{self, gltf};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The arguments of `solidtex export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// One or more models (.lst), each its own mesh in the file (a cake's layers stay
    /// apart). Or one skin (.ply with vertex colours, as `solidtex surface` writes it).
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// Split the surface to edges about this long, in model units (an edge longer than 4/3
    /// of it is halved until none is); 0 keeps the input surface's triangles. Default: two
    /// pixels of a 512x512 `view` from the default camera (0 with --atlas).
    #[arg(long, allow_hyphen_values = true)]
    pub edge: Option<f32>,
    /// Edges sharper than this many degrees keep two normals (as in `view`), 0 to 180
    /// (default 60; filled models).
    #[arg(long)]
    pub crease: Option<f32>,
    /// The displaced surface, as `view --displacement SCALE` shows it: moved along its
    /// normal by SCALE x (the exemplars' Displacement channel - 0.5), in model units.
    #[arg(long, allow_hyphen_values = true)]
    pub displacement: Option<f32>,
    /// A texture atlas of SIZE x SIZE texels (a PNG inside the file, 64 to 8192) instead
    /// of vertex colours: each triangle gets its own square of it.
    #[arg(long)]
    pub atlas: Option<usize>,
    /// The .glb to write.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The picture side and edge in pixels the default `--edge` is measured against.
const DEFAULT_VIEW: (usize, f32) = (512, 2.0);

/// Run `solidtex export`.
pub fn run(args: &ExportArgs) -> Result<()> {
    let checks = || -> Result<()> {
        if let Some(crease) = args.crease {
            io::values::within("--crease", crease, 0.0, 180.0)?;
        }
        if let Some(edge) = args.edge.filter(|e| !(e.is_finite() && *e >= 0.0)) {
            return Err(Error::invalid(format!(
                "--edge {edge} is out of range; allowed: 0 (the input surface's triangles) or a positive length in model units"
            )));
        }
        if let Some(side) = args.atlas {
            io::values::within("--atlas", side, 64, 8192)?;
        }
        if let Some(scale) = args.displacement {
            io::values::within("--displacement", scale, -1000.0, 1000.0)?;
        }
        Ok(())
    };
    checks().map_err(super::commands::usage)?;
    let inputs: Vec<&Path> = args.models.iter().map(PathBuf::as_path).collect();
    super::guided::not_taken_by(
        "export",
        &inputs,
        " to see it in 3D with `solidtex web solid.exr`; export takes filled models (.lst, from `solidtex fill`) \
         and skins (.ply)",
    )?;
    io::guard::file_output(&args.output, &inputs, &["glb"], "a glTF binary")?;
    let is_skin = |p: &PathBuf| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if let [one] = args.models.as_slice()
        && is_skin(one)
    {
        return export_skin(args, one);
    }
    if let Some(skin) = args.models.iter().find(|p| is_skin(p)) {
        return Err(Error::usage(format!(
            "{}: a skin (.ply) is exported alone, as it is; filled models (.lst) go together in another export",
            skin.display()
        )));
    }
    let loaded = load_models(&args.models, &args.output)?;
    if let Some(scale) = args.displacement {
        within_models("--displacement", scale, &loaded)?;
    }
    let options = options(args, &loaded)?;
    let reliefs = match args.displacement {
        None => None,
        Some(_) => Some(channel_textures(&loaded, &crate::volume::Channel::Displacement)?),
    };
    let started = Instant::now();
    let mut meshes = Vec::new();
    for (i, l) in loaded.iter().enumerate() {
        let relief = reliefs.as_ref().zip(args.displacement).map(|(t, scale)| Relief { textures: &t[i], scale });
        let bar = Bar::new();
        let done = export::export(&l.model, &l.textures, relief, options, &bar);
        bar.0.finish_and_clear();
        // what the core refuses is the options' doing (the edge, the atlas side)
        meshes.push(done.map_err(super::commands::usage)?);
    }
    let names: Vec<String> = args.models.iter().map(|p| stem(p)).collect();
    let parts: Vec<gltf::Part> =
        names.iter().zip(&meshes).map(|(name, mesh)| gltf::Part { name: name.clone(), mesh }).collect();
    let extras = provenance(args, &loaded, &meshes, options);
    if let Some(side) = options.atlas.filter(|side| *side >= 2048) {
        // PNG-encoding a large atlas takes seconds after the bar has finished
        tell!("encoding {} {side}x{side} atlas(es) as PNG and writing {}…", meshes.len(), args.output.display());
    }
    gltf::write_glb(&args.output, &parts, extras)?;
    let triangles: usize = meshes.iter().map(|m| m.triangles.len()).sum();
    let vertices: usize = meshes.iter().map(|m| m.positions.len()).sum();
    let unsplit = triangles == loaded.iter().map(|l| l.model.surface.triangles.len()).sum::<usize>();
    tell!(
        "wrote {} in {:.0} ms: {} mesh(es), {triangles} triangles, {vertices} vertices{}",
        args.output.display(),
        started.elapsed().as_secs_f64() * 1000.0,
        meshes.len(),
        match options.atlas {
            Some(side) => format!(", a {side}x{side} atlas"),
            None if options.edge == 0.0 => ", vertex colours, the input surface's own triangles".to_string(),
            None if unsplit => {
                format!(
                    ", vertex colours, the input surface's own triangles (none longer than --edge {})",
                    options.edge
                )
            }
            None => format!(", vertex colours, edges about {} model units", crate::surface::four_digits(options.edge)),
        }
    );
    Ok(())
}

/// The export settings, the default edge measured on the models, the triangle count
/// checked before any work.
fn options(args: &ExportArgs, loaded: &[Loaded]) -> Result<Options> {
    let models: Vec<&crate::fill::LstModel> = loaded.iter().map(|l| &l.model).collect();
    let (size, pixels) = DEFAULT_VIEW;
    let edge = match (args.edge, args.atlas) {
        (Some(edge), _) => edge,
        (None, Some(_)) => 0.0,
        (None, None) => pixels * crate::fill::view::pixel_size(&models, (35.0, 25.0), size),
    };
    let most = export::MAX_TRIANGLES;
    let count =
        models.iter().try_fold(0u64, |sum, m| Some(sum + export::triangle_count(m, edge, most - sum.min(most))?));
    if count.is_none_or(|n| n > most) {
        return Err(Error::usage(format!(
            "--edge {edge}: splitting the surface(s) that fine gives more than {most} triangles; give a longer edge"
        )));
    }
    Ok(Options { edge, crease: args.crease.unwrap_or(DEFAULT_CREASE), atlas: args.atlas })
}

/// The file name without its extension.
fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned())
}

/// What the file was made from, for `asset.extras`.
fn provenance(args: &ExportArgs, loaded: &[Loaded], meshes: &[Exported], options: Options) -> serde_json::Value {
    let models: Vec<serde_json::Value> = (args.models.iter().zip(loaded).zip(meshes))
        .map(|((path, l), mesh)| {
            let exemplars: Vec<&str> = l.model.sources.iter().map(|s| s.exemplar.as_str()).collect();
            json!({
                "name": stem(path),
                "file": path.display().to_string(),
                "exemplars": exemplars,
                "triangles": mesh.triangles.len(),
            })
        })
        .collect();
    json!({
        "made_by": format!("solidtex {} export", env!("CARGO_PKG_VERSION")),
        "models": models,
        "edge": options.edge,
        "crease_degrees": options.crease,
        "displacement": args.displacement,
        "colours": if options.atlas.is_some() { "atlas" } else { "vertex" },
        "units": "one model unit is one metre; +y is up",
    })
}

/// `solidtex export SKIN.ply`: the skin's mesh and vertex colours as they are.
fn export_skin(args: &ExportArgs, path: &Path) -> Result<()> {
    if args.displacement.is_some() || args.atlas.is_some() || args.edge.is_some() || args.crease.is_some() {
        return Err(Error::usage(format!(
            "{}: a skin is exported as it is; --edge, --crease, --displacement and --atlas apply to filled models (.lst)",
            path.display()
        )));
    }
    let skin = io::mesh_file::read_coloured_ply(path)?;
    let mesh = &skin.mesh;
    let normals = crate::surface::retile::vertex_normals(&mesh.vertices, &mesh.triangles);
    let exported = Exported {
        positions: mesh.vertices.clone(),
        normals: normals.iter().map(|n| n.normalize_or(glam::Vec3::Y)).collect(),
        colours: skin.colours.clone(),
        triangles: mesh.triangles.clone(),
        atlas: None,
    };
    let extras = json!({
        "made_by": format!("solidtex {} export", env!("CARGO_PKG_VERSION")),
        "skin": path.display().to_string(),
        "units": "one model unit is one metre; +y is up",
    });
    gltf::write_glb(&args.output, &[gltf::Part { name: stem(path), mesh: &exported }], extras)?;
    tell!("wrote {}: the skin's {} triangles with vertex colours", args.output.display(), mesh.triangles.len());
    Ok(())
}
