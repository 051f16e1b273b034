//! Shared helpers: random volumes, running the binary, checking folders.

use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use solidtex::{Channel, Volume};
use std::path::Path;
use std::process::{Command, Output};

/// A volume of uniform random samples in [0, 1).
pub fn random_volume(dims: [usize; 3], channels: Vec<Channel>, seed: u64) -> Volume {
    let mut rng = Pcg64::seed_from_u64(seed);
    Volume::from_fn(dims, channels, |_, _, _, out| {
        for v in out.iter_mut() {
            *v = rng.random::<f32>();
        }
    })
    .unwrap()
}

/// Run `solidtex` with `args`.
pub fn solidtex(args: &[&str]) -> Output {
    solidtex_env(args, &[])
}

/// Run `solidtex` with `args` and extra environment variables.
pub fn solidtex_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_solidtex"));
    cmd.args(args).env_remove("JOB_COMPLETION_INDEX").env_remove("SLURM_ARRAY_TASK_ID");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("the solidtex binary runs")
}

/// Stderr as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Assert a run failed with exit code 1 and an error line containing every `needle`.
pub fn assert_fails(out: &Output, needles: &[&str]) {
    assert_exit(out, 1, needles);
}

/// Assert a run was refused as a usage error (exit code 2) with an error line containing
/// every `needle`.
pub fn assert_usage(out: &Output, needles: &[&str]) {
    assert_exit(out, 2, needles);
}

fn assert_exit(out: &Output, code: i32, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(code), "expected exit {code}, stderr: {err}");
    let line = err.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("no error line in {err:?}"));
    for n in needles {
        assert!(line.contains(n), "{line:?} does not mention {n:?}");
    }
}

/// The names in a folder, sorted.
pub fn listing(folder: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(folder).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// A path inside `dir` as a string.
pub fn at(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// Grey spots on a ground: a share `white` of the 40x40 pixels (whole 4x4 cells, picked by
/// hash) is 0.9, the rest 0.1.
pub fn spots(white: f64, seed: u64) -> solidtex::volume::Image2d {
    let cell = |x: usize, y: usize| solidtex::noise::hash3(seed, (x / 4) as i64, (y / 4) as i64, 0) % 1000;
    let data = (0..40 * 40).map(|i| if (cell(i % 40, i / 40) as f64) < white * 1000.0 { 0.9 } else { 0.1 }).collect();
    solidtex::volume::Image2d::from_data(40, 40, Channel::grey(), data).unwrap()
}

/// The share of `samples` above one half.
pub fn white_share(samples: &[f32]) -> f64 {
    samples.iter().filter(|v| **v > 0.5).count() as f64 / samples.len() as f64
}
