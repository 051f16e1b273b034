//! The coordinate core (`synth --core coordinates`, docs/synthesis.md, "The coordinate
//! core"): labels stay labels and keep far fewer pieces than the blend; outputs are
//! bit-identical on any thread count.

use crate::support::{assert_usage, at, solidtex, stderr};
use solidtex::labels;
use solidtex::procedural::{Recipe, generate};
use solidtex::progress::NoProgress;
use solidtex::synth::{Core, Exemplars, LayeredParams, SynthParams, synthesize, synthesize_layered};
use solidtex::volume::{Axis, Channel, Image2d, Volume};

fn central_slices(volume: &Volume) -> [Image2d; 3] {
    Axis::ALL.map(|a| volume.slice(a, volume.dims()[a.index()] / 2).unwrap())
}

fn coordinates(size: [usize; 3]) -> SynthParams {
    SynthParams { core: Core::Coordinates, size, ..SynthParams::default() }
}

/// The channels truth's central slices at 128 px into a 64³ solid by each core: the
/// coordinate core's voxels are all truth labels, and its phases come in at most twice
/// the truth's pieces per voxel, on average at most 1.3 times (0.45, 0.59 and 0.78
/// measured against the truth's 64³ tiles, z synthesized twice as finely; the blend: 18,
/// 55 and 30), each at most a quarter of the blend's. The channels (the lightest phase)
/// meet the synthesis issue's figures: pieces within twice the truth's, correlation
/// lengths 0.67-1.5 times on each axis (z 1.83 times at the grid's own sampling, 1.30
/// twice as fine), share within 2 points of the slices' mean, at most 1 speck per 100k
/// voxels more than the truth.
#[test]
fn labels_stay_labels_and_keep_far_fewer_pieces_than_the_blend() {
    let truth = generate(Recipe::Channels, [128; 3], 3).unwrap();
    let [x, y, z] = central_slices(&truth);
    let ex = Exemplars { x: &x, y: Some(&y), z: Some(&z) };
    let coords = synthesize(ex, &coordinates([64; 3]), 1, &NoProgress).unwrap();
    let blend = synthesize(ex, &SynthParams { size: [64; 3], ..SynthParams::default() }, 1, &NoProgress).unwrap();
    let labels: Vec<&[f32]> = x.data().chunks_exact(x.channel_count()).collect();
    for voxel in coords.data().chunks_exact(coords.channel_count()) {
        assert!(labels.contains(&voxel), "{voxel:?} is no label of the slices");
    }
    let pieces = |v: &Volume| -> Vec<f64> {
        labels::against_truth(v, &truth).unwrap().ratios.iter().map(|r| r.pieces_ratio).collect()
    };
    let (ours, theirs) = (pieces(&coords), pieces(&blend));
    let mean = ours.iter().sum::<f64>() / ours.len() as f64;
    assert!(mean <= 1.3 && ours.iter().all(|r| *r <= 2.0), "pieces over the truth's: {ours:?}");
    for (o, t) in ours.iter().zip(&theirs) {
        assert!(*o <= 0.25 * t, "pieces over the truth's: coordinates {ours:?}, blend {theirs:?}");
    }
    assert_eq!(coords.meta.get(solidtex::synth::finer::FINER_KEY), Some("z"), "the lenses are thin along z");
    let against = labels::against_truth(&coords, &truth).unwrap();
    let (channel, phase) = (against.ratios.last().unwrap(), against.volume.phases.last().unwrap());
    assert!((0.5..=2.0).contains(&channel.pieces_ratio), "{channel:?}");
    assert!(channel.correlation_ratio.iter().all(|c| c.is_some_and(|c| (0.67..=1.5).contains(&c))), "{channel:?}");
    assert!(channel.extra_specks_per_100k <= 1.0, "{channel:?}");
    let share = |image: &Image2d| {
        let pixels = image.data().chunks_exact(image.channel_count());
        pixels.filter(|p| p[0] == phase.label).count() as f64 / (image.width() * image.height()) as f64
    };
    let slices = (share(&x) + share(&y) + share(&z)) / 3.0;
    assert!((phase.share - slices).abs() <= 0.02, "channel share {} against the slices' {slices}", phase.share);
}

fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(f)
}

#[test]
fn homogeneous_and_layered_runs_are_bit_identical_on_1_and_2_threads() {
    let truth = generate(Recipe::Marble, [48; 3], 2).unwrap();
    let [x, ..] = central_slices(&truth);
    let params = SynthParams { levels: 2, ..coordinates([20, 16, 24]) };
    let plain = || synthesize(Exemplars { x: &x, y: None, z: None }, &params, 9, &NoProgress).unwrap();
    let layered = || synthesize_layered(&x, None, &params, &LayeredParams::default(), 9, &NoProgress).unwrap();
    let one = on_threads(1, plain);
    assert_eq!(on_threads(2, plain), one);
    assert_eq!(one.meta.get("core"), Some("coordinates"));
    let one = on_threads(1, layered);
    assert_eq!(on_threads(2, layered), one);
    assert_eq!(one.channels().last(), Some(&Channel::Depth));
}

#[test]
fn the_command_line_takes_a_core_and_refuses_others() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("spots.png");
    solidtex::io::write_image(&photo, &crate::support::spots(0.4, 2)).unwrap();
    let out = dir.path().join("v.exr");
    let (p, o) = (photo.to_string_lossy().into_owned(), out.to_string_lossy().into_owned());
    let ok = solidtex(&["synth", &p, "--size", "16", "--levels", "2", "--core", "coordinates", "-o", &o]);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let v = solidtex::io::read_volume(&out, u64::MAX).unwrap();
    assert_eq!(v.meta.get("core"), Some("coordinates"));
    let read = solidtex::io::read_image(&photo).unwrap();
    let dark = read.data().iter().copied().fold(1.0, f32::min);
    let light = read.data().iter().copied().fold(0.0, f32::max);
    assert!(v.data().iter().all(|s| *s == dark || *s == light), "a two-colour exemplar gives a two-colour solid");
    let bad = solidtex(&["synth", &p, "--size", "16", "--core", "mean", "-o", &o]);
    assert_usage(&bad, &["--core", "mean"]);
    assert!(crate::support::stderr(&bad).contains("possible values: blend, coordinates"));
    // by default a layered solid and a label image's solid come from the coordinate core, a
    // photo's homogeneous solid (or a layered one with a blend-only option) from the blend core
    let shaded = dir.path().join("shaded.png");
    let mut photo = crate::support::spots(0.4, 2);
    photo.data_mut().iter_mut().enumerate().for_each(|(i, v)| *v += (i % 40) as f32 / 400.0);
    solidtex::io::write_image(&shaded, &photo).unwrap();
    let shaded = shaded.to_string_lossy().into_owned();
    let core_of = |image: &str, args: &[&str]| {
        let base = ["synth", image, "--size", "8", "--levels", "1", "-o", &o];
        let run = solidtex(&[&base[..], args].concat());
        assert!(run.status.success(), "{}", crate::support::stderr(&run));
        let v = solidtex::io::read_volume(&out, u64::MAX).unwrap();
        (v.meta.get("core").map(str::to_string), v.data().iter().all(|s| *s == dark || *s == light))
    };
    assert_eq!(core_of(&shaded, &["--layered"]).0.as_deref(), Some("coordinates"));
    assert_eq!(core_of(&shaded, &[]).0.as_deref(), Some("blend"));
    assert_eq!(core_of(&p, &[]), (Some("coordinates".to_string()), true), "a label image keeps its labels");
    assert_eq!(core_of(&p, &["--core", "blend"]).0.as_deref(), Some("blend"));
    assert_eq!(core_of(&shaded, &["--layered", "--no-anti-sweeping"]).0.as_deref(), Some("blend"));
    assert_eq!(core_of(&shaded, &["--layered", "--core", "blend"]).0.as_deref(), Some("blend"));
}

/// Three exemplars with 20, 40 and 60 % white (mean 0.407): without the balance the
/// solid drifts to the dark majority (0.374); the balance moves it back the more the
/// stronger it is (0.378, 0.385 and 0.394 at `--histogram` 1, 2 and 4), within 3 points at
/// the default strength and 1.5 at 4.
#[test]
fn the_balance_holds_the_colour_distribution() {
    let images = [(0.2, 1), (0.4, 2), (0.6, 3)].map(|(white, seed)| crate::support::spots(white, seed));
    let expected = images.iter().map(|i| crate::support::white_share(i.data())).sum::<f64>() / 3.0;
    let ex = Exemplars { x: &images[0], y: Some(&images[1]), z: Some(&images[2]) };
    let share = |strength: f32| {
        let params = SynthParams { levels: 2, max_iterations: 2, histogram_strength: strength, ..coordinates([32; 3]) };
        crate::support::white_share(synthesize(ex, &params, 5, &NoProgress).unwrap().data())
    };
    let (off, on, strong) = (share(0.0), share(1.0), share(4.0));
    assert!((on - expected).abs() <= 0.03, "with the balance {on:.3}, the exemplars' mean {expected:.3}");
    assert!((strong - expected).abs() <= 0.015, "at strength 4 {strong:.3}, the exemplars' mean {expected:.3}");
    assert!(off < on && on < strong && strong - off >= 0.01, "shares {off:.3}, {on:.3}, {strong:.3} at 0, 1, 4");
}

/// A coordinate solid records how coherently it copies its exemplar (docs/synthesis.md,
/// "Coherent patches"): some neighbours coherent, no cut a tile of the exemplar; the blend
/// records nothing; `quality --check` names a largest patch above a quarter of the
/// exemplar's area.
#[test]
fn a_coordinate_solid_records_its_coherent_patches_and_quality_checks_them() {
    let truth = generate(Recipe::Marble, [64; 3], 4).unwrap();
    let [x, ..] = central_slices(&truth);
    let ex = Exemplars { x: &x, y: None, z: None };
    let params = SynthParams { levels: 2, ..coordinates([32; 3]) };
    let coords = synthesize(ex, &params, 3, &NoProgress).unwrap();
    let figure = |key: &str| coords.meta.get(key).and_then(|v| v.parse::<f64>().ok());
    let (pairs, largest) = (figure("coherent_pairs").unwrap(), figure("largest_patch").unwrap());
    assert!(pairs > 0.05 && pairs < 0.95, "coherent pairs {pairs}");
    assert!(largest > 1.0 / 4096.0 && largest <= 0.25, "largest patch {largest} of the exemplar's area");
    let blend = synthesize(ex, &SynthParams { size: [32; 3], levels: 2, ..SynthParams::default() }, 3, &NoProgress);
    assert_eq!(blend.unwrap().meta.get("largest_patch"), None);

    let dir = tempfile::tempdir().unwrap();
    let (photo, tiled) = (dir.path().join("x.png"), dir.path().join("tiled.exr"));
    solidtex::io::write_image(&photo, &x).unwrap();
    let mut forged = coords.clone();
    forged.meta.set("largest_patch", "0.5");
    solidtex::io::write_volume(&tiled, &forged).unwrap();
    let (p, t) = (photo.to_string_lossy().into_owned(), tiled.to_string_lossy().into_owned());
    let out = solidtex(&["quality", &t, "--exemplar", &p]);
    assert!(out.status.success());
    let table = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(table.contains("largest patch           0.500"), "{table}");
    let checked = solidtex(&["quality", &t, "--exemplar", &p, "--check"]);
    assert!(!checked.status.success());
    let said = crate::support::stderr(&checked);
    assert!(said.contains("largest coherent patch 0.500 of the exemplar's area (allowed at most 0.25)"), "{said}");
}

/// One picture named for every plane (from two files, or one file named three times) is the
/// isotropic case: the same solid as the picture alone, of type 0, never synthesized more
/// finely along an axis (the brick photo's rows and columns differ enough that the planes
/// taken as three exemplars would make x finer).
#[test]
fn one_picture_named_for_every_plane_is_the_picture_alone() {
    let dir = tempfile::tempdir().unwrap();
    let brick = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/brick_photo.png");
    let copy = at(dir.path(), "copy.png");
    std::fs::copy(brick, &copy).unwrap();
    let synth = |name: &str, planes: &[&str]| {
        let out = at(dir.path(), name);
        let mut args = vec!["synth", brick, "--core", "coordinates", "--max-exemplar", "64", "--size", "16"];
        args.extend_from_slice(planes);
        args.extend(["-o", &out]);
        let run = solidtex(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        assert!(!stderr(&run).contains("finely"), "{planes:?}: {}", stderr(&run));
        std::fs::read(&out).unwrap()
    };
    let alone = synth("alone.exr", &[]);
    assert_eq!(synth("three.exr", &["--ey", brick, "--ez", brick]), alone);
    assert_eq!(synth("copy.exr", &["--ey", &copy]), alone);
}
