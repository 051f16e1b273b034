//! Bad input: one test per kind of mistake. Each must fail with exit code 1, one
//! clear line naming the file and the problem, and leave no output behind.

use crate::support::{assert_fails, assert_usage, at, listing, random_volume, solidtex, solidtex_env, stderr};
use solidtex::io::{read_image, write_volume};
use solidtex::volume::{Channel, Volume};
use std::path::Path;

/// A good 8³ RGB volume written in `format` inside `dir`.
fn good(dir: &Path, name: &str) -> String {
    let path = dir.join(name);
    write_volume(&path, &random_volume([8, 8, 8], Channel::rgb(), 7)).unwrap();
    path.to_string_lossy().into_owned()
}

/// Keep the first `keep` bytes of a file.
fn truncate(path: &str, keep: usize) {
    let bytes = std::fs::read(path).unwrap();
    std::fs::write(path, &bytes[..keep.min(bytes.len())]).unwrap();
}

/// Converting `input` must fail with `needles` and write nothing next to it.
fn convert_fails(dir: &Path, input: &str, needles: &[&str]) {
    let before = listing(dir);
    let out = at(dir, "out.exr");
    assert_fails(&solidtex(&["convert", input, &out]), needles);
    assert_eq!(listing(dir), before, "convert left files behind");
}

#[test]
fn truncated_png_atlas() {
    let dir = tempfile::tempdir().unwrap();
    let png = good(dir.path(), "atlas.png");
    let len = std::fs::metadata(&png).unwrap().len() as usize;
    truncate(&png, len / 2);
    convert_fails(dir.path(), &png, &["atlas.png", "corrupt or truncated"]);
}

#[test]
fn truncated_png_exemplar_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("photo.png");
    image::RgbImage::from_pixel(32, 32, image::Rgb([9, 99, 199])).save(&path).unwrap();
    truncate(&path.to_string_lossy(), 60);
    let err = read_image(&path).unwrap_err().to_string();
    assert!(err.contains("photo.png") && err.contains("corrupt, truncated"), "{err}");
}

#[test]
fn corrupt_exr() {
    let dir = tempfile::tempdir().unwrap();
    let exr = good(dir.path(), "v.exr");
    let mut bytes = std::fs::read(&exr).unwrap();
    let mid = bytes.len() / 2;
    bytes.truncate(mid);
    bytes[8..40].fill(0xff);
    std::fs::write(&exr, bytes).unwrap();
    convert_fails(dir.path(), &exr, &["v.exr", "cannot read EXR"]);
}

#[test]
fn truncated_nrrd() {
    let dir = tempfile::tempdir().unwrap();
    let nrrd = good(dir.path(), "v.nrrd");
    let len = std::fs::metadata(&nrrd).unwrap().len() as usize;
    truncate(&nrrd, len - 100);
    convert_fails(dir.path(), &nrrd, &["v.nrrd", "truncated", "6144 bytes"]);
}

#[test]
fn truncated_vol() {
    let dir = tempfile::tempdir().unwrap();
    let vol = good(dir.path(), "v.vol");
    truncate(&vol, 5000);
    convert_fails(dir.path(), &vol, &["v.vol", "truncated .vol", "6144 bytes"]);
    truncate(&vol, 100);
    convert_fails(dir.path(), &vol, &["v.vol", "shorter than the 4096-byte header"]);
}

fn exr_with(path: &Path, size: (usize, usize), lines: &[&str]) {
    use exr::prelude::*;
    let mut attributes = LayerAttributes::named("test");
    let list = lines.iter().map(|l| Text::from(*l)).collect();
    attributes.other.insert(Text::from("solidtex"), AttributeValue::TextVector(list));
    let samples = FlatSamples::F32(vec![0.5; size.0 * size.1]);
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![AnyChannel::new("R", samples)]));
    Image::from_layer(Layer::new(size, attributes, Encoding::UNCOMPRESSED, channels)).write().to_file(path).unwrap();
}

#[test]
fn exr_whose_atlas_attributes_disagree_with_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("odd.exr");
    exr_with(&path, (10, 10), &["dims: 8 8 8"]);
    let p = path.to_string_lossy();
    convert_fails(dir.path(), &p, &["odd.exr", "atlas is 10x10 pixels", "dims 8x8x8", "24x24"]);
    exr_with(&path, (24, 24), &["dims: 8 8 8", "tiles: 2 4"]);
    convert_fails(dir.path(), &p, &["odd.exr", "tiles says \"2 4\"", "3x3"]);
    exr_with(&path, (24, 24), &["dims: 8 8 eight"]);
    convert_fails(dir.path(), &p, &["odd.exr", "dims \"8 8 eight\""]);
}

#[test]
fn plain_2d_exr_is_not_a_volume() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("photo.exr");
    image::Rgb32FImage::from_pixel(4, 4, image::Rgb([0.1, 0.2, 0.3])).save(&path).unwrap();
    convert_fails(dir.path(), &path.to_string_lossy(), &["photo.exr", "not a solidtex volume atlas"]);
}

#[test]
fn nan_in_exr_volume_and_exr_image() {
    let dir = tempfile::tempdir().unwrap();
    let mut v = random_volume([4, 4, 4], Channel::rgb(), 1);
    v.set(1, 2, 0, 1, f32::NAN);
    let path = dir.path().join("nan.exr");
    write_volume(&path, &v).unwrap();
    convert_fails(dir.path(), &path.to_string_lossy(), &["nan.exr", "channel G", "(1, 2)", "not finite"]);
    let photo = dir.path().join("nan_photo.exr");
    image::Rgb32FImage::from_fn(3, 3, |x, y| image::Rgb([if (x, y) == (2, 1) { f32::NAN } else { 0.5 }; 3]))
        .save(&photo)
        .unwrap();
    let err = read_image(&photo).unwrap_err().to_string();
    assert!(err.contains("nan_photo.exr") && err.contains("(2, 1)") && err.contains("not finite"), "{err}");
}

fn nrrd_header(sizes: &str) -> Vec<u8> {
    format!("NRRD0004\ntype: float\ndimension: 3\nsizes: {sizes}\nendian: little\nencoding: raw\n\n").into_bytes()
}

#[test]
fn zero_dims() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("zero.nrrd");
    std::fs::write(&path, nrrd_header("8 0 8")).unwrap();
    convert_fails(dir.path(), &path.to_string_lossy(), &["zero.nrrd", "contain a zero"]);
    let out = at(dir.path(), "m.exr");
    assert_usage(&solidtex(&["make", "marble", "--size", "8x0x8", "-o", &out]), &["\"8x0x8\"", "at least 1"]);
    assert_eq!(listing(dir.path()), ["zero.nrrd"]);
}

#[test]
fn dims_over_the_voxel_budget() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.nrrd");
    std::fs::write(&path, nrrd_header("100000 100000 100000")).unwrap();
    convert_fails(dir.path(), &path.to_string_lossy(), &["huge.nrrd", "100000x100000x100000", "voxel budget"]);
    let out = at(dir.path(), "m.exr");
    let run = solidtex_env(&["make", "wood", "--size", "64", "-o", &out], &[("SOLIDTEX_MAX_BYTES", "100000")]);
    assert_fails(&run, &["64x64x64", "over the voxel budget of 100000 bytes"]);
    assert_eq!(listing(dir.path()), ["huge.nrrd"]);
    // an empty value is unset: the default budget
    let run = solidtex_env(&["make", "wood", "--size", "8", "-o", &out], &[("SOLIDTEX_MAX_BYTES", "")]);
    assert!(run.status.success(), "{}", stderr(&run));
}

#[test]
fn a_channel_count_that_does_not_fit_the_format() {
    let dir = tempfile::tempdir().unwrap();
    let mut channels = Channel::rgba();
    channels.push(Channel::Depth);
    let input = dir.path().join("five.exr");
    write_volume(&input, &random_volume([4, 4, 4], channels, 1)).unwrap();
    let out = at(dir.path(), "five.png");
    assert_fails(
        &solidtex(&["convert", &input.to_string_lossy(), &out]),
        &["five.png", "1 to 4 channels", "R,G,B,A,Depth"],
    );
    let stack = at(dir.path(), "five_slices");
    assert_fails(&solidtex(&["convert", &input.to_string_lossy(), &stack]), &["1 to 4 channels"]);
    let cube = Volume::new([4, 4, 2], Channel::rgb()).unwrap();
    let err = write_volume(&dir.path().join("flat.vol"), &cube).unwrap_err().to_string();
    assert!(err.contains("cubes only") && err.contains("4x4x2"), "{err}");
    assert_eq!(listing(dir.path()), ["five.exr"]);
}

#[test]
fn output_in_a_folder_that_does_not_exist() {
    let dir = tempfile::tempdir().unwrap();
    let input = good(dir.path(), "v.exr");
    for out in ["missing/v.nrrd", "missing/v.png", "missing/slices/"] {
        let target = at(dir.path(), out);
        assert_fails(&solidtex(&["convert", &input, &target]), &["missing", "does not exist"]);
    }
    let sheet = at(dir.path(), "missing/sheet.png");
    assert_fails(&solidtex(&["sheet", &input, "-o", &sheet]), &["does not exist"]);
    assert_eq!(listing(dir.path()), ["v.exr"]);
}

#[test]
fn unknown_extension_and_missing_input() {
    let dir = tempfile::tempdir().unwrap();
    let input = good(dir.path(), "v.exr");
    // an output in no format solidtex writes is the command line's to correct: exit 2
    assert_usage(
        &solidtex(&["convert", &input, &at(dir.path(), "v.obj")]),
        &["v.obj", "allowed: .exr, .nrrd, .vol, .png"],
    );
    assert_fails(&solidtex(&["info", &at(dir.path(), "nope.exr")]), &["nope.exr", "no such file"]);
}

#[test]
fn usage_errors_exit_with_two() {
    let out = solidtex(&["slice"]);
    assert_eq!(out.status.code(), Some(2));
    let out = solidtex(&["frobnicate"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn synth_refuses_bad_exemplars_and_sizes_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = at(dir.path(), "out.exr");
    let photo = dir.path().join("nan.exr");
    image::Rgb32FImage::from_fn(32, 32, |x, y| image::Rgb([if (x, y) == (5, 6) { f32::NAN } else { 0.5 }; 3]))
        .save(&photo)
        .unwrap();
    let p = photo.to_string_lossy().into_owned();
    assert_fails(&solidtex(&["synth", &p, "--size", "8", "-o", &out]), &["nan.exr", "(5, 6)", "not finite"]);
    let small = dir.path().join("small.png");
    image::RgbImage::from_pixel(12, 12, image::Rgb([1, 2, 3])).save(&small).unwrap();
    let s = small.to_string_lossy().into_owned();
    assert_fails(&solidtex(&["synth", &s, "--size", "8", "-o", &out]), &["small.png", "12x12 pixels", "neighbourhood"]);
    assert_usage(&solidtex(&["synth", &s, "--size", "0", "-o", &out]), &["\"0\"", "at least 1"]);
    let run = solidtex(&["synth", &s, "--levels", "1", "--size", "8", "--pca-variance", "1.5", "-o", &out]);
    assert_usage(&run, &["--pca-variance 1.5", "0.01 to 1"]);
    assert_usage(&solidtex(&["synth", &s, "--size", "4096", "-o", &out]), &["\"4096\"", "at most 512"]);
    let big = solidtex_env(
        &["synth", &s, "--levels", "1", "--size", "512", "-o", &out],
        &[("SOLIDTEX_MAX_BYTES", "1000000")],
    );
    assert_fails(&big, &["512x512x512", "voxel budget"]);
    let depth = dir.path().join("depth.png");
    image::GrayImage::from_pixel(20, 12, image::Luma([9])).save(&depth).unwrap();
    let d = depth.to_string_lossy().into_owned();
    let run = solidtex(&["synth", &s, "--layered", "--depth", &d, "--levels", "1", "--size", "8", "-o", &out]);
    assert_fails(&run, &["depth image is 20x12", "12x12"]);
    let start = at(dir.path(), "start.exr");
    assert!(solidtex(&["make", "marble", "--size", "8", "-o", &start]).status.success());
    let run = solidtex(&["synth", &s, "--levels", "1", "--size", "10", "--start", &start, "-o", &out]);
    assert_fails(&run, &["start.exr", "8x8x8", "10x10x10"]);
    let grey = dir.path().join("grey.png");
    image::GrayImage::from_pixel(12, 12, image::Luma([90])).save(&grey).unwrap();
    let g = grey.to_string_lossy().into_owned();
    let run = solidtex(&["synth", &g, "--levels", "1", "--size", "8", "--start", &start, "-o", &out]);
    assert_fails(&run, &["start.exr", "channels R,G,B", "exemplar has"]);
    assert_eq!(listing(dir.path()), ["depth.png", "grey.png", "nan.exr", "small.png", "start.exr"]);
}

/// `bench --only` with a text no workload name contains is an error that names the groups
/// in full and where the whole list is, not a silent run of nothing; `--list` lists every
/// name, one per line.
#[test]
fn bench_refuses_an_only_that_matches_nothing() {
    let run = solidtex(&["bench", "--runs", "1", "--only", "no-such-workload"]);
    assert_usage(&run, &["--only \"no-such-workload\" matches no workload", "synth-coords, ", "bench --list"]);
    assert!(!crate::support::stderr(&run).contains("left out"), "{}", crate::support::stderr(&run));
    let list = solidtex(&["bench", "--list"]);
    let out = String::from_utf8_lossy(&list.stdout);
    assert!(list.status.success() && out.lines().any(|l| l == "synth/64cube/128px-rgb"), "{out}");
    assert!(out.lines().any(|l| l == "fill/large/fruit-2b/50k") && out.lines().count() > 20, "{out}");
}

/// A file name holding a NUL byte (possible in a manifest's TOML string, never on a command
/// line) is named with the byte shown as `\0`, and the message says no file name may hold one.
#[test]
fn a_nul_byte_in_a_file_name_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("nul.toml");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"a\"\nrecipe = \"load\"\nvolume = \"x\\u0000y.exr\"\n").unwrap();
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &at(dir.path(), "out")]);
    assert_eq!(run.status.code(), Some(1));
    let says = "x\\0y.exr\" holds a NUL byte (shown as \\0); no file name may contain one";
    assert!(stderr(&run).contains(says), "{}", stderr(&run));
}

/// A volume (EXR or PNG flipbook atlas) where a 2D photo is asked for is refused by name,
/// with its size, and nothing is written; one of its slices is a 2D image and is taken.
#[test]
fn a_volume_is_not_taken_for_a_photo() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for name in ["v.exr", "v.png"] {
        let volume = good(d, name);
        let before = listing(d);
        assert_fails(
            &solidtex(&["synth", &volume, "--size", "8", "--levels", "1", "-o", &at(d, "s.exr")]),
            &[name, "solidtex volume (8x8x8 voxels", "solidtex slice"],
        );
        assert_fails(&solidtex(&["noise", &volume, "--size", "8", "-o", &at(d, "n.exr")]), &[name, "not a 2D"]);
        assert_eq!(listing(d), before, "{name}: files left behind");
    }
    // an EXR volume under a .png name: the advice renames it first (a slice of fake.png would
    // be read as a PNG)
    std::fs::copy(d.join("v.exr"), d.join("fake.png")).unwrap();
    let run = solidtex(&["synth", &at(d, "fake.png"), "--size", "8", "--levels", "1", "-o", &at(d, "s.exr")]);
    assert_fails(&run, &["fake.png", "a .exr file under another extension", "fake.exr --axis z"]);
    std::fs::remove_file(d.join("fake.png")).unwrap();
    let slice = at(d, "slice.png");
    assert!(solidtex(&["slice", &at(d, "v.exr"), "--axis", "z", "-o", &slice]).status.success());
    assert_eq!(read_image(Path::new(&slice)).unwrap().width(), 8, "a slice reads as a picture");
}

/// A large photo read at its own size gets a note about `--max-exemplar`; one too large to
/// prepare within the memory budget is refused with its size and that way out, before the
/// work; shrunk, it is taken.
#[test]
fn a_photo_too_large_to_prepare_names_max_exemplar() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("big.png");
    let grey = (0..600 * 600).map(|i| (solidtex::noise::hash3(5, i, 0, 0) % 256) as f32 / 255.0).collect();
    solidtex::io::write_image(&photo, &solidtex::volume::Image2d::from_data(600, 600, Channel::grey(), grey).unwrap())
        .unwrap();
    let out = at(dir.path(), "s.exr");
    let budget = [("SOLIDTEX_MAX_BYTES", "4000000")];
    let run = solidtex_env(&["synth", &photo.to_string_lossy(), "--size", "8", "-o", &out], &budget);
    assert_fails(&run, &["600x600 pixels", "preparing it for synthesis", "--max-exemplar"]);
    assert!(stderr(&run).contains("note: ") && stderr(&run).contains("--max-exemplar 128 or 256"), "{}", stderr(&run));
    assert!(!Path::new(&out).exists());
    let small =
        solidtex_env(&["synth", &photo.to_string_lossy(), "--size", "8", "--max-exemplar", "64", "-o", &out], &budget);
    assert!(small.status.success(), "{}", stderr(&small));
}

/// A problem with an --ey or --ez image names that image, not the exemplar.
#[test]
fn errors_about_the_other_exemplars_name_their_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let (thin, colour) = (at(d, "w1.png"), at(d, "rgb.png"));
    image::GrayImage::from_pixel(1, 64, image::Luma([90])).save(&thin).unwrap();
    image::RgbImage::from_pixel(64, 64, image::Rgb([90, 60, 30])).save(&colour).unwrap();
    let starts = |run: &std::process::Output, file: &str| {
        let err = stderr(run);
        assert!(err.contains(&format!("error: {file}: ")), "{err}");
    };
    let run = solidtex(&["synth", photo, "--ez", &thin, "--max-exemplar", "64", "--size", "16", "-o", &at(d, "s.exr")]);
    assert_fails(&run, &["Ez is 1x64 pixels"]);
    starts(&run, &thin);
    let run = solidtex(&["noise", photo, "--ez", &colour, "--size", "16", "-o", &at(d, "n.exr")]);
    assert_fails(&run, &["3 channel(s)", "the same channels"]);
    starts(&run, &colour);
    let vol = at(d, "v.exr");
    assert!(solidtex(&["make", "marble", "--size", "16", "-o", &vol]).status.success());
    let run = solidtex(&["quality", &vol, "--exemplar", &thin]);
    assert_fails(&run, &["at least 10x10 pixels"]);
    starts(&run, &thin);
    // one least size, said the first time and of the exemplar, whatever the exemplar's size
    let small = at(d, "small.png");
    image::RgbImage::from_pixel(5, 5, image::Rgb([90, 60, 30])).save(&small).unwrap();
    let run = solidtex(&["quality", &vol, "--exemplar", &small]);
    assert_fails(&run, &["5x5 pixels", "at least 10x10 pixels"]);
    starts(&run, &small);
    assert!(!d.join("s.exr").exists() && !d.join("n.exr").exists());
}

/// `guided` names the --ez image whose size or channels do not fit, too.
#[test]
fn guided_names_the_other_exemplar_at_fault() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let thin = at(d, "w1.png");
    image::GrayImage::from_pixel(1, 64, image::Luma([90])).save(&thin).unwrap();
    let args = ["guided", &fruit, "--spec", &spec, "--exemplar", photo, "--ez", &thin, "--res", "32"];
    let run = solidtex(&[&args[..], &["--cut", "0,0,0,1,0,0", "-o", &at(d, "g.png")]].concat());
    assert_fails(&run, &["Ez is 1x64 pixels"]);
    assert!(stderr(&run).contains(&format!("error: {thin}: ")), "{}", stderr(&run));
}

/// The voxel budget of `noise` counts the channels the volume will have: the exemplar's.
#[test]
fn the_noise_budget_counts_the_exemplars_channels() {
    let dir = tempfile::tempdir().unwrap();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let args = ["noise", photo, "--size", "128", "-o", &at(dir.path(), "n.exr")];
    // the photo fits (2.4 MB to decode), its 128³ grey volume (8.4 MB) does not
    let run = solidtex_env(&args, &[("SOLIDTEX_MAX_BYTES", "4000000")]);
    assert_fails(&run, &["128x128x128 volume with 1 channel(s)"]);
}

/// `quality` refuses an --ey image whose channels differ from the exemplar's, naming it
/// and both counts (as `synth` and `noise` do), instead of measuring.
#[test]
fn quality_refuses_other_exemplars_with_other_channels() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (grey, colour, vol) = (at(d, "grey.png"), at(d, "rgb.png"), at(d, "v.exr"));
    image::GrayImage::from_pixel(64, 64, image::Luma([90])).save(&grey).unwrap();
    image::RgbImage::from_pixel(64, 64, image::Rgb([90, 60, 30])).save(&colour).unwrap();
    assert!(solidtex(&["make", "marble", "--size", "16", "-o", &vol]).status.success());
    let run = solidtex(&["quality", &vol, "--exemplar", &colour, "--ey", &grey, "--check"]);
    assert_fails(&run, &["has 1 channel(s)", &colour, "has 3", "the same channels"]);
    assert!(stderr(&run).contains(&format!("error: {grey}: ")), "{}", stderr(&run));
}

/// `quality` measures a volume on cuts of at least 8x8 voxels: a volume with no such cut
/// is refused, naming it, its size and the size needed, with no figures printed; a volume
/// with some (1x64x64: the cut across x) is measured there, saying which axes are not.
#[test]
fn quality_measures_only_the_cuts_large_enough() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let (dot, sheet) = (at(d, "dot.exr"), at(d, "sheet.exr"));
    assert!(solidtex(&["make", "marble", "--size", "1", "-o", &dot]).status.success());
    assert!(solidtex(&["make", "marble", "--size", "1x64x64", "-o", &sheet]).status.success());
    let run = solidtex(&["quality", &dot, "--exemplar", photo, "--check"]);
    assert_fails(&run, &[&dot, "1x1x1", "8x8"]);
    assert!(run.stdout.is_empty(), "{}", String::from_utf8_lossy(&run.stdout));
    let run = solidtex(&["quality", &sheet, "--exemplar", photo, "--json"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let axes = |key: &str| report[key].as_array().unwrap().iter().map(|a| a["axis"].clone()).collect::<Vec<_>>();
    assert_eq!(axes("axes"), ["x"]);
    assert_eq!(axes("sharpness"), ["x"]);
    assert_eq!(axes("lines"), ["x"]);
    let err = stderr(&run);
    assert!(err.contains("1x64x64") && err.contains("y and z") && err.contains("not measured"), "{err}");
}

/// `guided --planes` names the --ez image whose size or channels do not fit, as the
/// solid-cube path does.
#[test]
fn guided_on_planes_names_the_other_exemplar_at_fault() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let (thin, colour) = (at(d, "w1.png"), at(d, "rgb.png"));
    image::GrayImage::from_pixel(1, 64, image::Luma([90])).save(&thin).unwrap();
    image::RgbImage::from_pixel(64, 64, image::Rgb([90, 60, 30])).save(&colour).unwrap();
    for (ez, says) in [(&thin, "is 1x64 pixels"), (&colour, "channels R,G,B")] {
        let args = ["guided", &fruit, "--spec", &spec, "--exemplar", photo, "--ez", ez, "--planes", "--res", "32"];
        let run = solidtex(&[&args[..], &["--cut", "0,0,0,1,0,0", "-o", &at(d, "g.png")]].concat());
        assert_fails(&run, &[says]);
        assert!(stderr(&run).contains(&format!("error: {ez}: ")), "{}", stderr(&run));
    }
    assert!(!d.join("g.png").exists());
}

/// The voxel budget of `make` counts the channels the recipe makes: three for marble,
/// four for strata (colours and Depth).
#[test]
fn the_make_budget_counts_the_recipes_channels() {
    let dir = tempfile::tempdir().unwrap();
    let budget = [("SOLIDTEX_MAX_BYTES", "100000")];
    for (recipe, says) in [("marble", "64x64x64 volume with 3 channel(s)"), ("strata", "with 4 channel(s)")] {
        let out = at(dir.path(), "m.exr");
        let run = solidtex_env(&["make", recipe, "--size", "64", "-o", &out], &budget);
        assert_fails(&run, &[says]);
        assert!(!Path::new(&out).exists());
    }
}
