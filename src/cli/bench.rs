//! `solidtex bench`: timed workloads on exemplars the project makes itself, so anyone
//! can measure on any machine from a fresh clone. Prints the median of several runs.

use crate::error::{Error, Result};
use crate::procedural::{Recipe, generate};
use crate::progress::NoProgress;
use crate::synth::{Core, Exemplars, LayeredParams, SynthParams, synthesize, synthesize_layered};
use crate::volume::{Axis, Channel, Image2d};
use std::time::Instant;

/// The arguments of `solidtex bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Runs per workload, 1 to 100 (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Only workloads whose name contains this text (e.g. `fill`, `synth`, `/128`).
    #[arg(long)]
    pub only: Option<String>,
    /// List the workloads' names, one per line, and run none.
    #[arg(long)]
    pub list: bool,
    /// Also time filling the closed meshes of this folder that it knows (the bunny, sphere,
    /// stepped cylinder and pipe of ../shared/data/meshes).
    #[arg(long)]
    pub meshes: Option<std::path::PathBuf>,
    /// Also grow each PNG of this folder on a flat square (surface synthesis) and report the
    /// yardstick: gradient and length ratios against the photo, histogram distance.
    #[arg(long)]
    pub photos: Option<std::path::PathBuf>,
}

struct Workload {
    name: &'static str,
    size: [usize; 3],
    layered: bool,
    core: Core,
}

const WORKLOADS: [Workload; 6] = [
    Workload { name: "synth/64cube/128px-rgb", size: [64; 3], layered: false, core: Core::Blend },
    Workload { name: "layered/64x64x128/128px-rgb", size: [64, 64, 128], layered: true, core: Core::Blend },
    Workload { name: "synth/128cube/128px-rgb", size: [128; 3], layered: false, core: Core::Blend },
    Workload { name: "synth-coords/64cube/128px-rgb", size: [64; 3], layered: false, core: Core::Coordinates },
    Workload { name: "layered-coords/64x64x128/128px", size: [64, 64, 128], layered: true, core: Core::Coordinates },
    Workload { name: "synth-coords/128cube/128px-rgb", size: [128; 3], layered: false, core: Core::Coordinates },
];

/// Every workload's name, in the order they run.
fn workload_names(args: &BenchArgs) -> Result<Vec<String>> {
    let mut names: Vec<String> =
        HAND_MADE.iter().chain(WORKLOADS.iter().map(|w| &w.name)).map(|n| n.to_string()).collect();
    names.extend(super::bench_fill::names());
    names.extend(super::bench_surface::names(args)?);
    names.extend(super::bench_guided::names());
    Ok(names)
}

/// Run `solidtex bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    crate::io::values::within("--runs", args.runs, 1, 100).map_err(super::commands::usage)?;
    if args.list {
        workload_names(args)?.iter().for_each(|name| say!("{name}"));
        return Ok(());
    }
    if let Some(only) = &args.only {
        let names = workload_names(args)?;
        if !names.iter().any(|n| n.contains(only.as_str())) {
            let mut groups: Vec<&str> = names.iter().map(|n| n.split('/').next().unwrap_or(n)).collect();
            groups.dedup();
            return Err(Error::usage(format!(
                "--only {only:?} matches no workload; their names start {} (`solidtex bench --list` lists them all)",
                groups.join(", ")
            )));
        }
    }
    let wanted = |name: &str| args.only.as_ref().is_none_or(|o| name.contains(o.as_str()));
    let works: Vec<_> = hand_made()?.into_iter().filter(|(name, _)| wanted(name)).collect();
    if !works.is_empty() {
        say!("{:<30} {:>5} {:>9} {:>9}", "workload", "runs", "median s", "min s");
    }
    for (name, work) in works {
        let mut times = Vec::new();
        for _ in 0..args.runs.max(1) {
            let started = Instant::now();
            work()?;
            times.push(started.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        say!("{:<30} {:>5} {:>9.3} {:>9.3}", name, times.len(), times[times.len() / 2], times[0]);
    }
    super::bench_fill::run(args)?;
    super::bench_surface::run(args)?;
    super::bench_guided::run(args)?;
    synthesis(args)
}

type Work = Box<dyn Fn() -> Result<()>>;

/// The names of the hand-made workloads, in the order [`hand_made`] returns them.
const HAND_MADE: [&str; 3] = ["stamp/2k-tri/128cube (+clone)", "scatter/100-seeds/128cube", "sweep+noise+skin/128cube"];

/// The hand-made workloads: stamp, scatter, sweep + noise + skin at 128³.
fn hand_made() -> Result<Vec<(&'static str, Work)>> {
    let seed = std::rc::Rc::new(crate::sections::seed_mesh(32, 32)?);
    let section = std::rc::Rc::new(crate::sections::draw("kiwi", 128, 128, 1)?);
    let base = std::rc::Rc::new(crate::volume::Volume::from_fn([128; 3], Channel::rgb(), |_, _, _, o| o.fill(0.5))?);
    let (s1, b1) = (seed.clone(), base.clone());
    let stamp_one: Work = Box::new(move || {
        let mut v = (*b1).clone();
        let at = crate::stamp::Placement {
            at: glam::Vec3::splat(64.0),
            rotation: glam::Quat::IDENTITY,
            scale: glam::Vec3::splat(10.0),
        };
        crate::stamp::stamp(&mut v, &s1, &at, [0.0; 3]).map(|_| ())
    });
    let (s2, b2) = (seed.clone(), base.clone());
    let scatter: Work = Box::new(move || {
        let mut v = (*b2).clone();
        let region = crate::stamp::Region::Box(glam::Vec3::ZERO, glam::Vec3::splat(128.0));
        let params = crate::stamp::Scatter { count: 100, region, scale: (4.0, 6.0), colour: [0.0; 3], attempts: 200 };
        crate::stamp::scatter(&mut v, &s2, &params, 1).map(|_| ())
    });
    let sweep: Work = Box::new(move || {
        let params = crate::sweep::Sweep {
            length: 128,
            axis: Axis::X,
            depth_axis: Some(Axis::Z),
            noise: Some(crate::sweep::Noise { amplitude: 1.5, frequency: 4.0, jitter: 0.02 }),
            skin: Some(crate::sweep::Skin {
                look: crate::sweep::SkinLook::Colour([0.4, 0.3, 0.1]),
                width: 2.0,
                width_noise: 0.5,
            }),
            displacement: None,
        };
        crate::sweep::sweep(&section, &params, 1).map(|_| ())
    });
    Ok(HAND_MADE.into_iter().zip([stamp_one, scatter, sweep]).collect())
}

/// The synthesis workloads: homogeneous 64³ and 128³, layered 64x64x128, by each core.
fn synthesis(args: &BenchArgs) -> Result<()> {
    let works: Vec<&Workload> =
        WORKLOADS.iter().filter(|w| args.only.as_ref().is_none_or(|o| w.name.contains(o.as_str()))).collect();
    if works.is_empty() {
        return Ok(());
    }
    let marble = exemplar(Recipe::Marble, Axis::Z)?;
    let strata = exemplar(Recipe::Strata, Axis::Y)?;
    say!("{:<30} {:>5} {:>9} {:>9} {:>12} {:>10}", "workload", "runs", "median s", "min s", "voxels/s", "peak MiB");
    for w in works {
        let mut times = Vec::new();
        for run in 0..args.runs.max(1) {
            let params = SynthParams { size: w.size, core: w.core, ..SynthParams::default() };
            let started = Instant::now();
            if w.layered {
                synthesize_layered(&strata, None, &params, &LayeredParams::default(), run as u64, &NoProgress)?;
            } else {
                synthesize(Exemplars { x: &marble, y: None, z: None }, &params, run as u64, &NoProgress)?;
            }
            times.push(started.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        let voxels = w.size.iter().product::<usize>() as f64;
        let peak = peak_mib().map(|m| format!("{m:.0}")).unwrap_or_else(|| "-".to_string());
        say!(
            "{:<30} {:>5} {:>9.2} {:>9.2} {:>12.0} {:>10}",
            w.name,
            times.len(),
            median,
            times[0],
            voxels / median,
            peak
        );
    }
    Ok(())
}

/// A 128x128 RGB slice of a procedural volume, across `axis`.
fn exemplar(recipe: Recipe, axis: Axis) -> Result<Image2d> {
    let dims = match axis {
        Axis::Z => [128, 128, 1],
        _ => [128, 1, 128],
    };
    let slice = generate(recipe, dims, 11)?.slice(axis, 0)?;
    let rgb: Vec<f32> = slice.data().chunks(slice.channel_count()).flat_map(|p| p[..3].iter().copied()).collect();
    Image2d::from_data(slice.width(), slice.height(), Channel::rgb(), rgb)
}

/// Peak resident memory of this process (Linux), in MiB.
fn peak_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
