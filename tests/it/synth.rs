//! Solid synthesis: determinism, layering, the anti-sweeping rule, histograms, bad input.

use solidtex::progress::NoProgress;
use solidtex::quality;
use solidtex::synth::{Exemplars, LayeredParams, SynthParams, synthesize, synthesize_layered};
use solidtex::volume::{Channel, Image2d, Volume};
use solidtex::{Error, noise};

/// A 40x40 exemplar of soft blobs in `channels` channels (procedural, so tests need no files).
fn blobs(channels: usize, seed: u64) -> Image2d {
    let roles = match channels {
        1 => Channel::grey(),
        3 => Channel::rgb(),
        _ => Channel::rgba(),
    };
    let mut data = Vec::new();
    for y in 0..40 {
        for x in 0..40 {
            let p = glam::Vec3::new(x as f32 / 10.0, y as f32 / 10.0, 0.5);
            for c in 0..channels {
                let n = noise::fbm(seed + c as u64, p, [4, 4, 4], 3);
                data.push((n * 0.5 + 0.5).clamp(0.0, 1.0));
            }
        }
    }
    Image2d::from_data(40, 40, roles, data).unwrap()
}

/// Horizontal bands that darken with the row: a layered exemplar.
fn bands() -> Image2d {
    let data = (0..40 * 40)
        .flat_map(|i| {
            let (x, y) = ((i % 40) as f32, (i / 40) as f32);
            let band = ((y / 5.0).floor() % 2.0) * 0.3
                + 0.2
                + 0.1 * noise::fbm(3, glam::Vec3::new(x / 8.0, y / 8.0, 0.0), [5; 3], 2);
            [band, band * 0.8, 1.0 - y / 40.0]
        })
        .collect();
    Image2d::from_data(40, 40, Channel::rgb(), data).unwrap()
}

fn small(size: [usize; 3]) -> SynthParams {
    SynthParams { size, levels: 2, max_iterations: 2, ..SynthParams::default() }
}

fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(f)
}

#[test]
fn the_same_seed_gives_the_same_volume_on_1_2_and_8_threads() {
    let ex = blobs(3, 1);
    let params = small([12, 10, 14]);
    let run = || synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 42, &NoProgress).unwrap();
    let one = on_threads(1, run);
    assert_eq!(on_threads(2, run), one);
    assert_eq!(on_threads(8, run), one);
    let other = synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 43, &NoProgress).unwrap();
    assert_ne!(other.data(), one.data(), "another seed gives another volume");
    assert_eq!(one.dims(), [12, 10, 14]);
    assert_eq!(one.meta.texture_type, Some(solidtex::TextureType::T0));
}

#[test]
fn layered_synthesis_is_deterministic_too() {
    let ex = bands();
    let params = small([10, 10, 16]);
    let run = || synthesize_layered(&ex, None, &params, &LayeredParams::default(), 5, &NoProgress).unwrap();
    let one = on_threads(1, run);
    assert_eq!(on_threads(3, run), one);
}

#[test]
fn layered_depth_rises_along_z() {
    let ex = bands();
    let v = synthesize_layered(&ex, None, &small([12, 12, 24]), &LayeredParams::default(), 1, &NoProgress).unwrap();
    let d = v.channel_index(&Channel::Depth).expect("a Depth channel");
    let means: Vec<f32> =
        (0..24).map(|z| (0..12 * 12).map(|i| v.get(i % 12, i / 12, z, d)).sum::<f32>() / 144.0).collect();
    assert!(means.windows(2).all(|w| w[1] >= w[0]), "{means:?}");
    assert!(means[0] < 0.15 && means[23] > 0.85, "{means:?}");
    assert_eq!(v.meta.texture_type, Some(solidtex::TextureType::T1b));
}

/// Progress that keeps the warnings.
#[derive(Default)]
struct Warnings(std::sync::Mutex<Vec<String>>);

impl solidtex::progress::Progress for Warnings {
    fn update(&self, _stage: &str, _fraction: f32) {}

    fn warn(&self, message: &str) {
        self.0.lock().unwrap().push(message.to_string());
    }
}

/// The blend core loses the layers' depths in a shallow solid (3 levels, 6 voxels deep):
/// the synthesis says so, with the figure; a deep enough one says nothing.
#[test]
fn a_layered_solid_whose_depth_strays_is_warned_about() {
    let ex = bands();
    let blend = |z: usize| {
        let params = SynthParams { size: [12, 12, z], levels: 3, core: solidtex::synth::Core::Blend, ..small([1; 3]) };
        let warnings = Warnings::default();
        let v = synthesize_layered(&ex, None, &params, &LayeredParams::default(), 1, &warnings).unwrap();
        (solidtex::synth::depth_error(&v).unwrap(), warnings.0.into_inner().unwrap())
    };
    let (error, said) = blend(6);
    assert!(error > 0.08 && said.iter().any(|w| w.contains("stray from their depths")), "{error}: {said:?}");
    let (error, said) = blend(40);
    assert!(error < 0.08 && said.is_empty(), "{error}: {said:?}");
}

/// Mean over rows (or z-slices) of the standard deviation of channel 0 inside the row.
fn within_layer_spread(rows: impl Iterator<Item = Vec<f32>>) -> f32 {
    let spreads: Vec<f32> = rows
        .map(|r| {
            let mean = r.iter().sum::<f32>() / r.len() as f32;
            (r.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / r.len() as f32).sqrt()
        })
        .collect();
    spreads.iter().sum::<f32>() / spreads.len() as f32
}

/// Each layer keeps the variation the exemplar has along its rows: a volume whose layers
/// are flat (what a global histogram transfer leaves) has nothing to show across depth.
#[test]
fn layered_synthesis_keeps_the_contrast_inside_each_layer() {
    // Rows of strong fBm texture on a brightness that rises with the row.
    let data = (0..48 * 48)
        .flat_map(|i| {
            let (x, y) = ((i % 48) as f32, (i / 48) as f32);
            let n = noise::fbm(11, glam::Vec3::new(x / 6.0, y / 6.0, 0.0), [8; 3], 3);
            let v = (0.15 + 0.6 * y / 47.0 + 0.25 * n).clamp(0.0, 1.0);
            [v, v, v]
        })
        .collect();
    let ex = Image2d::from_data(48, 48, Channel::rgb(), data).unwrap();
    let rows = within_layer_spread((0..48).map(|y| (0..48).map(|x| ex.pixel(x, y)[0]).collect()));
    let params = SynthParams { size: [24, 24, 48], levels: 2, max_iterations: 3, ..SynthParams::default() };
    let v = synthesize_layered(&ex, None, &params, &LayeredParams::default(), 3, &NoProgress).unwrap();
    let slices = within_layer_spread((0..48).map(|z| (0..24 * 24).map(|i| v.get(i % 24, i / 24, z, 0)).collect()));
    assert!(slices > 0.6 * rows, "spread inside a layer: volume {slices}, exemplar rows {rows}");
    assert!(slices < 1.4 * rows, "spread inside a layer: volume {slices}, exemplar rows {rows}");
}

/// The rule takes the coincidence out of the naive extension's fixed point. The start is
/// the diagonal sweep E((x + y) mod W, z), where every voxel's x and y neighbourhoods are
/// the same exemplar neighbourhood; a level of synthesis with the rule ends with fewer
/// voxels whose x and y matches coincide than the same synthesis without it. (From random
/// pixels the naive extension here does not sweep, so both sit at the index's floor of
/// chance coincidences: docs/synthesis.md.)
#[test]
fn the_anti_sweeping_rule_lowers_the_sweeping_index() {
    let ex = bands();
    let size = [16, 16, 40];
    let data = (0..16 * 16 * 40).flat_map(|i| ex.pixel((i % 16 + (i / 16) % 16) % 40, i / 256).to_vec()).collect();
    let start = Volume::from_data(size, ex.channels().to_vec(), data).unwrap();
    let params = SynthParams { size, levels: 1, finest_iterations: 4, start: Some(start), ..SynthParams::default() };
    let index = |rule: bool| {
        let layered = LayeredParams { anti_sweeping: rule, ..LayeredParams::default() };
        let v = synthesize_layered(&ex, None, &params, &layered, 7, &NoProgress).unwrap();
        quality::assess(&v, [Some(&ex), Some(&ex), None], true).unwrap().layered.unwrap().sweeping_index
    };
    let (with, without) = (index(true), index(false));
    assert!(without > 0.2, "the sweep start keeps its coincidences without the rule: {without}");
    assert!(with < 0.92 * without, "with the rule {with}, without {without}");
}

/// No voxel grid: a finer level that inherited its coarser level's matches doubled kept
/// a step at every 2-voxel block border. Colour steps between neighbours along x must be
/// as large at odd positions as at even ones (the old synthesis: 1.2 to 2 times larger).
#[test]
fn synthesis_leaves_no_grid_of_blocks() {
    let ex = blobs(3, 5);
    let n = 32;
    let params = SynthParams { size: [n; 3], levels: 3, ..SynthParams::default() };
    let v = synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 2, &NoProgress).unwrap();
    let mut steps = [0.0f64; 2];
    for (y, z, x) in (0..n).flat_map(|y| (0..n).flat_map(move |z| (0..n - 1).map(move |x| (y, z, x)))) {
        steps[x % 2] += (v.get(x + 1, y, z, 0) - v.get(x, y, z, 0)).abs() as f64;
    }
    let ratio = steps[1] / steps[0];
    assert!((0.9..1.1).contains(&ratio), "steps at odd x / even x: {ratio}");
}

/// A start volume sets the layout: starting from a volume dark in its left half and bright
/// in its right half, the synthesized volume keeps that split (the exemplar has both dark
/// and bright areas); from random pixels it does not.
#[test]
fn synthesis_refines_a_start_volume() {
    let ex = blobs(1, 4);
    let size = [24, 16, 16];
    let (dark, bright) = quantiles(&ex, 0.2, 0.8);
    let data = (0..24 * 16 * 16).map(|i| if i % 24 < 12 { dark } else { bright }).collect();
    let start = Volume::from_data(size, Channel::grey(), data).unwrap();
    let halves = |v: &Volume| {
        let mean = |left: bool| {
            let picked: Vec<f32> =
                v.data().iter().enumerate().filter(|(i, _)| (i % 24 < 12) == left).map(|s| *s.1).collect();
            picked.iter().sum::<f32>() / picked.len() as f32
        };
        mean(false) - mean(true)
    };
    let run = |start: Option<Volume>| {
        let params = SynthParams { start, ..small(size) };
        synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 5, &NoProgress).unwrap()
    };
    let (refined, free) = (halves(&run(Some(start))), halves(&run(None)));
    assert!(refined > 0.5 * (bright - dark), "split kept: {refined} of {}", bright - dark);
    assert!(free.abs() < 0.25 * (bright - dark), "split from random pixels: {free}");
}

/// The exemplar values at two quantiles.
fn quantiles(ex: &Image2d, a: f32, b: f32) -> (f32, f32) {
    let mut values = ex.data().to_vec();
    values.sort_by(f32::total_cmp);
    let at = |q: f32| values[(q * (values.len() - 1) as f32) as usize];
    (at(a), at(b))
}

#[test]
fn histogram_matching_lowers_the_histogram_distance() {
    let ex = blobs(1, 9);
    let distance = |strength: f32| {
        let params = SynthParams { histogram_strength: strength, ..small([16, 16, 16]) };
        let v = synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 3, &NoProgress).unwrap();
        quality::assess(&v, [Some(&ex), Some(&ex), Some(&ex)], false).unwrap().histograms[0].distance
    };
    let (on, off) = (distance(1.0), distance(0.0));
    assert!(on < off, "with matching {on}, without {off}");
    assert!(on < 0.05, "{on}");
}

#[test]
fn tiny_outputs_and_one_or_four_channels_work() {
    let grey = blobs(1, 2);
    let v = synthesize(Exemplars { x: &grey, y: None, z: None }, &small([8, 8, 8]), 1, &NoProgress).unwrap();
    assert_eq!((v.dims(), v.channel_count()), ([8, 8, 8], 1));
    let rgba = blobs(4, 2);
    let v = synthesize(Exemplars { x: &rgba, y: None, z: None }, &small([9, 7, 5]), 1, &NoProgress).unwrap();
    assert_eq!((v.dims(), v.channels()), ([9, 7, 5], Channel::rgba().as_slice()));
    assert!(v.data().iter().all(|s| (0.0..=1.0).contains(s)));
}

#[test]
fn anisotropic_exemplars_set_the_type() {
    let (a, b) = (blobs(3, 1), blobs(3, 2));
    let v = synthesize(Exemplars { x: &a, y: Some(&b), z: None }, &small([8, 8, 8]), 1, &NoProgress).unwrap();
    assert_eq!(v.meta.texture_type, Some(solidtex::TextureType::T1a));
    let v = synthesize(Exemplars { x: &a, y: Some(&b), z: Some(&a) }, &small([8, 8, 8]), 1, &NoProgress).unwrap();
    assert_eq!(v.meta.texture_type, Some(solidtex::TextureType::T2a));
}

fn message(result: Result<Volume, Error>) -> String {
    result.expect_err("must fail").to_string()
}

#[test]
fn bad_synthesis_input_is_refused_with_a_clear_message() {
    let ex = blobs(3, 1);
    let none = |p: &SynthParams| message(synthesize(Exemplars { x: &ex, y: None, z: None }, p, 1, &NoProgress));
    let tiny = Image2d::from_data(6, 6, Channel::rgb(), vec![0.5; 108]).unwrap();
    let err = message(synthesize(Exemplars { x: &tiny, y: None, z: None }, &small([8, 8, 8]), 1, &NoProgress));
    assert!(err.contains("Ex is 6x6 pixels") && err.contains("neighbourhood"), "{err}");
    let grey = blobs(1, 1);
    let err = message(synthesize(Exemplars { x: &ex, y: Some(&grey), z: None }, &small([8, 8, 8]), 1, &NoProgress));
    assert!(err.contains("Ey has 1 channel(s)") && err.contains("Ex has 3"), "{err}");
    let err = none(&small([8, 0, 8]));
    assert!(err.contains("8x0x8") && err.contains("at least 1"), "{err}");
    let err = none(&SynthParams { budget_bytes: 1000, ..small([64, 64, 64]) });
    assert!(err.contains("voxel budget"), "{err}");
    let err = none(&SynthParams { levels: 0, ..small([8, 8, 8]) });
    assert!(err.contains("levels = 0") && err.contains("1 to 8"), "{err}");
    let mut nan = ex.clone();
    nan.pixel_mut(3, 4)[1] = f32::NAN;
    let err = message(synthesize(Exemplars { x: &nan, y: None, z: None }, &small([8, 8, 8]), 1, &NoProgress));
    assert!(err.contains("(3, 4)") && err.contains("not finite"), "{err}");
    let depth = Image2d::from_data(20, 40, Channel::grey(), vec![0.5; 800]).unwrap();
    let err =
        message(synthesize_layered(&ex, Some(&depth), &small([8, 8, 8]), &LayeredParams::default(), 1, &NoProgress));
    assert!(err.contains("depth image is 20x40") && err.contains("40x40"), "{err}");
}

/// An exemplar made by tiling one patch would give a split-half baseline of copies; the
/// quality report finds the repeat and measures the baseline away from the copies.
#[test]
fn the_quality_baseline_skips_the_copies_of_a_tiled_exemplar() {
    let tile = blobs(1, 5);
    let data: Vec<f32> = (0..80 * 80).map(|i| tile.pixel((i % 80) % 40, (i / 80) % 40)[0]).collect();
    let tiled = Image2d::from_data(80, 80, Channel::grey(), data.clone()).unwrap();
    let volume = Volume::from_fn([16, 16, 16], Channel::grey(), |x, y, z, o| o[0] = data[(y + z) * 80 + x]).unwrap();
    let report = quality::assess(&volume, [Some(&tiled), None, None], false).unwrap();
    let x = &report.axes[0];
    let is_period = |o: &[i64; 2]| o.iter().all(|c| c.abs() % 40 == 0);
    assert!(!x.repeats.is_empty() && x.repeats.iter().all(is_period), "{:?}", x.repeats);
    let with_copies = x.exemplar_with_copies.expect("a repeated exemplar keeps the plain figure");
    assert!(with_copies < 1e-3, "the copies match exactly: {with_copies}");
    assert!(x.exemplar > 20.0 * with_copies.max(1e-4), "baseline away from copies {}", x.exemplar);

    let plain = blobs(1, 5);
    let report = quality::assess(&volume, [Some(&plain), None, None], false).unwrap();
    assert!(report.axes[0].repeats.is_empty(), "{:?}", report.axes[0].repeats);
    assert_eq!(report.axes[0].exemplar_with_copies, None);
}

#[test]
fn every_exemplar_counts_for_the_colour_distribution() {
    let images = [(0.2, 1), (0.4, 2), (0.6, 3)].map(|(white, seed)| crate::support::spots(white, seed));
    let expected = images.iter().map(|i| crate::support::white_share(i.data())).sum::<f64>() / 3.0;
    let ex = Exemplars { x: &images[0], y: Some(&images[1]), z: Some(&images[2]) };
    let v = synthesize(ex, &small([16, 16, 16]), 5, &NoProgress).unwrap();
    let share = crate::support::white_share(v.data());
    assert!((share - expected).abs() <= 0.02, "volume share {share:.3}, mean of the exemplars' {expected:.3}");
}

#[test]
fn a_directional_image_alone_gets_a_warning_naming_ey_ez_and_layered() {
    let dir = tempfile::tempdir().unwrap();
    let grain = dir.path().join("grain.png");
    image::GrayImage::from_fn(32, 32, |_, y| image::Luma([if (y / 3) % 2 == 0 { 40 } else { 200 }]))
        .save(&grain)
        .unwrap();
    let speckle = dir.path().join("speckle.png");
    image::GrayImage::from_fn(32, 32, |x, y| image::Luma([(noise::hash3(2, x as i64, y as i64, 0) % 256) as u8]))
        .save(&speckle)
        .unwrap();
    let out = dir.path().join("v.exr").to_string_lossy().into_owned();
    let run = |image: &std::path::Path| {
        let args = ["synth", &image.to_string_lossy(), "--size", "8", "--levels", "1", "-o", &out];
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex")).args(args).output().unwrap();
        assert!(output.status.success());
        String::from_utf8_lossy(&output.stderr).into_owned()
    };
    let warned = run(&grain);
    assert!(warned.contains("warning: ") && warned.contains("grain.png"), "{warned}");
    assert!(warned.contains("--ey/--ez") && warned.contains("--layered"), "{warned}");
    assert!(!run(&speckle).contains("warning"), "an isotropic image is not directional");
}

/// `--layered` takes each row of the image as one depth: an image whose rows are its
/// layers gets no warning, one whose stripes run down the columns is told to turn it or
/// give a depth image, and with `--depth` nothing is said; a depth image of another size is
/// refused by its own name.
#[test]
fn a_layered_image_whose_rows_are_not_layers_gets_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let save = |name: &str, f: &dyn Fn(u32, u32) -> u8| {
        let path = dir.path().join(name);
        image::GrayImage::from_fn(32, 32, |x, y| image::Luma([f(x, y)])).save(&path).unwrap();
        path.to_string_lossy().into_owned()
    };
    let rows = save("rows.png", &|_, y| if (y / 3) % 2 == 0 { 40 } else { 200 });
    let upright = save("upright.png", &|x, _| if (x / 3) % 2 == 0 { 40 } else { 200 });
    let ramp = save("ramp.png", &|_, y| (y * 8) as u8);
    let out = dir.path().join("v.exr").to_string_lossy().into_owned();
    let run = |args: &[&str]| {
        let base = ["synth", "--layered", "--size", "8", "--levels", "1", "-o", &out];
        let output = crate::support::solidtex(&[&base[..], args].concat());
        assert!(output.status.success(), "{}", crate::support::stderr(&output));
        crate::support::stderr(&output)
    };
    assert!(!run(&[&rows]).contains("warning"));
    let warned = run(&[&upright]);
    assert!(warned.contains("warning: ") && warned.contains("upright.png"), "{warned}");
    assert!(warned.contains("layers run down the columns") && warned.contains("--depth"), "{warned}");
    assert!(!run(&[&upright, "--depth", &ramp]).contains("warning"));
    // a depth image of another size is named as the file at fault
    let small = dir.path().join("small.png");
    image::GrayImage::from_fn(16, 16, |_, y| image::Luma([(y * 16) as u8])).save(&small).unwrap();
    let base = ["synth", "--layered", "--size", "8", "--levels", "1", "-o", &out];
    let run = crate::support::solidtex(&[&base[..], &[&upright, "--depth", &small.to_string_lossy()]].concat());
    crate::support::assert_fails(&run, &["small.png: the depth image is 16x16 pixels", "upright.png is 32x32"]);
}

/// The three central slices of a known solid (the procedural marble) as Ex, Ey, Ez: the
/// synthesized volume's grey-level shares stay within 2 points of the truth's, and on every
/// axis its two-point correlation is at most 1.5 times as far from the truth's as the
/// slices' own (0.73-1.43 times with the power spectrum matched; 1.4-5.5 times without).
#[test]
fn a_solid_from_the_slices_of_a_known_solid_keeps_its_shares() {
    let truth = solidtex::procedural::generate(solidtex::procedural::Recipe::Marble, [48, 48, 48], 3).unwrap();
    let axes = solidtex::volume::Axis::ALL;
    let ex: Vec<Image2d> = axes.iter().map(|&a| truth.slice(a, truth.dims()[a.index()] / 2).unwrap()).collect();
    let params = SynthParams { size: [48, 48, 48], ..SynthParams::default() };
    let v = synthesize(Exemplars { x: &ex[0], y: Some(&ex[1]), z: Some(&ex[2]) }, &params, 1, &NoProgress).unwrap();
    let comparison = solidtex::ground_truth::compare(&v, &truth).unwrap();
    assert!(comparison.share_error <= 2.0, "{comparison:?}");
    assert!(comparison.axes.iter().all(|a| a.volume_error <= 1.5 * a.slices_error), "{comparison:?}");
}

/// A 64x64 grey "gravel": light stones of radius 2 to 3 pixels packed on a dark ground
/// (procedural, by hash), a structured exemplar that random pixels do not imitate.
fn gravel() -> Image2d {
    let mut data = vec![0.15f32; 64 * 64];
    for k in 0..220 {
        let h = |i| noise::hash3(9, k, i, 0);
        let (cx, cy, r) = ((h(0) % 64) as i64, (h(1) % 64) as i64, 2.0 + (h(2) % 100) as f32 / 100.0);
        let shade = 0.55 + (h(3) % 40) as f32 / 100.0;
        for y in cy - 3..=cy + 3 {
            for x in cx - 3..=cx + 3 {
                let d = (((x - cx) * (x - cx) + (y - cy) * (y - cy)) as f32).sqrt();
                if d <= r {
                    data[(y.rem_euclid(64) * 64 + x.rem_euclid(64)) as usize] = shade - 0.05 * d;
                }
            }
        }
    }
    Image2d::from_data(64, 64, Channel::grey(), data).unwrap()
}

/// The finer levels keep the exemplar's sharpness and feature size: on a gravel of small
/// stones, three levels give cuts inside the yardstick's targets (gradient ratio 0.8 to
/// 1.2, autocorrelation-length ratio 0.7 to 1.3). A blend of disagreeing predictions, with
/// the whole volume's histogram stretched afterwards, gave soft blobs twice the stones'
/// size (gradient 0.55, length 2.0 on this exemplar).
#[test]
fn three_levels_keep_small_stones_sharp() {
    let ex = gravel();
    let params = SynthParams { size: [32, 32, 32], ..SynthParams::default() };
    let v = synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 1, &NoProgress).unwrap();
    for axis in solidtex::volume::Axis::ALL {
        let s = solidtex::sharpness::measure(&v, &ex, &[0], axis).unwrap();
        assert!(s.in_range(), "{s:?}");
    }
}
