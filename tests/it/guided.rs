//! Sketch-guided solid texturing: the frame field and its picture, guided cuts and solids.

use crate::support::{at, solidtex, stderr};

/// The background of a cut's picture outside the model, `solidtex cut`'s and `guided --cut`'s.
const BACKGROUND: [u8; 3] = [24, 24, 28];

/// Whether a cut's pixel shows the model (anything but the background).
fn shown(p: &image::Rgba<u8>) -> bool {
    p.0[..3] != BACKGROUND
}

/// `solidtex field` draws the kiwi spec's field on the cut through the fruit's axis: inside,
/// the frames' x axis follows the stroke along the fruit (red: x in model space), outside
/// is black; a spec without strokes is refused by name.
#[test]
fn the_field_of_a_kiwi_spec_follows_its_stroke_on_a_cut() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let png = at(d, "field.png");
    let run = solidtex(&["field", &fruit, "--spec", &spec, "--size", "96", "--plane", "0,0,0,0,0,1", "-o", &png]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("sketched frames; the field solved in"), "{}", stderr(&run));
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.get_pixel(1, 1).0, [0, 0, 0], "outside the fruit");
    let mut red = 0;
    for x in 30..66 {
        let [r, g, b] = img.get_pixel(x, 48).0;
        if r > g && r > b {
            red += 1;
        }
    }
    assert!(red >= 30, "{red} of 36 pixels along the axis show x as red");
    assert!(stderr(&run).contains("the frames turn by at most"), "{}", stderr(&run));
    assert!(!stderr(&run).contains("misses the model"), "{}", stderr(&run));
    let run = solidtex(&["field", &fruit, "--spec", &spec, "--size", "32", "--plane", "9,0,0,1,0,0", "-o", &png]);
    assert!(stderr(&run).contains("warning: the plane misses the model"), "{}", stderr(&run));

    // one straight stroke and no depth: the same frame everywhere, no turn anywhere
    let straight = crate::fill::spec(
        d,
        "straight.toml",
        "exemplar = \"kiwi\"\n[[direction]]\npoints = [[-0.5, 0, 0], [0.5, 0, 0]]\n",
    );
    let run = solidtex(&["field", &fruit, "--spec", &straight, "--size", "96", "-o", &at(d, "straight.png")]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("at most 0.0° between neighbouring voxels of the cut; 0 of "), "{}", stderr(&run));

    let bare = crate::fill::spec(d, "bare.toml", "exemplar = \"kiwi\"\n");
    let run = solidtex(&["field", &fruit, "--spec", &bare, "-o", &at(d, "bare.png")]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("bare.toml") && stderr(&run).contains("direction stroke"), "{}", stderr(&run));
    assert!(!d.join("bare.png").exists());
}

/// `field`'s report on the cut of `mesh` by `spec` through `plane`: the largest turn
/// between neighbouring voxels' frames (as `guided --res 256` reads the field) and how
/// many pairs turn by more than 30°. The picture is small: the turns are counted between
/// voxels whatever its size.
fn turns(mesh: &str, spec: &str, plane: &str, png: &str) -> (f32, usize) {
    let run = solidtex(&["field", mesh, "--spec", spec, "--plane", plane, "--size", "32", "-o", png]);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    let largest = err.split("turn by at most ").nth(1).and_then(|t| t.split('°').next()).expect("the turn report");
    let tail = err.split("between neighbouring voxels of the cut; ").nth(1).expect("the turn report");
    (largest.parse().unwrap(), tail.split(' ').next().unwrap().parse().unwrap())
}

/// No blob where the field vanishes (a blob turns frames by 90-180° between neighbours):
/// neighbouring voxels' frames turn by at most 30° everywhere but within two voxels of a
/// depth axis or of the line it carries on along past its ends, on the kiwi (the tests'
/// spec on the drawn fruit, whose axis ends inside the fruit) and on the log (the
/// repository's trunk spec on the drawn log). With the RBF's own gradient beside the axis
/// the kiwi's cuts through the axis held 2-10 pairs of 31-34° just past the two voxels.
#[test]
fn the_frames_turn_smoothly_but_on_the_depth_axes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, kiwi) = crate::fill::kiwi_fruit(d);
    let png = at(d, "field.png");
    for plane in ["0,0,0,1,0,0", "0,0,0,0,0,1", "0,0,0,0,1,0", "0,0,0,0,1,1"] {
        let (largest, over) = turns(&fruit, &kiwi, plane, &png);
        assert!(largest <= 30.0 && over == 0, "kiwi, plane {plane}: {largest}°, {over} pairs over 30°");
    }
    let log = crate::fill::draw(d, "log");
    let trunk = crate::fill::spec(d, "trunk.toml", crate::fill::TRUNK);
    for plane in ["0,0,1,0,0,1", "0,0,1,1,0,0", "0,0,1,1,1,0"] {
        assert_eq!(turns(&log, &trunk, plane, &png).1, 0, "log, plane {plane}");
    }
}

/// The repository's CC0 gravel photo.
fn gravel() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png").to_string()
}

/// `solidtex guided --cut` writes the cut through the fruit: the background of `solidtex
/// cut` outside, textured (not flat) inside; it reports the voxels it synthesized, far fewer than a
/// whole solid; with `--cache` a second cut is the same picture, a file at the cache's
/// name that solidtex did not write there stops the run and stays as it was, and a cache
/// file of its own that was damaged is rebuilt with a warning.
#[test]
fn a_guided_cut_is_synthesized_on_demand_and_cached() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let cut = |out: &str, cache: bool| {
        let mut args = vec!["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64"];
        args.extend(["--res", "64", "--cut", "0,0,0,0,0,1", "--size", "64", "-o", out]);
        let folder = at(d, "cache");
        if cache {
            args.extend(["--cache", &folder]);
        }
        solidtex(&args.iter().map(|s| &**s).collect::<Vec<&str>>())
    };
    let plain = at(d, "cut.png");
    let run = cut(&plain, false);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    let line = err.lines().find(|l| l.starts_with("voxels synthesized:")).expect("the voxel report");
    let numbers: Vec<f64> = line.split(' ').filter_map(|w| w.parse().ok()).collect();
    assert!(numbers[0] < 0.6 * numbers[1], "{line}");
    let img = image::open(&plain).unwrap().to_rgb8();
    assert_eq!(img.get_pixel(0, 0).0, BACKGROUND, "outside the fruit is the cut's background");
    let inside: Vec<[u8; 3]> = (24..40).map(|x| img.get_pixel(x, 32).0).collect();
    assert!(inside.iter().all(|p| *p != BACKGROUND), "inside is the texture");
    let (lo, hi) = inside.iter().fold((255, 0), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
    assert!(hi - lo > 20, "the cut is textured: green {lo}..{hi}");

    // a wider coarsest neighbourhood gives another cut; an even side is refused
    let wide = at(d, "wide.png");
    let mut args = vec!["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "64"];
    args.extend(["--cut", "0,0,0,0,0,1", "--size", "64", "--coarse-n", "7", "-o", &wide]);
    let run = solidtex(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_ne!(std::fs::read(&wide).unwrap(), std::fs::read(&plain).unwrap());
    let even = at(d, "even.png");
    let last = args.len() - 1;
    args[last] = &even;
    args[last - 2] = "6";
    crate::support::assert_usage(&solidtex(&args), &["--coarse-n 6", "odd"]);
    args[last - 3] = "--n";
    args[last - 2] = "13";
    crate::support::assert_usage(&solidtex(&args), &["--n 13", "3 to 11"]);
    args[last - 2] = "5";
    args.extend(["--cache", &fruit]);
    crate::support::assert_usage(&solidtex(&args), &["--cache", "fruit.obj", "is a file"]);
    assert!(!d.join("even.png").exists());

    let (first, second) = (at(d, "first.png"), at(d, "second.png"));
    assert!(cut(&first, true).status.success());
    let run = cut(&second, true);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(std::fs::read(&first).unwrap(), std::fs::read(&second).unwrap());
    assert_eq!(std::fs::read(&first).unwrap(), std::fs::read(&plain).unwrap(), "the cache changes nothing");
    // the coarse level and the solid cube, each kept under its key
    let names = crate::support::listing(&d.join("cache"));
    assert_eq!(names.len(), 2, "{names:?}");
    assert!(names.iter().all(|n| n.starts_with("guided-") && n.ends_with(".cache")), "{names:?}");
    assert_eq!(names.iter().filter(|n| n.starts_with("guided-cube-")).count(), 1, "{names:?}");
    for name in &names {
        let planted = d.join("cache").join(name);
        let kept = std::fs::read(&planted).unwrap();
        std::fs::write(&planted, b"my notes").unwrap();
        let third = at(d, "third.png");
        crate::support::assert_fails(&cut(&third, true), &[name, "does not overwrite"]);
        assert_eq!(std::fs::read(&planted).unwrap(), b"my notes");
        assert!(!d.join("third.png").exists());
        // solidtex's own file with a sample overwritten: rebuilt with a warning, the cut unchanged
        let mut damaged = kept.clone();
        let at = damaged.len() - 7;
        damaged[at..].fill(0);
        std::fs::write(&planted, &damaged).unwrap();
        let run = cut(&third, true);
        assert!(run.status.success(), "{}", stderr(&run));
        let warning = format!("{} is damaged (its checksum does not match its contents); rebuilt", planted.display());
        assert!(stderr(&run).contains(&warning), "{}", stderr(&run));
        assert_eq!(std::fs::read(&third).unwrap(), std::fs::read(&first).unwrap());
        assert_eq!(std::fs::read(&planted).unwrap(), kept, "the cache is written anew");
        std::fs::remove_file(&third).unwrap();
    }

    // matched as planes, an exemplar too small for a second level keeps its one level's
    // bricks: a second cut reads them all and shows the same picture
    let small = at(d, "small.png");
    assert!(solidtex(&["draw", "kiwi", "--size", "24x24", "-o", &small]).status.success());
    let args = ["guided", &fruit, "--spec", &spec, "--exemplar", &small, "--res", "32", "--cut", "0,0,0,0,0,1"];
    let cache2 = at(d, "cache2");
    let (one, two) = (at(d, "small_cut.png"), at(d, "small_again.png"));
    let run = solidtex(&[&args[..], &["--planes", "--cache", &cache2, "-o", &one]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let run = solidtex(&[&args[..], &["--planes", "--cache", &cache2, "-o", &two]].concat());
    assert!(stderr(&run).contains("voxels synthesized: 0 of"), "{}", stderr(&run));
    assert!(!stderr(&run).contains("misses the model"), "{}", stderr(&run));
    assert_eq!(std::fs::read(&one).unwrap(), std::fs::read(&two).unwrap());
    let run = solidtex(&[&args[..], &["--cache", &cache2, "-o", &at(d, "small_cube.png")]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let run = solidtex(&[&args[..], &["--cache", &cache2, "--cache-mb", "8", "-o", &at(d, "x.png")]].concat());
    crate::support::assert_usage(&run, &["--cache-mb 8", "16 to 65536"]);
}

/// With `--cache` the first cut computes the levels below the finest over the model alone
/// (not the grid's margin around it) and says so; a cut of another plane then computes only
/// the finest level: the same picture as without the cache, from fewer voxels. Under too
/// small a `--cache-mb` the command says which cap would keep them.
#[test]
fn a_cache_keeps_the_coarse_levels_over_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let folder = at(d, "cache");
    let cut = |res: &str, plane: &str, out: &str, cache: &[&str]| {
        let mut args = vec!["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64"];
        args.extend(["--res", res, "--cut", plane, "--size", "96", "-o", out]);
        args.extend(cache);
        let run = solidtex(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        let err = stderr(&run);
        let line = err.lines().find(|l| l.starts_with("voxels synthesized:")).expect("the voxel report");
        (err.clone(), line.split(' ').nth(2).and_then(|w| w.parse::<u64>().ok()).expect("a count"))
    };
    let (first, _) = cut("96", "0,0,0,0,0,1", &at(d, "a.png"), &["--cache", &folder]);
    let line = first.lines().find(|l| l.starts_with("computing the levels below the finest")).expect(&first);
    let share: f64 = line.split(' ').find_map(|w| w.parse().ok().filter(|_| line.contains(&format!("{w} %")))).unwrap();
    assert!(share < 85.0, "the coarse levels over the model only: {line}");
    let (again, cached) = cut("96", "0,0,0,1,0,0", &at(d, "b.png"), &["--cache", &folder]);
    assert!(!again.contains("computing the levels below"), "{again}");
    let (_, plain) = cut("96", "0,0,0,1,0,0", &at(d, "c.png"), &[]);
    assert_eq!(std::fs::read(at(d, "b.png")).unwrap(), std::fs::read(at(d, "c.png")).unwrap());
    assert!(3 * cached < 2 * plain, "another plane from the cache: {cached} voxels, without it {plain}");
    // a cache file past what --cache-mb reads is used by no run and left as it is; a link
    // at the file's name and a --cache that is a link to nothing are refused before any work
    let file = crate::support::listing(&d.join("cache")).into_iter().find(|n| !n.contains("cube")).unwrap();
    let file = d.join("cache").join(file);
    let mut padded = std::fs::read(&file).unwrap();
    padded.resize(16 << 20, 0);
    std::fs::write(&file, &padded).unwrap();
    let (warned, _) = cut("96", "0,0,0,1,0,0", &at(d, "f.png"), &["--cache", &folder, "--cache-mb", "16"]);
    assert!(warned.contains("more than --cache-mb 16 lets a run read; not used and kept as it is"), "{warned}");
    assert_eq!(std::fs::read(&file).unwrap(), padded);
    assert_eq!(std::fs::read(at(d, "f.png")).unwrap(), std::fs::read(at(d, "c.png")).unwrap());
    #[cfg(unix)]
    {
        std::fs::rename(&file, d.join("elsewhere")).unwrap();
        std::os::unix::fs::symlink(d.join("elsewhere"), &file).unwrap();
        let args = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "96"];
        let run = solidtex(&[&args[..], &["--cut", "0,0,0,1,0,0", "--cache", &folder, "-o", &at(d, "g.png")]].concat());
        crate::support::assert_usage(&run, &["is a link", "another --cache folder"]);
        assert!(!d.join("g.png").exists());
        std::os::unix::fs::symlink(d.join("nothing"), d.join("dangling")).unwrap();
        let run = solidtex(
            &[&args[..], &["--cut", "0,0,0,1,0,0", "--cache", &at(d, "dangling"), "-o", &at(d, "g.png")]].concat(),
        );
        crate::support::assert_usage(&run, &["--cache", "a link to nothing"]);
    }
    let small = &["--cache", &at(d, "small"), "--cache-mb", "16"];
    let (small, _) = cut("256", "0,0,0,1,0,0", &at(d, "e.png"), small);
    assert!(
        small.contains("more than a quarter of --cache-mb 16") && small.contains("a cut with --cache-mb 256"),
        "{small}"
    );
}

/// A guided model of a plain photo keeps its solid cube beside it: the first command makes
/// it and says where it kept it, the next reads it (nothing said, the same picture, as
/// `guided --cut` gives without any cache); a file of the user's at the cube's name is left
/// as it was and the cube is made again, with a warning.
#[test]
fn a_guided_model_keeps_its_solid_cube_for_the_next_command() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let (model, direct) = (at(d, "fruit.guided"), at(d, "direct.png"));
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "48"];
    assert!(solidtex(&[&base[..], &["-o", &model]].concat()).status.success());
    let run = solidtex(&[&base[..], &["--cut", "0,0,0,0,0,1", "--size", "48", "-o", &direct]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let cut = |out: &str| solidtex(&["cut", &model, "--plane", "0,0,0,0,0,1", "--size", "48", "-o", out]);
    let (first, second, third) = (at(d, "first.png"), at(d, "second.png"), at(d, "third.png"));
    let run = cut(&first);
    assert!(run.status.success(), "{}", stderr(&run));
    let names = crate::support::listing(&d.join(".solidtex-cache"));
    assert_eq!(names.len(), 1, "{names:?}");
    let cube = d.join(".solidtex-cache").join(&names[0]);
    let said = format!("kept the solid cube in {}", cube.display());
    assert!(stderr(&run).contains(&said), "{}", stderr(&run));
    let run = cut(&second);
    assert!(run.status.success() && !stderr(&run).contains("solid cube"), "{}", stderr(&run));
    for png in [&first, &second] {
        assert_eq!(std::fs::read(png).unwrap(), std::fs::read(&direct).unwrap(), "the kept cube changes nothing");
    }
    std::fs::write(&cube, b"my notes").unwrap();
    let run = cut(&third);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("warning: the solid cube was not kept"), "{}", stderr(&run));
    assert!(stderr(&run).contains("move it away") && !stderr(&run).contains("--cache"), "{}", stderr(&run));
    assert_eq!(std::fs::read(&cube).unwrap(), b"my notes");
    assert_eq!(std::fs::read(&third).unwrap(), std::fs::read(&direct).unwrap());
}

/// A photo's guided cut is as sharp as the photo: the sharpness line `guided` prints for
/// a cut (gradient and autocorrelation-length ratios against the exemplar) is within the
/// yardstick's targets through the solid cube (and the line figures are said not to apply
/// to the gravel's specks); matched as planes (`--planes`) each voxel
/// shows one of its three pixels, and the cut keeps a gradient ratio of 0.81 (the mean of
/// the three gave 0.64 on the gravel at a larger size: soft).
#[test]
fn a_guided_cut_of_a_photo_is_as_sharp_as_the_photo() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let ratios = |extra: &[&str]| -> (f64, f64) {
        let out = at(d, "cut.png");
        let args = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "64"];
        let run = solidtex(&[&args[..], &["--cut", "0,0,0,0,0,1", "--size", "64", "-o", &out], extra].concat());
        assert!(run.status.success(), "{}", stderr(&run));
        let err = stderr(&run);
        let line = err.lines().find(|l| l.starts_with("sharpness against the exemplar:")).expect("the sharpness line");
        // the gravel's thin lines are specks, so the line figures are said not to apply
        let lines = "line structure: the exemplar's light lines form no long pieces (top-3 share 0.06, under 0.3)";
        assert!(err.contains(lines), "{err}");
        let numbers: Vec<f64> = line.split([' ', ',']).filter_map(|w| w.parse().ok()).collect();
        (numbers[0], numbers[1])
    };
    let (gradient, length) = ratios(&[]);
    assert!((0.8..=1.2).contains(&gradient) && (0.7..=1.3).contains(&length), "{gradient} {length}");
    let (planes, _) = ratios(&["--planes"]);
    assert!(planes >= 0.78, "as planes: gradient ratio {planes}");
}

/// `--solid` reads a volume along the field as it is: every pixel of the cut inside the
/// fruit has a colour of the volume; a volume that is not a cube halving evenly is refused
/// by name, and `--solid --layered` with a volume without a Depth channel as a usage error
/// naming the volume and what it has.
#[test]
fn a_solid_exemplar_is_read_along_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let marble = at(d, "marble.exr");
    assert!(solidtex(&["make", "marble", "--size", "32", "-o", &marble]).status.success());
    let out = at(d, "cut.png");
    let base = ["guided", &fruit, "--spec", &spec, "--res", "48", "--cut", "0,0,0,0,1,0", "--size", "48"];
    let run = solidtex(&[&base[..], &["--solid", &marble, "-o", &out]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let volume = solidtex::io::read_volume(std::path::Path::new(&marble), 1 << 30).unwrap();
    let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let colours: std::collections::HashSet<[u8; 3]> =
        volume.data().chunks_exact(volume.channel_count()).map(|p| [byte(p[0]), byte(p[1]), byte(p[2])]).collect();
    let img = image::open(&out).unwrap().to_rgb8();
    let inside: Vec<[u8; 3]> = img.pixels().map(|p| p.0).filter(|p| *p != BACKGROUND).collect();
    assert!(inside.len() > 500, "{} pixels inside", inside.len());
    let foreign = inside.iter().filter(|c| !colours.contains(*c)).count();
    assert_eq!(foreign, 0, "{foreign} of {} pixels show a colour the volume lacks", inside.len());

    let flat = at(d, "flat.exr");
    assert!(solidtex(&["make", "marble", "--size", "32x32x24", "-o", &flat]).status.success());
    let refused = at(d, "refused.png");
    let run = solidtex(&[&base[..], &["--solid", &flat, "-o", &refused]].concat());
    crate::support::assert_fails(&run, &["flat.exr", "cube", "32x32x24"]);
    let deep = ["--solid", &marble, "--layered", "-o", &refused];
    let run = solidtex(&[&base[..2], &base[2..4], &["--res", "96"], &base[6..], &deep].concat());
    crate::support::assert_usage(&run, &["marble.exr", "--layered with --solid", "Depth channel", "R, G, B"]);
    assert!(!d.join("refused.png").exists());
}

/// A built cross-section (the library's trunk: rings, heartwood and bark, with its Depth)
/// is followed as layered exemplars with `--solid --layered`; the cut's outline is the
/// log's round cross-section (the surface's, as the lapped fill's), not the tets' polygon.
#[test]
fn a_built_cross_section_is_followed_in_layers_inside_the_surfaces_outline() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::fill::filled(d, "log", "trunk", crate::fill::TRUNK);
    let (log, trunk, built) = (at(d, "log.obj"), at(d, "trunk.toml"), at(d, "built/trunk.exr"));
    // without --layered, a section is no solid cube: the message says what to add
    let refused = at(d, "refused.png");
    let flat = ["guided", &log, "--spec", &trunk, "--solid", &built, "--res", "64", "-o", &refused];
    crate::support::assert_fails(&solidtex(&flat), &["trunk.exr", "Depth", "add --layered"]);
    assert!(!d.join("refused.png").exists());
    let out = at(d, "across.png");
    let args = ["guided", &log, "--spec", &trunk, "--solid", &built, "--layered", "--res", "256"];
    let run = solidtex(&[&args[..], &["--cut", "0,0,1,0,0,1", "--size", "128", "-o", &out]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&out).unwrap().to_rgba8();
    // the log's radius is 0.5 of the cut's 1.04 units: a disc of 61.5 px radius
    let (inside, radius) = (img.pixels().filter(|p| shown(p)).count() as f64, 0.5 * 128.0 / 1.04);
    let disc = std::f64::consts::PI * radius * radius;
    assert!((inside / disc - 1.0).abs() < 0.02, "{inside} pixels inside, a disc holds {disc:.0}");
    let reds: Vec<u8> = img.pixels().filter(|p| shown(p)).map(|p| p.0[0]).collect();
    let (lo, hi) = (reds.iter().min().unwrap(), reds.iter().max().unwrap());
    assert!(hi - lo > 40, "rings and heartwood: red {lo} to {hi}");
    // the bark, the section's outermost 3 % of depth (two voxels at this resolution),
    // rims the cut: dark on most of the outer band (past 0.95 of the radius) against the
    // wood between 0.5 and 0.9
    let luminance = |p: &image::Rgba<u8>| 0.3 * p.0[0] as f64 + 0.59 * p.0[1] as f64 + 0.11 * p.0[2] as f64;
    let band = |lo: f64, hi: f64| -> Vec<f64> {
        img.enumerate_pixels()
            .filter(|(x, y, p)| {
                let r = (*x as f64 - 63.5).hypot(*y as f64 - 63.5) / radius;
                shown(p) && r > lo && r <= hi
            })
            .map(|(_, _, p)| luminance(p))
            .collect()
    };
    let wood = band(0.5, 0.9).iter().sum::<f64>() / band(0.5, 0.9).len() as f64;
    let rim = band(0.95, 1.1);
    let dark = rim.iter().filter(|l| **l < 0.6 * wood).count() as f64 / rim.len() as f64;
    assert!(dark >= 0.4, "the bark rims {:.0} % of the outer band", dark * 100.0);
}

/// Without `--cut`, the whole solid is written: the exemplar's channels (one: the photo is
/// grey) and the fruit's coverage as alpha. Bad values, and a solid larger than the memory
/// budget, are refused by name before any work.
#[test]
fn a_whole_guided_solid_carries_the_model_as_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let out = at(d, "solid.exr");
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64"];
    let run = solidtex(&[&base[..], &["--res", "24", "-o", &out]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let volume = solidtex::io::read_volume(std::path::Path::new(&out), 1 << 30).unwrap();
    let names: Vec<String> = volume.channels().iter().map(|c| c.to_string()).collect();
    assert_eq!(names, ["R", "A"], "the grey photo's channel, then alpha");
    let [x, y, z] = volume.dims();
    assert_eq!(volume.voxel(x / 2, y / 2, z / 2)[1], 1.0, "the fruit's centre is inside");
    assert_eq!(volume.voxel(0, 0, 0)[1], 0.0, "the grid's corner is outside");

    crate::support::assert_usage(&solidtex(&[&base[..], &["--res", "8", "-o", &out]].concat()), &["--res", "16"]);
    let big = at(d, "big.exr");
    let run = crate::support::solidtex_env(
        &[&base[..], &["--res", "256", "-o", &big]].concat(),
        &[("SOLIDTEX_MAX_BYTES", "100000000")],
    );
    crate::support::assert_fails(&run, &["--res 256", "budget", "SOLIDTEX_MAX_BYTES"]);
    assert!(!d.join("big.exr").exists());
    let bare = crate::fill::spec(d, "bare.toml", "exemplar = \"kiwi\"\n");
    let run = solidtex(&["guided", &fruit, "--spec", &bare, "--exemplar", &ex, "-o", &at(d, "bare.exr")]);
    crate::support::assert_fails(&run, &["bare.toml", "direction stroke"]);
    assert!(!d.join("bare.exr").exists());
}

/// A guided solid is written as a lapped fill's bake is: every channel 0 outside the model
/// (alpha 0), the texture inside, and its place in model space recorded (its grid's box
/// holds the fruit's). A guided cut leaves `solidtex cut`'s background outside the fruit,
/// not black or transparent.
#[test]
fn a_guided_bake_is_empty_outside_the_model_and_its_cut_shows_the_cut_background() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let (model, baked) = (at(d, "fruit.guided"), at(d, "baked.exr"));
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "24"];
    assert!(solidtex(&[&base[..], &["-o", &model]].concat()).status.success());
    let run = solidtex(&["bake", &model, "-o", &baked]);
    assert!(run.status.success(), "{}", stderr(&run));
    let volume = solidtex::io::read_volume(std::path::Path::new(&baked), 1 << 30).unwrap();
    let (mut outside, mut textured) = (0, 0);
    for voxel in volume.data().chunks_exact(volume.channel_count()) {
        if voxel.last() == Some(&0.0) {
            assert!(voxel.iter().all(|v| *v == 0.0), "a voxel outside the fruit holds {voxel:?}");
            outside += 1;
        } else {
            textured += usize::from(voxel[0] > 0.0);
        }
    }
    assert!(outside > 1000 && textured > 1000, "{outside} voxels outside, {textured} textured inside");
    let info: serde_json::Value = serde_json::from_slice(&solidtex(&["info", &baked, "--json"]).stdout).unwrap();
    let corner = |key: &str, a: usize| info["model_grid"][key][a].as_f64().map(|v| v as f32);
    let (lo, hi) = solidtex::io::mesh_file::read_mesh(std::path::Path::new(&fruit)).unwrap().bounds();
    let holds = (0..3)
        .all(|a| corner("box_min", a).is_some_and(|v| v < lo[a]) && corner("box_max", a).is_some_and(|v| v > hi[a]));
    assert!(holds, "the bake's box {} holds the fruit's, {lo} to {hi}", info["model_grid"]);

    let cut = at(d, "cut.png");
    let run = solidtex(&["cut", &model, "--plane", "0,0,0,0,0,1", "--size", "48", "-o", &cut]);
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&cut).unwrap().to_rgba8();
    assert_eq!(img.get_pixel(0, 0).0, [24, 24, 28, 255], "outside the fruit");
    assert!(shown(img.get_pixel(24, 24)), "the fruit's centre shows its texture");
}

/// `--mask` adds a feature mask to the exemplar: matched (the cut changes), not shown (the
/// solid keeps the photo's channel and alpha). A mask of another size, and `--ey` without
/// its `--ey-mask`, are refused by name, with nothing written.
#[test]
fn a_feature_mask_steers_the_match_and_is_not_shown() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let photo = image::open(&ex).unwrap().to_luma8();
    let mask = image::GrayImage::from_fn(photo.width(), photo.height(), |x, y| {
        image::Luma([if photo.get_pixel(x, y).0[0] > 110 { 255 } else { 0 }])
    });
    let mask_path = at(d, "mask.png");
    mask.save(&mask_path).unwrap();
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64"];
    let cut = ["--res", "48", "--cut", "0,0,0,0,0,1", "--size", "48"];
    let (plain, masked) = (at(d, "plain.png"), at(d, "masked.png"));
    assert!(solidtex(&[&base[..], &cut, &["-o", &plain]].concat()).status.success());
    let run = solidtex(&[&base[..], &cut, &["--mask", &mask_path, "-o", &masked]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert_ne!(std::fs::read(&plain).unwrap(), std::fs::read(&masked).unwrap(), "the mask is matched");

    let solid = at(d, "solid.exr");
    let run = solidtex(&[&base[..], &["--res", "24", "--mask", &mask_path, "-o", &solid]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let volume = solidtex::io::read_volume(std::path::Path::new(&solid), 1 << 30).unwrap();
    let names: Vec<String> = volume.channels().iter().map(|c| c.to_string()).collect();
    assert_eq!(names, ["R", "A"], "the mask is not a channel of the solid");

    let small = at(d, "small.png");
    image::GrayImage::new(10, 10).save(&small).unwrap();
    let out = at(d, "refused.png");
    let run = solidtex(&[&base[..], &cut, &["--mask", &small, "-o", &out]].concat());
    crate::support::assert_fails(&run, &["small.png", "10x10", "64x64", "gravel_photo.png"]);
    let run = solidtex(&[&base[..], &cut, &["--mask", &mask_path, "--ey", &ex, "-o", &out]].concat());
    crate::support::assert_usage(&run, &["--ey", "--ey-mask"]);
    assert!(!d.join("refused.png").exists());
}

/// `--layered` scales the exemplar so that its rows span the model's depth in voxels (and
/// says so; the section turned a quarter is warned about), and the kiwi section's pale core, its innermost rows, fills the middle of a
/// cut across the fruit's axis. A resolution too low for one row per voxel is refused by
/// name with the one that would do, with nothing written.
#[test]
fn a_layered_cut_shows_the_innermost_rows_at_the_axis() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let kiwi = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/kiwi_section.png");
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", kiwi, "--layered", "--cut", "0,0,0,1,0,0"];
    let png = at(d, "across.png");
    let run = solidtex(&[&base[..], &["--res", "128", "--size", "64", "-o", &png]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("kiwi_section.png scaled from 64x64 to"), "{}", stderr(&run));
    assert!(!stderr(&run).contains("warning"), "its rows are its layers: {}", stderr(&run));
    let turned = at(d, "turned.png");
    image::open(kiwi).unwrap().rotate90().save(&turned).unwrap();
    let args = ["guided", &fruit, "--spec", &spec, "--exemplar", &turned, "--layered", "--cut", "0,0,0,1,0,0"];
    let run = solidtex(&[&args[..], &["--res", "64", "--size", "16", "-o", &at(d, "turned_cut.png")]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("turned.png: its layers run down the columns"), "{}", stderr(&run));
    let img = image::open(&png).unwrap().to_rgb8();
    let pale = (30..34).flat_map(|y| (30..34).map(move |x| (x, y))).filter(|&(x, y)| {
        let [r, g, b] = img.get_pixel(x, y).0;
        r > 200 && g > 200 && b > 160
    });
    assert!(pale.count() >= 14, "the middle 4x4 pixels are mostly the pale core");
    let [r, g, _] = img.get_pixel(32, 8).0;
    assert!(g > r + 30, "green flesh between the core and the skin: {:?}", img.get_pixel(32, 8).0);
    // a section of fewer rows than the depth spans is magnified at the finest level: said,
    // and its core lands at the axis
    let small = at(d, "small.png");
    image::open(kiwi).unwrap().resize_exact(24, 24, image::imageops::FilterType::Triangle).save(&small).unwrap();
    let args = ["guided", &fruit, "--spec", &spec, "--exemplar", &small, "--layered", "--cut", "0,0,0,1,0,0"];
    let magnified = at(d, "magnified.png");
    let run = solidtex(&[&args[..], &["--res", "256", "--size", "64", "-o", &magnified]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("the finest 1 of 2 levels magnify the level below"), "{}", stderr(&run));
    let img = image::open(&magnified).unwrap().to_rgb8();
    let [r, g, b] = img.get_pixel(32, 32).0;
    assert!(r > 180 && g > 180 && b > 140, "the pale core at the axis: {:?}", [r, g, b]);

    let low = at(d, "low.png");
    crate::support::assert_fails(
        &solidtex(&[&base[..], &["--res", "32", "-o", &low]].concat()),
        &["fruit.obj: --res 32:", "resolution 32", "raise the resolution to"],
    );
    assert!(!d.join("low.png").exists());
}

/// A spec's `[[region]]` entries texture the log by depth: a red exemplar outside (depth
/// 0 to 0.3), a blue one inside, blended across a band of 0.1. On a cut across the log,
/// red holds at least 90 % of the outer band's pixels (past 0.85 of the radius) and at
/// most 5 % of the inner region's (within half the radius). Given with `--exemplar`, the
/// spec's regions are a usage error naming the flag.
#[test]
fn regions_give_the_log_one_exemplar_outside_and_another_inside() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("built")).unwrap();
    let mut manifest = String::new();
    for (seed, name) in [(1, "red"), (2, "blue")] {
        let noise = crate::support::random_volume([32, 32, 32], solidtex::Channel::rgb(), seed);
        let hue = |k: usize, v: f32| if (k == 0) == (name == "red") && k != 1 { 0.6 + 0.4 * v } else { 0.2 * v };
        let data = noise.data().chunks_exact(3).flat_map(|p| (0..3).map(move |k| hue(k, p[k]))).collect();
        let volume = solidtex::Volume::from_data([32; 3], solidtex::Channel::rgb(), data).unwrap();
        solidtex::io::write_volume(&d.join(format!("built/{name}.exr")), &volume).unwrap();
        manifest += &format!("[[exemplar]]\nname = \"{name}\"\nrecipe = \"procedural:marble\"\nsize = 32\n\n");
    }
    std::fs::write(d.join("library.toml"), manifest).unwrap();
    let log = crate::fill::draw(d, "log");
    let regions =
        "[[region]]\nexemplar = \"red\"\ndepth = [0, 0.3]\n[[region]]\nexemplar = \"blue\"\ndepth = [0.3, 1]\n";
    let body =
        crate::fill::TRUNK.replacen("exemplar = \"trunk\"", "exemplar = \"red\"\nregion_band = 0.1", 1) + regions;
    let spec = at(d, "regions.toml");
    std::fs::write(&spec, format!("library = \"library.toml\"\nbuilt = \"built\"\n{body}")).unwrap();
    let out = at(d, "across.png");
    let args = ["guided", &log, "--spec", &spec, "--res", "128", "--cut", "0,0,1,0,0,1", "--size", "128", "-o", &out];
    let run = solidtex(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&out).unwrap().to_rgba8();
    let radius = 0.5 * 128.0 / 1.04;
    let red_share = |lo: f64, hi: f64| {
        let ring: Vec<bool> = img
            .enumerate_pixels()
            .filter(|(x, y, p)| {
                let r = (*x as f64 - 63.5).hypot(*y as f64 - 63.5) / radius;
                shown(p) && r > lo && r <= hi
            })
            .map(|(_, _, p)| p.0[0] > p.0[2])
            .collect();
        assert!(ring.len() > 300, "{} pixels between {lo} and {hi} of the radius", ring.len());
        ring.iter().filter(|red| **red).count() as f64 / ring.len() as f64
    };
    let (outer, inner) = (red_share(0.85, 1.1), red_share(0.0, 0.5));
    assert!(
        outer >= 0.9 && inner <= 0.05,
        "red: {:.1} % of the outer band, {:.1} % inside",
        outer * 100.0,
        inner * 100.0
    );

    let photo = at(d, "photo.png");
    image::RgbImage::from_pixel(32, 32, image::Rgb([90, 90, 90])).save(&photo).unwrap();
    let refused = at(d, "refused.png");
    let run = solidtex(&[&args[..10], &["--exemplar", &photo, "-o", &refused]].concat());
    crate::support::assert_usage(&run, &["--exemplar", "regions.toml", "[[region]]"]);
    // each region keeps its exemplar's neighbourhoods: another size is refused by name
    let run = solidtex(&[&args[..10], &["--n", "7", "-o", &refused]].concat());
    crate::support::assert_usage(&run, &["--n 7", "regions.toml", "[[region]]"]);
    assert!(!d.join("refused.png").exists());

    // a region's built volume is an input: neither the solid nor a guided model's bake
    // writes over it
    let blue = d.join("built/blue.exr");
    let before = std::fs::read(&blue).unwrap();
    let model = at(d, "regions.guided");
    assert!(solidtex(&[&args[..6], &["-o", &model]].concat()).status.success());
    let blue = blue.to_string_lossy();
    crate::support::assert_usage(&solidtex(&[&args[..6], &["-o", &blue]].concat()), &["blue.exr", "input"]);
    crate::support::assert_usage(&solidtex(&["bake", &model, "-o", &blue]), &["blue.exr", "input"]);
    assert_eq!(std::fs::read(d.join("built/blue.exr")).unwrap(), before);
}

/// A spec's `[[scale_at]]` points scale the texture: on a block whose left end asks for
/// the photo at one pixel per voxel (three points) and whose right end for half that, the right end's
/// features are half as long (autocorrelation length) within 20 %. With `--solid` the
/// scale field is a usage error naming the spec.
#[test]
fn a_scale_field_halves_the_texture_where_it_asks_for_half() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let block = crate::fill::draw(d, "block");
    // the grid is 128 voxels over the block's 2 units and a 5 % margin each side: an
    // exemplar of 128 pixels spans 2.2 units at one pixel per voxel
    let spec = crate::fill::spec(
        d,
        "scaled.toml",
        &["exemplar = \"gravel\"\ntets = 3000\n[[direction]]\npoints = [[-0.9, 0, 0], [0.9, 0, 0]]\n".to_string()]
            .into_iter()
            .chain([-0.9f32, -0.7, -0.5, 0.5, 0.7, 0.9].map(|x| {
                let scale = if x < 0.0 { 2.2 } else { 1.1 };
                format!("[[scale_at]]\npoint = [{x}, 0, 0]\nscale = {scale}\n")
            }))
            .collect::<String>(),
    );
    let photo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars/gravel_photo.png");
    let photo = photo.to_string_lossy();
    let out = at(d, "scaled.png");
    let args = ["guided", &block, "--spec", &spec, "--exemplar", &photo, "--res", "128", "--cut", "0,0,0,0,0,1"];
    let run = solidtex(&[&args[..], &["--size", "128", "-o", &out]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&out).unwrap().to_rgba8();
    let rows: Vec<u32> = (0..img.height()).filter(|&y| shown(img.get_pixel(64, y))).collect();
    let crop = |from: f32, to: f32| {
        let (x0, x1) = ((from * 128.0) as u32, (to * 128.0) as u32);
        let data: Vec<f32> = rows
            .iter()
            .flat_map(|&y| (x0..x1).map(move |x| (x, y)))
            .map(|(x, y)| img.get_pixel(x, y).0[0] as f32 / 255.0)
            .collect();
        solidtex::volume::Image2d::from_data((x1 - x0) as usize, rows.len(), solidtex::Channel::grey(), data).unwrap()
    };
    let exemplar = solidtex::io::read_image_fit(std::path::Path::new(&*photo), Some(128)).unwrap();
    let length = |image| solidtex::sharpness::compare(&[image], &exemplar, &[0]).unwrap().length_ratio;
    let (left, right) = (length(crop(0.05, 0.3)), length(crop(0.7, 0.95)));
    assert!((0.4..=0.6).contains(&(right / left)), "feature length {left:.2} at the left end, {right:.2} at the right");

    let refused = at(d, "refused.png");
    let marble = at(d, "marble.exr");
    assert!(solidtex(&["make", "marble", "--size", "32", "-o", &marble]).status.success());
    let run = solidtex(&["guided", &block, "--spec", &spec, "--solid", &marble, "--res", "64", "-o", &refused]);
    crate::support::assert_usage(&run, &["scaled.toml", "[[scale_at]]", "--solid"]);
    assert!(!d.join("refused.png").exists());

    // a scale that would grow the exemplar past what synthesis can hold is refused before
    // anything is allocated (it took all the memory, or aborted)
    for huge in ["1000", "1e30"] {
        let body = format!(
            "{}[[scale_at]]\npoint = [0, 0, 0]\nscale = {huge}\n",
            "exemplar = \"gravel\"\ntets = 3000\n[[direction]]\npoints = [[-0.9, 0, 0], [0.9, 0, 0]]\n"
        );
        let spec = crate::fill::spec(d, "huge.toml", &body);
        let run = solidtex(&["guided", &block, "--spec", &spec, "--exemplar", &photo, "--res", "64", "-o", &refused]);
        assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
        assert!(stderr(&run).contains("[[scale_at]] scales grow the 128x128 exemplar"), "{}", stderr(&run));
        assert!(!d.join("refused.png").exists());
    }
}

/// `guided -o X.guided` writes the recipe, not voxels: `cut X.guided` equals `guided --cut`
/// of the same plane byte for byte, `bake X.guided` equals the whole solid `guided` writes,
/// and `view X.guided` shows the fruit's surface in the photo's greys (shaded), the same on
/// one thread and two, synthesizing a small share of the solid; `render` draws its whole
/// solid. View options for filled models are refused by name, as is a guided model
/// combined with another.
#[test]
fn a_guided_model_is_viewed_cut_and_baked_on_demand() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let model = at(d, "fruit.guided");
    let base =
        ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--planes", "--res", "96"];
    let run = solidtex(&[&base[..], &["-o", &model]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let text = std::fs::read_to_string(&model).unwrap();
    assert!(text.contains("res = 96") && text.contains("mesh = \"fruit.obj\""), "{text}");

    let (direct, from_model) = (at(d, "direct.png"), at(d, "model.png"));
    let run = solidtex(&[&base[..], &["--cut", "0,0,0,0,1,0", "--size", "64", "-o", &direct]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let run = solidtex(&["cut", &model, "--plane", "0,0,0,0,1,0", "--size", "64", "-o", &from_model]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(std::fs::read(&direct).unwrap(), std::fs::read(&from_model).unwrap(), "the same cut");
    let (solid, baked) = (at(d, "solid.exr"), at(d, "baked.exr"));
    assert!(solidtex(&[&base[..], &["-o", &solid]].concat()).status.success());
    let run = solidtex(&["bake", &model, "-o", &baked]);
    assert!(run.status.success(), "{}", stderr(&run));
    let read = |p: &str| solidtex::io::read_volume(std::path::Path::new(p), 1 << 30).unwrap();
    assert_eq!(read(&solid).data(), read(&baked).data(), "the same solid");
    let other = at(d, "other.exr");
    crate::support::assert_usage(&solidtex(&["bake", &model, "--res", "32", "-o", &other]), &["--res", "fruit.guided"]);
    assert!(!d.join("other.exr").exists());

    let views: Vec<Vec<u8>> = ["1", "2"]
        .iter()
        .map(|threads| {
            let png = at(d, &format!("view{threads}.png"));
            let run = crate::support::solidtex_env(
                &["view", &model, "--size", "128", "-o", &png],
                &[("RAYON_NUM_THREADS", threads)],
            );
            assert!(run.status.success(), "{}", stderr(&run));
            let said = stderr(&run);
            let share: f64 = said
                .split(" a whole solid needs over all its pyramid levels (")
                .nth(1)
                .and_then(|t| t.split(' ').next())
                .unwrap()
                .parse()
                .unwrap();
            assert!(share < 50.0, "{said}");
            std::fs::read(&png).unwrap()
        })
        .collect();
    assert_eq!(views[0], views[1], "the same view on one thread and two");
    let img = image::load_from_memory(&views[0]).unwrap().to_rgb8();
    let background = *img.get_pixel(0, 0);
    let surface: Vec<&image::Rgb<u8>> = img.pixels().filter(|p| **p != background).collect();
    assert!(surface.len() > 128 * 128 / 4, "{} pixels show the fruit", surface.len());
    let grey = surface.iter().filter(|p| p.0[0] == p.0[1] && p.0[1] == p.0[2]).count();
    assert_eq!(grey, surface.len(), "the grey photo's colours, lit");
    let distinct: std::collections::HashSet<u8> = surface.iter().map(|p| p.0[0]).collect();
    assert!(distinct.len() > 40, "textured, not flat: {} greys", distinct.len());

    // render synthesizes the whole solid and draws it through the field's tets
    let small = at(d, "small.guided");
    assert!(solidtex(&[&base[..9], &["--res", "32", "-o", &small]].concat()).status.success());
    let glass = at(d, "glass.png");
    let run = solidtex(&["render", &small, "--size", "64", "--opacity", "0.9", "-o", &glass]);
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&glass).unwrap().to_rgb8();
    let shown = img.pixels().filter(|p| p.0 != img.get_pixel(0, 0).0).count();
    assert!(shown > 64 * 64 / 5, "{shown} pixels show the fruit");

    let refused = at(d, "refused.png");
    // a model file's settings out of range are errors in the file, named as it names them
    for (line, says) in [("res = 100000", "res = 100000 is out of range"), ("n = 4", "n = 4 must be odd")] {
        let bad = at(d, "bad.guided");
        let field = line.split(' ').next().unwrap();
        let edited: Vec<String> = text
            .lines()
            .map(|l| if l.starts_with(&format!("{field} =")) { line.to_string() } else { l.to_string() })
            .collect();
        std::fs::write(&bad, edited.join("\n")).unwrap();
        crate::support::assert_fails(&solidtex(&["view", &bad, "-o", &refused]), &["bad.guided", says]);
    }
    let bad = at(d, "bad.guided");
    let without: Vec<&str> = text.lines().filter(|l| !l.starts_with("exemplar =")).collect();
    std::fs::write(&bad, without.join("\n")).unwrap();
    let run = solidtex(&["cut", &bad, "-o", &refused]);
    crate::support::assert_fails(&run, &["bad.guided", "neither exemplar nor solid"]);
    let run = solidtex(&["view", &model, "--displacement", "0.1", "-o", &refused]);
    crate::support::assert_usage(&run, &["--displacement", "fruit.guided"]);
    crate::support::assert_usage(&solidtex(&["view", &model, &model, "-o", &refused]), &["fruit.guided", "alone"]);
    let run = solidtex(&[&base[..], &["--cut", "0,0,0,0,1,0", "-o", &at(d, "cut.guided")]].concat());
    crate::support::assert_usage(&run, &["cut.guided", "--cut writes a PNG"]);
    assert!(!d.join("refused.png").exists() && !d.join("cut.guided").exists());
}

/// A guided model's commands never write over the model's own inputs: `view`, `cut` and
/// `render` naming the model's exemplar photo as their picture are usage errors naming it,
/// and the photo stays as it was; so is `guided -o` naming its spec.
#[test]
fn a_guided_model_never_writes_over_its_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let photo = at(d, "photo.png");
    std::fs::copy(gravel(), &photo).unwrap();
    let model = at(d, "fruit.guided");
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &photo, "--max-exemplar", "64", "--planes"];
    let run = solidtex(&[&base[..], &["--res", "32", "-o", &model]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let before = std::fs::read(&photo).unwrap();
    for command in ["view", "cut", "render"] {
        let run = solidtex(&[command, &model, "--size", "32", "-o", &photo]);
        crate::support::assert_usage(&run, &["photo.png", "input"]);
        assert_eq!(std::fs::read(&photo).unwrap(), before, "{command} left the photo as it was");
    }
    let spec_before = std::fs::read(&spec).unwrap();
    let run = solidtex(&[&base[..], &["--res", "32", "-o", &spec]].concat());
    crate::support::assert_usage(&run, &[".toml"]);
    assert_eq!(std::fs::read(&spec).unwrap(), spec_before);
}

/// A guided model written with an exemplar whose name holds a backslash (part of a name on
/// Unix) names it as it is, so the model reads back.
#[cfg(unix)]
#[test]
fn a_guided_model_keeps_a_backslash_in_a_file_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let odd = at(d, "we\"ird \\ name.png");
    std::fs::copy(gravel(), &odd).unwrap();
    let model = at(d, "w.guided");
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &odd, "--max-exemplar", "64", "--res", "24"];
    let run = solidtex(&[&base[..], &["-o", &model]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let run = solidtex(&["cut", &model, "--size", "32", "-o", &at(d, "w.png")]);
    assert!(run.status.success(), "{}", stderr(&run));
}

/// A skin that cannot be read, or was grown on another mesh, stops `render` of a guided
/// model before anything of the model is synthesized; `web` and `export` refuse a guided
/// model and say to bake it first.
#[test]
fn a_guided_model_is_checked_before_synthesis_and_refused_where_not_taken() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = at(d, "gravel.png");
    std::fs::copy(gravel(), &ex).unwrap();
    let model = at(d, "g.guided");
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "24"];
    assert!(solidtex(&[&base[..], &["-o", &model]].concat()).status.success());
    let (log, skin) = (at(d, "log.obj"), at(d, "log.ply"));
    assert!(solidtex(&["draw", "log", "-o", &log]).status.success());
    let grown = solidtex(&["surface", &log, "--exemplar", &ex, "--points", "500", "-o", &skin]);
    assert!(grown.status.success(), "{}", stderr(&grown));
    let run = solidtex(&["render", &model, "--skin", &skin, "-o", &at(d, "r.png")]);
    crate::support::assert_fails(&run, &["log.ply", "the skin spans"]);
    assert!(!stderr(&run).contains("synthesized"), "the skin is checked first: {}", stderr(&run));
    // with its exemplar gone the model cannot be synthesized: the missing skin is named first
    std::fs::remove_file(&ex).unwrap();
    let run = solidtex(&["render", &model, "--skin", &at(d, "missing.ply"), "-o", &at(d, "r.png")]);
    crate::support::assert_fails(&run, &["missing.ply"]);
    for (command, out) in [("web", "w.html"), ("export", "w.glb")] {
        let run = solidtex(&[command, &model, "-o", &at(d, out)]);
        crate::support::assert_usage(&run, &["g.guided", "does not take guided models", "solidtex bake"]);
        assert!(!d.join(out).exists());
    }
}

/// An output that is or lies in the folder where a guided model's solid cube is kept
/// (beside the model, or `--cache`) is refused before any synthesis: nothing is written
/// there, not even the cube.
#[test]
fn an_output_in_the_cube_folder_is_refused_before_synthesis() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let ex = gravel();
    let model = at(d, "fruit.guided");
    let base = ["guided", &fruit, "--spec", &spec, "--exemplar", &ex, "--max-exemplar", "64", "--res", "24"];
    assert!(solidtex(&[&base[..], &["-o", &model]].concat()).status.success());
    let cache = d.join(".solidtex-cache");
    if cache.exists() {
        std::fs::remove_dir_all(&cache).unwrap();
    }
    let output = at(d, ".solidtex-cache");
    let run = solidtex(&["bake", &model, "-o", &output]);
    crate::support::assert_fails(&run, &[&output, "solid cube"]);
    assert!(!stderr(&run).contains("kept the solid cube"), "{}", stderr(&run));
    assert!(!cache.exists(), "{}", stderr(&run));
    let (mine, cut) = (at(d, "mine"), at(d, "mine/cut.png"));
    std::fs::create_dir(&mine).unwrap();
    let run = solidtex(&[&base[..], &["--cache", &mine, "--cut", "0,0,0,1,0,0", "-o", &cut]].concat());
    crate::support::assert_fails(&run, &[&cut, "is inside", "solid cube"]);
    assert!(crate::support::listing(&d.join("mine")).is_empty(), "{}", stderr(&run));
}
