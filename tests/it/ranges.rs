//! Values out of range: a command-line value is a usage error (exit 2) naming the option,
//! the value and the allowed range, before any work and with nothing written; a manifest
//! or fill-spec value names the file, the line, the field, the value and the range.

use crate::support::{assert_usage, at, listing, random_volume, solidtex, stderr};
use solidtex::Channel;
use std::path::Path;
use std::process::Output;
use std::time::{Duration, Instant};

/// A folder with `base.exr` (an 8-voxel RGB cube), `seed.obj` and `kiwi.png` (16x16).
fn inputs() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let volume = random_volume([8, 8, 8], Channel::rgb(), 3);
    solidtex::io::write_volume(&dir.path().join("base.exr"), &volume).unwrap();
    let seed = solidtex(&["draw", "seed", "-o", &at(dir.path(), "seed.obj")]);
    assert!(seed.status.success(), "{}", stderr(&seed));
    let kiwi = solidtex(&["draw", "kiwi", "--size", "16x16", "-o", &at(dir.path(), "kiwi.png")]);
    assert!(kiwi.status.success(), "{}", stderr(&kiwi));
    dir
}

/// The files of `dir` besides the inputs made by [`inputs`].
fn written(dir: &Path) -> Vec<String> {
    listing(dir).into_iter().filter(|n| !["base.exr", "seed.obj", "kiwi.png"].contains(&n.as_str())).collect()
}

fn sweep_with_noise(dir: &Path, noise: &str) -> Output {
    let (kiwi, out) = (at(dir, "kiwi.png"), at(dir, "swept.exr"));
    solidtex(&["sweep", &kiwi, "--length", "8", "--noise", noise, "-o", &out])
}

#[test]
fn a_noise_frequency_of_two_million_is_a_usage_error() {
    let dir = inputs();
    let out = sweep_with_noise(dir.path(), "1,2000000");
    assert_usage(&out, &["--noise frequency 2000000 is out of range", "allowed: 0 to 64"]);
    assert!(written(dir.path()).is_empty(), "{:?}", written(dir.path()));
}

#[test]
fn a_noise_frequency_of_four_billion_is_refused_at_once() {
    let dir = inputs();
    let started = Instant::now();
    let out = sweep_with_noise(dir.path(), "1,4294967295");
    assert_usage(&out, &["--noise frequency 4294967300", "allowed: 0 to 64"]);
    assert!(started.elapsed() < Duration::from_secs(10), "took {:?}", started.elapsed());
    assert!(written(dir.path()).is_empty(), "{:?}", written(dir.path()));
}

#[test]
fn noise_amplitude_and_jitter_that_are_not_numbers_are_usage_errors() {
    let dir = inputs();
    assert_usage(&sweep_with_noise(dir.path(), "1e9,2"), &["--noise amplitude 1000000000", "allowed: 0 to 64"]);
    assert_usage(&sweep_with_noise(dir.path(), "1,2,nan"), &["--noise", "\"1,2,nan\""]);
    assert_usage(&sweep_with_noise(dir.path(), "1,2,5"), &["--noise jitter 5", "allowed: 0 to 1"]);
    assert!(written(dir.path()).is_empty(), "{:?}", written(dir.path()));
}

#[test]
fn scattering_ten_million_seeds_is_a_usage_error() {
    let dir = inputs();
    let (base, seed, out) = (at(dir.path(), "base.exr"), at(dir.path(), "seed.obj"), at(dir.path(), "out.exr"));
    let started = Instant::now();
    let run = solidtex(&["scatter", &base, &seed, "--count", "10000000", "--color", "0,0,0", "-o", &out]);
    assert_usage(&run, &["--count 10000000 is out of range; allowed: 1 to 2000"]);
    assert!(started.elapsed() < Duration::from_secs(10), "took {:?}", started.elapsed());
    assert!(written(dir.path()).is_empty(), "{:?}", written(dir.path()));
}

#[test]
fn out_of_range_numbers_of_other_commands_are_usage_errors_before_any_file_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let (missing, out) = (at(dir.path(), "missing.png"), at(dir.path(), "out.exr"));
    let cases: [(Vec<&str>, &str); 9] = [
        (vec!["synth", &missing, "--levels", "99", "-o", &out], "--levels 99 is out of range; allowed: 1 to 8"),
        (
            vec!["synth", &missing, "--pca-variance", "nan", "-o", &out],
            "--pca-variance <PCA_VARIANCE>': nan is not a finite number",
        ),
        (vec!["synth", &missing, "--size", "100000", "-o", &out], "--size \"100000\" is out of range"),
        (
            vec!["blur", &missing, "--at", "1,1,1", "--radius", "inf", "-o", &out],
            "--radius <RADIUS>': inf is not a finite number",
        ),
        (vec!["stamp", &missing, &missing, "--at", "1,1,1", "--scale", "0", "--color", "0,0,0", "-o", &out], "--scale"),
        (vec!["mask", "splotch", "--size", "100000", "-o", &out], "--size 100000 is out of range; allowed: 6 to 512"),
        (vec!["bake", &missing, "--res", "100000", "-o", &out], "--res 100000 is out of range; allowed: 2 to 512"),
        (
            vec!["make", "marble", "--size", "0", "-o", &out],
            "--size \"0\" is out of range; allowed: each side at least 1 and at most 512",
        ),
        (
            vec!["make", "marble", "--size", "99999999999999999999", "-o", &out],
            "is too large; allowed: each side at most 512",
        ),
    ];
    for (args, needle) in cases {
        assert_usage(&solidtex(&args), &[needle]);
    }
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
}

fn build(manifest: &Path, out: &Path) -> Output {
    solidtex(&["build", &manifest.to_string_lossy(), "-o", &out.to_string_lossy()])
}

#[test]
fn a_manifest_value_out_of_range_names_file_line_field_value_and_range() {
    let dir = inputs();
    let manifest = dir.path().join("lib.toml");
    let text = "[[exemplar]]\nname = \"k\"\nrecipe = \"sweep\"\nimage = \"kiwi.png\"\nlength = 8\naxis = \"x\"\n\
                [[exemplar.steps]]\nscatter = \"seed.obj\"\ncolor = \"#000000\"\ncount = 10000000\n";
    std::fs::write(&manifest, text).unwrap();
    let run = build(&manifest, &dir.path().join("out"));
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    for needle in ["lib.toml", "line 10", "entry 1 (k)", "count = 10000000", "allowed: 1 to 2000"] {
        assert!(err.contains(needle), "{needle:?} not in {err}");
    }
    assert!(!dir.path().join("out").join("k.exr").exists());
}

#[test]
fn a_vol_export_of_a_volume_that_is_not_a_cube_fails_with_the_manifest_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("lib.toml");
    let text = "[[exemplar]]\nname = \"flat\"\nrecipe = \"procedural:marble\"\nsize = [8, 8, 4]\n\
                exports = [\"nrrd\", \"vol\"]\n";
    std::fs::write(&manifest, text).unwrap();
    let out = dir.path().join("out");
    let run = build(&manifest, &out);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    for needle in ["lib.toml", "line 5", "entry 1 (flat)", "\"vol\" needs a cube", "8x8x4", "cubes only"] {
        assert!(err.contains(needle), "{needle:?} not in {err}");
    }
    let left: Vec<String> = if out.exists() { listing(&out) } else { Vec::new() };
    assert!(left.iter().all(|n| !n.starts_with("flat")), "{left:?}");
}

#[test]
fn a_manifest_that_is_not_toml_is_named_but_not_quoted() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("shape.obj");
    std::fs::write(&mesh, "v 0 0 0 private-words\nv 1 0 0\nf 1 2 1\n").unwrap();
    let run = build(&mesh, &dir.path().join("out"));
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("shape.obj") && err.contains("is not a TOML manifest"), "{err}");
    assert!(!err.contains("private-words") && !err.contains("v 0 0 0"), "the content is echoed: {err}");
    let png = dir.path().join("picture.png");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR secret").unwrap();
    let err = stderr(&build(&png, &dir.path().join("out")));
    assert!(err.contains("picture.png") && err.contains("not UTF-8"), "{err}");
    assert!(!err.contains("IHDR") && !err.contains("secret"), "the content is echoed: {err}");
}

#[test]
fn a_fill_spec_value_out_of_range_names_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let spec = dir.path().join("spec.toml");
    std::fs::write(&spec, "exemplar = \"marble\"\nseed = 2\ntets = 50000000\n").unwrap();
    let (mesh, out) = (at(dir.path(), "fruit.obj"), at(dir.path(), "model.lst"));
    assert!(solidtex(&["draw", "fruit", "-o", &mesh]).status.success());
    let run = solidtex(&["fill", &mesh, "--spec", &spec.to_string_lossy(), "-o", &out]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    for needle in ["spec.toml", "line 3", "tets = 50000000", "allowed: 100 to 200000"] {
        assert!(err.contains(needle), "{needle:?} not in {err}");
    }
    let run = solidtex(&["fill", &mesh, "--spec", &spec.to_string_lossy(), "--tets", "9", "-o", &out]);
    assert_usage(&run, &["--tets 9 is out of range"]);
}

#[test]
fn a_seed_outside_the_volume_names_the_mesh_and_the_volume() {
    let dir = inputs();
    let (base, seed, out) = (at(dir.path(), "base.exr"), at(dir.path(), "seed.obj"), at(dir.path(), "out.exr"));
    let run = solidtex(&["stamp", &base, &seed, "--at", "500,500,500", "--scale", "2", "--color", "0,0,0", "-o", &out]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    let line = err.lines().find(|l| l.starts_with("error:")).unwrap();
    assert!(line.contains("seed.obj") && line.contains("base.exr") && line.contains("wholly outside"), "{line}");
    let run = solidtex(&["blur", &base, "--at", "500,500,500", "--radius", "2", "-o", &out]);
    let line = stderr(&run).lines().find(|l| l.starts_with("error:")).unwrap_or_default().to_string();
    assert!(line.contains("base.exr") && line.contains("misses"), "{line}");
    assert!(written(dir.path()).is_empty(), "{:?}", written(dir.path()));
}

#[test]
fn stamping_into_the_file_it_reads_stays_allowed() {
    let dir = inputs();
    let (base, seed) = (at(dir.path(), "base.exr"), at(dir.path(), "seed.obj"));
    let run = solidtex(&["stamp", &base, &seed, "--at", "4,4,4", "--scale", "3", "--color", "0,0,0", "-o", &base]);
    assert!(run.status.success(), "{}", stderr(&run));
}

#[test]
fn an_output_folder_holding_other_files_is_refused_before_any_input_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("keep");
    std::fs::create_dir(&folder).unwrap();
    std::fs::write(folder.join("notes.txt"), "keep").unwrap();
    let (missing, keep) = (at(dir.path(), "missing.png"), folder.to_string_lossy().into_owned());
    let runs = [
        solidtex(&["sweep", &missing, "--length", "8", "-o", &keep]),
        solidtex(&["convert", &missing, &keep]),
        solidtex(&["synth", &missing, "--size", "8", "-o", &keep]),
        solidtex(&["mask", "layered", "--size", "8", "-o", &keep]),
    ];
    for run in &runs {
        let err = stderr(run);
        assert_eq!(run.status.code(), Some(1), "{err}");
        assert!(err.contains("keep") && err.contains("did not write") && !err.contains("missing.png"), "{err}");
    }
    assert_eq!(listing(&folder), ["notes.txt"]);
}

/// A negative, fractional, empty or too large number given to a whole-number option is
/// refused as a value of that option (exit 2), saying what it takes, not mistaken for an
/// unknown flag.
#[test]
fn negative_whole_numbers_are_refused_as_values() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png").to_string_lossy().into_owned();
    let cases =
        [("-5", "-5 is negative"), ("2.5", "2.5 is not a whole number"), ("", "an empty value is not a number")];
    let too_large = ("99999999999999999999", "99999999999999999999 is too large; give a whole number within");
    for (value, said) in cases.into_iter().chain([too_large]) {
        let run = crate::support::solidtex(&["make", "marble", "--seed", value, "-o", &out]);
        crate::support::assert_usage(&run, &["--seed", said, "whole number"]);
        assert!(!crate::support::stderr(&run).contains("unexpected argument"));
    }
    assert!(!dir.path().join("out.png").exists());
}

/// A number option given a value past what it holds (`1e308` for an f32), `inf` or `nan`
/// is refused as a value of that option (exit 2), naming the value, not read as infinity.
#[test]
fn numbers_that_are_not_finite_are_refused_as_values() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr").to_string_lossy().into_owned();
    for value in ["1e308", "inf", "-inf", "nan"] {
        let run = solidtex(&["mask", "splotch", "--size", "8", &format!("--falloff={value}"), "-o", &out]);
        assert_usage(&run, &["--falloff", &format!("{value} is not a finite number")]);
        let run = solidtex(&["export", "model.lst", &format!("--edge={value}"), "-o", &out]);
        assert_usage(&run, &["--edge", &format!("{value} is not a finite number")]);
    }
    assert!(!dir.path().join("out.exr").exists());
}

/// The options of a stroke cut's 3D view and sweep are refused with a planar cut, by name,
/// before any work (a planar cut has no camera, extrusion or displacement).
#[test]
fn stroke_cut_options_are_refused_with_a_plane() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cut.png").to_string_lossy().into_owned();
    for extra in [["--yaw", "30"], ["--pitch", "-10"], ["--extrude", "0,0,1"], ["--displacement", "0.1"]] {
        let run = solidtex(&[&["cut", "model.lst", "--plane", "0,0,0,1,0,0"][..], &extra, &["-o", &out]].concat());
        assert_usage(&run, &[extra[0], "--plane"]);
    }
    assert!(!dir.path().join("cut.png").exists());
}
