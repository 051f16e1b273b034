//! The surface-synthesis workloads of `solidtex bench`: the project's own skins grown on a
//! flat square (time and the yardstick's figures), with `--meshes` 100,000 points on the
//! bunny, with `--photos` the yardstick on every PNG of a folder; and the guided frame
//! field's solve on the kiwi's 5,000 tets.

use super::bench::BenchArgs;
use super::bench_fill::{timed, wanted};
use crate::error::Result;
use crate::io;
use crate::progress::NoProgress;
use crate::surface::{self, Guide, Options};
use crate::volume::Image2d;
use std::path::{Path, PathBuf};

/// Points on the square: 128 exemplar pixels across at four points per pixel.
const SQUARE_POINTS: usize = 65_536;
/// The frame-field workload.
const FIELD: &str = "guided/field/fruit/5k";
/// Points on the bunny.
const BUNNY_POINTS: usize = 100_000;

/// The workload names (a photo's: `surface/photo/` and its file name without `.png`).
pub fn names(args: &BenchArgs) -> Result<Vec<String>> {
    let mut names: Vec<String> = crate::sections::SKINS.iter().map(|s| format!("surface/square/{s}")).collect();
    names.push("surface/bunny/100k".into());
    names.push(FIELD.into());
    for photo in photos(args)? {
        names.push(format!("surface/photo/{}", stem(&photo)));
    }
    Ok(names)
}

/// The PNGs of `--photos`, sorted.
fn photos(args: &BenchArgs) -> Result<Vec<PathBuf>> {
    let Some(folder) = &args.photos else { return Ok(Vec::new()) };
    let mut photos: Vec<PathBuf> = std::fs::read_dir(folder)
        .map_err(|e| crate::Error::file(folder, e.to_string()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")))
        .collect();
    photos.sort();
    Ok(photos)
}

fn stem(path: &Path) -> String {
    path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Run the surface workloads.
pub fn run(args: &BenchArgs) -> Result<()> {
    if !names(args)?.iter().any(|n| wanted(args, n)) {
        return Ok(());
    }
    say!("{:<30} {:>5} {:>9} {:>9}  {}", "workload", "runs", "median s", "min s", "figures");
    for skin in crate::sections::SKINS {
        let name = format!("surface/square/{skin}");
        if wanted(args, &name) {
            square(args, &name, &crate::sections::draw(skin, 128, 128, 1)?)?;
        }
    }
    let bunny = args.meshes.as_deref().map(|d| d.join("libigl_bunny.obj")).filter(|p| p.exists());
    if let Some(path) = bunny.filter(|_| wanted(args, "surface/bunny/100k")) {
        let bunny = io::mesh_file::read_mesh(&path)?;
        let image = crate::sections::draw("bark-skin", 128, 128, 1)?;
        let options = Options { points: BUNNY_POINTS, seed: 1, texel: None, guide: Guide::Along(glam::Vec3::Y) };
        timed(args, "surface/bunny/100k", || {
            let skin = surface::synthesize(&bunny, &image, &options, &NoProgress)?;
            let h = surface::histogram_distances(&skin.colours, &image)?;
            Ok(format!("{} points, histogram {:.3} {:.3} {:.3}", skin.mesh.vertices.len(), h[0], h[1], h[2]))
        })?;
    }
    if wanted(args, FIELD) {
        field(args)?;
    }
    for photo in photos(args)? {
        let name = format!("surface/photo/{}", stem(&photo));
        if wanted(args, &name) {
            square(args, &name, &io::read_image_fit(&photo, Some(128))?)?;
        }
    }
    Ok(())
}

/// The kiwi spec's frame field on the fruit's tet mesh: the sketched frames and the solve.
fn field(args: &BenchArgs) -> Result<()> {
    let fruit = crate::mesh::shapes::named("fruit").expect("a drawn shape").canonical();
    let tets = crate::fill::mesher::tetrahedralize(&fruit, 5000)?;
    let directions =
        [(glam::Vec3::new(-0.75, 0.0, 0.0), glam::Vec3::X), (glam::Vec3::new(0.0, 0.2, 0.0), glam::Vec3::X)];
    let depth: Vec<(glam::Vec3, f32)> =
        fruit.vertices.iter().map(|p| (*p, 0.0)).chain([(glam::Vec3::ZERO, 1.0)]).collect();
    timed(args, FIELD, || {
        let frames = crate::guided::field::sketched_frames(&directions, &depth)?;
        let field = crate::guided::field::solve(&tets, &frames)?;
        Ok(format!("{} tets, {} vertices", tets.tets.len(), field.components.len()))
    })
}

/// Grows `image` on the unit square and reports the yardstick.
fn square(args: &BenchArgs, name: &str, image: &Image2d) -> Result<()> {
    timed(args, name, || {
        let y = surface::on_a_square(image, SQUARE_POINTS, 1, &NoProgress)?;
        let (s, h) = (&y.sharpness, y.histogram);
        Ok(format!(
            "gradient {:.2} length {:.2} histogram {:.3}",
            s.gradient_ratio,
            s.length_ratio,
            h.iter().fold(0.0f64, |a, b| a.max(*b))
        ))
    })
}
