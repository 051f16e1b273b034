//! The guided-synthesis workloads of `solidtex bench`, on the drawn fruit with the kiwi
//! spec's frames (a stroke along the axis, depth 1 on it) and the drawn bark-skin
//! exemplar (its solid cube synthesized first, as `guided` does, and timed apart): a 256²
//! cut through the axis at resolution 256 on demand, the same cut with the coarse levels
//! kept from an earlier run, and the whole solid at 128.

use super::bench::BenchArgs;
use super::bench_fill::{timed, timed_then, wanted};
use crate::error::Result;
use crate::fill::render::View;
use crate::fill::tets::TetMesh;
use crate::guided::field::{FrameField, sketched_frames, solve};
use crate::guided::solid::{self, Domain};
use crate::progress::NoProgress;
use crate::synth::coords::{self as synth, Exemplars, Options, Setup};
use crate::synth::region::Mask;
use crate::volume::Image2d;
use glam::Vec3;
use std::time::Instant;

const CUT: &str = "guided/cut/fruit/256";
const CACHED: &str = "guided/cut/fruit/256/cached";
const SOLID: &str = "guided/solid/fruit/128";

/// The workload names.
pub fn names() -> Vec<String> {
    [CUT, CACHED, SOLID].map(String::from).to_vec()
}

/// The bench's fruit: its surface, tets, frame field and depth constraints.
type Fruit = (crate::mesh::Mesh, TetMesh, FrameField, Vec<(Vec3, f32)>);

/// The fruit, its tets, its frame field and its depth.
fn fruit() -> Result<Fruit> {
    let fruit = crate::mesh::shapes::named("fruit").expect("a drawn shape").canonical();
    let tets = crate::fill::mesher::tetrahedralize(&fruit, 5000)?;
    let directions = [(Vec3::new(-0.75, 0.0, 0.0), Vec3::X), (Vec3::new(0.0, 0.2, 0.0), Vec3::X)];
    let depth: Vec<(Vec3, f32)> = fruit.vertices.iter().map(|p| (*p, 0.0)).chain([(Vec3::ZERO, 1.0)]).collect();
    let field = solve(&tets, &sketched_frames(&directions, &depth)?)?;
    Ok((fruit, tets, field, depth))
}

/// Run the guided workloads.
pub fn run(args: &BenchArgs) -> Result<()> {
    if !names().iter().any(|n| wanted(args, n)) {
        return Ok(());
    }
    let (fruit, tets, field, depth) = fruit()?;
    let image = crate::sections::draw("bark-skin", 128, 128, 1)?;
    let options = Options::for_exemplar(crate::synth::cube::SIDE);
    let started = Instant::now();
    let cube = crate::synth::cube::synthesize(&[image.clone(), image.clone(), image.clone()], 1)?;
    let exemplars = Exemplars::of_volume(&cube, &options)?;
    let prepared = started.elapsed().as_secs_f64();
    let view = View::framing(fruit.bounds(), Vec3::ZERO, Vec3::Y, 256)?;
    let domain = Domain::around(fruit.bounds(), 256)?;
    let frames = solid::frames_over(&tets, &field, &domain, &depth, &[])?;
    let setup = Setup {
        exemplars: &exemplars,
        frames: Some(&frames),
        wrap: [false; 3],
        depth: None,
        dims: domain.dims,
        seed: 1,
        options,
    };
    let whole: usize = setup.level_dims().iter().map(|d| d.iter().product::<usize>()).sum();
    timed_then(
        args,
        CUT,
        || solid::cut(&setup, &domain, &fruit, &view, &[], &NoProgress),
        |(picture, out)| {
            Ok(format!("{} the exemplar's cube synthesized in {prepared:.2} s", report(picture, &image, out, whole)?))
        },
    )?;
    if wanted(args, CACHED) {
        let coarse = solid::coarse_levels(&setup, &solid::interior_plan(&setup, &domain, &fruit), &NoProgress)?;
        let kept: Vec<_> = coarse.iter().map(Some).collect();
        timed_then(
            args,
            CACHED,
            || solid::cut(&setup, &domain, &fruit, &view, &kept, &NoProgress),
            |(picture, out)| report(picture, &image, out, whole),
        )?;
    }
    let domain = Domain::around(fruit.bounds(), 128)?;
    let frames = solid::frames_over(&tets, &field, &domain, &depth, &[])?;
    let setup = Setup { dims: domain.dims, frames: Some(&frames), ..setup };
    timed(args, SOLID, || {
        let out = synth::run(&setup, &synth::plan(&setup, &Mask::full(domain.dims), &[]), &[], &NoProgress)?;
        Ok(format!("{} voxels, {} corrections", out.voxels, out.corrections))
    })
}

/// The voxels a cut took against the whole solid's, and the sharpness yardstick of the
/// largest centred square inside the model against the exemplar.
fn report(picture: &Image2d, exemplar: &Image2d, out: &synth::Synthesized, whole: usize) -> Result<String> {
    let s = solid::cut_sharpness(picture, exemplar)?;
    Ok(format!(
        "{:.1} % of the voxels, gradient {:.2} length {:.2},",
        100.0 * out.voxels as f64 / whole as f64,
        s.gradient_ratio,
        s.length_ratio
    ))
}
