//! `solidtex bench`: timed workloads on exemplars the project makes itself, so anyone
//! can measure on any machine from a fresh clone. Prints the median of several runs.

use crate::error::Result;
use crate::procedural::{Recipe, generate};
use crate::progress::NoProgress;
use crate::synth::{Exemplars, LayeredParams, SynthParams, synthesize, synthesize_layered};
use crate::volume::{Axis, Channel, Image2d};
use std::time::Instant;

/// The arguments of `solidtex bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Runs per workload (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Only workloads whose name contains this text.
    #[arg(long)]
    pub only: Option<String>,
}

struct Workload {
    name: &'static str,
    size: [usize; 3],
    layered: bool,
}

const WORKLOADS: [Workload; 3] = [
    Workload { name: "synth/64cube/128px-rgb", size: [64; 3], layered: false },
    Workload { name: "layered/64x64x128/128px-rgb", size: [64, 64, 128], layered: true },
    Workload { name: "synth/128cube/128px-rgb", size: [128; 3], layered: false },
];

/// Run `solidtex bench`.
pub fn run(args: &BenchArgs) -> Result<()> {
    let marble = exemplar(Recipe::Marble, Axis::Z)?;
    let strata = exemplar(Recipe::Strata, Axis::Y)?;
    println!("{:<30} {:>5} {:>9} {:>9} {:>12} {:>10}", "workload", "runs", "median s", "min s", "voxels/s", "peak MiB");
    for w in WORKLOADS.iter().filter(|w| args.only.as_ref().is_none_or(|o| w.name.contains(o.as_str()))) {
        let mut times = Vec::new();
        for run in 0..args.runs.max(1) {
            let params = SynthParams { size: w.size, ..SynthParams::default() };
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
        println!(
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
