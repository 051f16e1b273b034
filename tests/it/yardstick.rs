//! The structure yardstick (docs/synthesis.md, "Line structure" and "Checking a volume"):
//! 3D truths with long features pass against their own central slices; volumes with the
//! right numbers but no shapes (random-phase noise with the spectrum and exact colours, a
//! blur, a flat and a shuffled volume) fail, on the truths and on the brick photo.

use crate::support::{assert_fails, assert_usage, at, solidtex, stderr};
use solidtex::controls;
use solidtex::labels;
use solidtex::lines::{self, Lines};
use solidtex::procedural::{Recipe, generate};
use solidtex::volume::{Axis, Image2d, Volume};

/// The two truths at the size their figures are documented for, and the seed.
const TRUTHS: [(Recipe, u64); 2] = [(Recipe::Foam, 1), (Recipe::Channels, 3)];
const SIDE: usize = 128;

fn central_slices(volume: &Volume) -> [Image2d; 3] {
    Axis::ALL.map(|a| volume.slice(a, volume.dims()[a.index()] / 2).unwrap())
}

fn line_figures(volume: &Volume, exemplars: &[Image2d; 3]) -> Vec<Lines> {
    let picks: Vec<usize> = (0..exemplars[0].channel_count()).collect();
    Axis::ALL.iter().map(|&a| lines::measure(volume, &exemplars[a.index()], &picks, a).unwrap()).collect()
}

/// Fails (a) or (b): the lines come in too many or too few pieces, or short ones.
fn shapeless(l: &Lines) -> bool {
    let p = &l.lines;
    !(lines::PIECES_BAND.0..=lines::PIECES_BAND.1).contains(&p.pieces_ratio) || p.top3_ratio < lines::TOP3_LEAST
}

fn spectral_noise(exemplars: &[Image2d; 3], seed: u64) -> Volume {
    let [x, y, z] = exemplars;
    controls::spectral_noise([Some(x), Some(y), Some(z)], [64; 3], seed).unwrap()
}

#[test]
fn the_truths_keep_their_lines_in_every_cut() {
    for (recipe, seed) in TRUTHS {
        let truth = generate(recipe, [SIDE; 3], seed).unwrap();
        for l in line_figures(&truth, &central_slices(&truth)) {
            assert!(l.applies, "{recipe} {}: the truth's slices have line structure: {l:?}", l.axis);
            assert!(l.outside_bands().is_empty(), "{recipe}: {:?} {:?}", l.outside_bands(), l.lines);
        }
    }
}

#[test]
fn noise_with_the_truths_spectrum_and_colours_fails_lines_and_labels() {
    for (recipe, seed) in TRUTHS {
        let truth = generate(recipe, [SIDE; 3], seed).unwrap();
        let slices = central_slices(&truth);
        let noise = spectral_noise(&slices, 7);
        for l in line_figures(&noise, &slices) {
            assert!(shapeless(&l), "{recipe} noise, axis {}: {:?}", l.axis, l.lines);
        }
        let against = labels::against_truth(&noise, &truth).unwrap();
        let most = against.ratios.iter().map(|r| r.pieces_ratio).fold(0.0, f64::max);
        assert!(most > 10.0, "{recipe} noise: pieces ratios {:?}", against.ratios);
        assert!(!against.outside_bands().is_empty());
        assert!(labels::against_truth(&truth, &truth).unwrap().outside_bands().is_empty());
    }
}

#[test]
fn blurred_flat_and_shuffled_truths_fail_on_every_axis() {
    let truth = generate(Recipe::Foam, [SIDE; 3], 1).unwrap();
    let slices = central_slices(&truth);
    let bad = [
        ("blurred", controls::blurred(&truth, 1.5).unwrap()),
        ("flat", controls::flat(&truth, 0.6).unwrap()),
        ("shuffled", controls::shuffled(&truth, 3).unwrap()),
    ];
    for (name, volume) in &bad {
        for l in line_figures(volume, &slices) {
            assert!(!l.outside_bands().is_empty(), "{name}, axis {}: {:?}", l.axis, l.lines);
        }
    }
}

/// The brick photo's mortar: noise with its spectrum and exact colours breaks the
/// connected grid into short pieces.
#[test]
fn noise_with_the_brick_photos_spectrum_and_colours_fails() {
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/brick_photo.png");
    let brick = solidtex::io::read_image_fit(std::path::Path::new(photo), Some(128)).unwrap();
    let noise = controls::spectral_noise([Some(&brick); 3], [64; 3], 1).unwrap();
    let grey = |data: &[f32]| -> std::collections::BTreeSet<u32> { data.iter().map(|v| v.to_bits()).collect() };
    assert_eq!(brick.channel_count(), 1);
    assert!(grey(noise.data()).is_subset(&grey(brick.data())), "the noise has the photo's exact greys");
    let slices = [brick.clone(), brick.clone(), brick];
    for l in line_figures(&noise, &slices) {
        assert!(l.applies && shapeless(&l), "axis {}: {:?}", l.axis, l.lines);
    }
}

/// The targets for synthesis from a truth's central slices, measured against the truth:
/// every label and line band. The blend core misses them (docs/synthesis.md, "Baseline"),
/// and so does the coordinate core so far ("The coordinate core": the foam's stones are
/// mottled; the channels' matrix lies in layers too thick along z and both it and the
/// rims come in fewer pieces than the truth's); `cargo test -- --ignored` runs this.
#[test]
#[ignore = "the targets of the coordinate core; it still misses the foam's label pieces (its stones mottled) and some of the channels' label bands"]
fn synthesis_from_the_truths_slices_keeps_their_pieces() {
    for (recipe, seed) in TRUTHS {
        let truth = generate(recipe, [SIDE; 3], seed).unwrap();
        let [x, y, z] = central_slices(&truth);
        let core = solidtex::synth::Core::Coordinates;
        let params = solidtex::synth::SynthParams { size: [64; 3], core, ..Default::default() };
        let ex = solidtex::synth::Exemplars { x: &x, y: Some(&y), z: Some(&z) };
        let v = solidtex::synth::synthesize(ex, &params, 1, &solidtex::progress::NoProgress).unwrap();
        let against = labels::against_truth(&v, &truth).unwrap();
        assert!(against.outside_bands().is_empty(), "{recipe}: {:?}", against.outside_bands());
        let lines = line_figures(&v, &[x, y, z]);
        assert!(lines.iter().all(|l| l.outside_bands().is_empty()), "{recipe}: {lines:?}");
    }
}

/// `quality --check` exits 0 on the truth and 1 on the noise, naming the figures outside
/// their bands; with `--labels` it needs `--truth` and reads no exemplar options.
#[test]
fn quality_check_passes_the_truth_and_names_what_the_noise_fails() {
    let dir = tempfile::tempdir().unwrap();
    let truth = generate(Recipe::Channels, [SIDE; 3], 3).unwrap();
    let slices = central_slices(&truth);
    let names = ["ex.png", "ey.png", "ez.png"].map(|n| at(dir.path(), n));
    for (image, name) in slices.iter().zip(&names) {
        solidtex::io::write_image(std::path::Path::new(name), image).unwrap();
    }
    let (t, n) = (at(dir.path(), "truth.exr"), at(dir.path(), "noise.exr"));
    solidtex::io::write_volume(std::path::Path::new(&t), &truth).unwrap();
    let made = solidtex(&["noise", &names[0], "--ey", &names[1], "--ez", &names[2], "--size", "64", "-o", &n]);
    assert!(made.status.success(), "{}", stderr(&made));
    let lines_only = |v: &str| {
        let run = solidtex(&["quality", v, "--exemplar", &names[0], "--ey", &names[1], "--ez", &names[2], "--json"]);
        assert!(run.status.success(), "{}", stderr(&run));
        run
    };
    let json: serde_json::Value = serde_json::from_slice(&lines_only(&t).stdout).unwrap();
    assert!(json["lines"].as_array().unwrap().iter().all(|l| l["applies"] == true), "{}", json["lines"]);
    let truth_check =
        solidtex(&["quality", &t, "--exemplar", &names[0], "--ey", &names[1], "--ez", &names[2], "--check"]);
    assert!(truth_check.status.success(), "the truth against its own slices: {}", stderr(&truth_check));
    let labels = |v: &str| solidtex(&["quality", v, "--labels", "--truth", &t, "--check"]);
    let good = labels(&t);
    assert!(good.status.success(), "{}", stderr(&good));
    assert!(stderr(&good).contains("every figure is within its band"), "{}", stderr(&good));
    let bad = labels(&n);
    assert_eq!(bad.status.code(), Some(1), "{}", stderr(&bad));
    assert!(stderr(&bad).contains("pieces ratio") && stderr(&bad).contains("allowed 0.7-1.3"), "{}", stderr(&bad));
    let check = solidtex(&["quality", &n, "--exemplar", &names[0], "--ey", &names[1], "--ez", &names[2], "--check"]);
    assert_eq!(check.status.code(), Some(1), "{}", stderr(&check));
    let named = stderr(&check);
    assert!(named.contains("line pieces ratio") || named.contains("line top-3 share ratio"), "{named}");
    assert_usage(&solidtex(&["quality", &n, "--labels", "--check"]), &["--check", "--truth"]);
    assert_usage(&solidtex(&["quality", &n, "--truth", &t]), &["--truth compares label volumes", "--labels"]);
    for extra in [["--ey", "missing.png"], ["--max-exemplar", "8"]] {
        let ignored = solidtex(&["quality", &n, "--labels", "--truth", &t, extra[0], extra[1]]);
        assert_usage(&ignored, &[extra[0], "--labels measures the volume's phases"]);
    }
    // a volume too small to compare is named, not the truth
    let tiny = at(dir.path(), "tiny.exr");
    solidtex::io::write_volume(std::path::Path::new(&tiny), &generate(Recipe::Channels, [7; 3], 1).unwrap()).unwrap();
    let small = solidtex(&["quality", &tiny, "--labels", "--truth", &t]);
    assert_fails(&small, &["tiny.exr: is 7x7x7 voxels", "at least 8 voxels"]);
    assert!(!stderr(&small).contains("truth.exr"), "{}", stderr(&small));
}

/// `slice --plane` cuts a volume obliquely: a plane with normal z through the middle is
/// the middle z slice, image axes and all; a bad plane is a usage error naming the option.
#[test]
fn slice_cuts_any_plane() {
    let dir = tempfile::tempdir().unwrap();
    let v = at(dir.path(), "v.exr");
    let volume = generate(Recipe::Foam, [32; 3], 1).unwrap();
    solidtex::io::write_volume(std::path::Path::new(&v), &volume).unwrap();
    let (a, b, c) = (at(dir.path(), "a.png"), at(dir.path(), "b.png"), at(dir.path(), "c.png"));
    assert!(solidtex(&["slice", &v, "--axis", "z", "--index", "16", "-o", &a]).status.success());
    let run = solidtex(&["slice", &v, "--plane", "16,16,16,0,0,1", "-o", &b]);
    assert!(run.status.success(), "{}", stderr(&run));
    let [pa, pb] = [&a, &b].map(|p| solidtex::io::read_image(std::path::Path::new(p)).unwrap());
    assert_eq!(pa, pb, "a plane with normal z through a voxel is the z slice");
    let run = solidtex(&["slice", &v, "--plane", "16,16,16,1,1,1", "-o", &c]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_ne!(solidtex::io::read_image(std::path::Path::new(&c)).unwrap(), pa);
    for bad in ["1,2,3", "1,2,3,0,0,0", "a,b,c,d,e,f", "1,2,3,4,5,nan"] {
        assert_usage(&solidtex(&["slice", &v, "--plane", bad, "-o", &c]), &["--plane"]);
    }
}
