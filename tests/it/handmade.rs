//! Hand-made exemplars: stamping, scattering, blurring, sweeping from the command line,
//! and the default library's kiwi, carrot and trunk.

use crate::support::{assert_fails, assert_usage, at, listing, solidtex, stderr};
use glam::{Quat, Vec3};
use solidtex::io::read_volume;
use solidtex::sections::seed_mesh;
use solidtex::stamp::{Placement, Region, Scatter, blur, bounding_capsule, scatter, stamp};
use solidtex::volume::{Channel, Volume};

fn grey_cube(side: usize) -> Volume {
    Volume::from_fn([side; 3], Channel::rgb(), |_, _, _, o| o.fill(0.5)).unwrap()
}

#[test]
fn stamping_blends_the_colour_by_coverage() {
    let mesh = seed_mesh(16, 16).unwrap();
    let mut v = grey_cube(32);
    let placement = Placement { at: Vec3::splat(16.0), rotation: Quat::IDENTITY, scale: Vec3::splat(6.0) };
    let done = stamp(&mut v, &mesh, &placement, [0.0, 0.0, 0.0]).unwrap();
    assert_eq!(v.voxel(16, 16, 16), &[0.0, 0.0, 0.0], "the centre is fully inside");
    assert_eq!(v.voxel(1, 1, 1), &[0.5, 0.5, 0.5], "far away is untouched");
    let edge = (0..32).map(|z| v.get(16, 16, z, 0)).filter(|c| *c > 0.0 && *c < 0.5).count();
    assert!(edge >= 1, "the boundary is anti-aliased");
    assert!(done.volume > 100.0 && (done.voxels as f64) >= done.volume);
    let outside = Placement { at: Vec3::splat(500.0), ..placement };
    let err = stamp(&mut v, &mesh, &outside, [1.0; 3]).unwrap_err().to_string();
    assert!(err.contains("wholly outside") && err.contains("32x32x32"), "{err}");
}

/// Black seeds scattered anywhere in a cube of `side` voxels, 200 tries each.
fn in_cube(count: usize, side: f32, scale: (f32, f32)) -> Scatter {
    Scatter { count, region: Region::Box(Vec3::ZERO, Vec3::splat(side)), scale, colour: [0.0; 3], attempts: 200 }
}

#[test]
fn scatter_never_overlaps_and_replays_from_its_seed() {
    let mesh = seed_mesh(12, 12).unwrap();
    let params = in_cube(25, 48.0, (2.0, 3.0));
    let (mut a, mut b) = (grey_cube(48), grey_cube(48));
    let first = scatter(&mut a, &mesh, &params, 11).unwrap();
    let second = scatter(&mut b, &mesh, &params, 11).unwrap();
    assert_eq!(first, second);
    assert_eq!(a, b);
    assert_eq!(first.placed.len(), 25);
    let capsules: Vec<_> = first.placed.iter().map(|p| bounding_capsule(&mesh).placed(p)).collect();
    for (i, c) in capsules.iter().enumerate() {
        for end in [c.a, c.b] {
            assert!((0..3).all(|k| end[k] - c.radius >= 0.0 && end[k] + c.radius <= 48.0), "seed {i} pokes out");
        }
        for d in &capsules[i + 1..] {
            assert!(sampled_distance(c.a, c.b, d.a, d.b) >= c.radius + d.radius - 1e-2, "seeds overlap");
        }
    }
    for v in &mesh.vertices {
        let capsule = bounding_capsule(&mesh);
        assert!(sampled_distance(*v, *v, capsule.a, capsule.b) <= capsule.radius + 1e-4, "the capsule holds the mesh");
    }
    let mut c = grey_cube(48);
    assert_ne!(scatter(&mut c, &mesh, &params, 12).unwrap(), first);
}

/// The distance of two segments, from 200 points along each (a check independent of the
/// closed form scatter uses).
fn sampled_distance(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f32 {
    let along = |p: Vec3, q: Vec3| (0..=200).map(move |i| p + (q - p) * (i as f32 / 200.0));
    along(p1, q1).flat_map(|a| along(p2, q2).map(move |b| a.distance(b))).fold(f32::INFINITY, f32::min)
}

/// Long thin seeds (a kiwi's: eight times longer than wide) are kept apart by their
/// capsules, not their bounding spheres: many more fit in the same box, still apart.
#[test]
fn thin_seeds_pack_as_closely_as_their_shapes_allow() {
    let corners =
        vec![Vec3::new(-0.12, -0.12, -1.0), Vec3::new(0.12, -0.12, -1.0), Vec3::new(0.0, 0.12, -1.0), Vec3::Z];
    let needle = solidtex::mesh::Mesh::new(corners, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]]).unwrap();
    let params = in_cube(400, 32.0, (3.0, 3.0));
    let placed = scatter(&mut grey_cube(32), &needle, &params, 5).unwrap().placed;
    // Spheres of radius 3 in a 32-voxel cube, their centres at least 3 from every face:
    // at most (26^3) / (4/3 pi 3^3) * 0.74 (the densest packing) = 115 of them.
    assert!(placed.len() > 150, "{} placed", placed.len());
}

#[test]
fn scatter_in_a_depth_band_stays_in_the_band() {
    let mesh = seed_mesh(12, 12).unwrap();
    let mut v =
        Volume::from_fn([40, 40, 40], vec![Channel::R, Channel::G, Channel::B, Channel::Depth], |_, _, z, o| {
            o.copy_from_slice(&[0.5, 0.5, 0.5, z as f32 / 39.0])
        })
        .unwrap();
    let params =
        Scatter { count: 10, region: Region::Depth(0.5, 0.7), scale: (1.5, 1.5), colour: [0.0; 3], attempts: 500 };
    let done = scatter(&mut v, &mesh, &params, 3).unwrap();
    assert_eq!(done.placed.len(), 10);
    for p in &done.placed {
        let depth = p.at.z / 39.0;
        assert!((0.48..=0.73).contains(&depth), "seed at depth {depth}");
    }
}

#[test]
fn blur_softens_inside_the_sphere_only() {
    let mut v = Volume::from_fn([20, 20, 20], Channel::rgb(), |x, _, _, o| o.fill((x % 2) as f32)).unwrap();
    let before = v.clone();
    let changed = blur(&mut v, Vec3::new(10.0, 10.0, 10.0), 4.0, 1.0).unwrap();
    assert!(changed > 100);
    let centre = v.get(10, 10, 10, 0);
    assert!((centre - 0.5).abs() < 0.2, "a checker blurs towards grey: {centre}");
    assert_eq!(v.voxel(1, 1, 1), before.voxel(1, 1, 1));
    assert!(blur(&mut v, Vec3::splat(100.0), 2.0, 1.0).unwrap_err().to_string().contains("misses"));
    assert!(blur(&mut v, Vec3::splat(5.0), -1.0, 1.0).unwrap_err().to_string().contains("radius"));
}

#[test]
fn the_command_line_sweeps_stamps_scatters_and_blurs() {
    let dir = tempfile::tempdir().unwrap();
    let (section, seed) = (at(dir.path(), "kiwi.png"), at(dir.path(), "seed.obj"));
    assert!(solidtex(&["draw", "kiwi", "--size", "32x24", "-o", &section]).status.success());
    assert!(solidtex(&["draw", "seed", "-o", &seed]).status.success());
    let swept = at(dir.path(), "swept.exr");
    let run = solidtex(&[
        "sweep",
        &section,
        "--length",
        "20",
        "--depth-axis",
        "z",
        "--noise",
        "1,2",
        "--skin",
        "#402010",
        "--skin-width",
        "2",
        "-o",
        &swept,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let v = read_volume(std::path::Path::new(&swept), 1 << 30).unwrap();
    assert_eq!(v.dims(), [20, 32, 24]);
    assert_eq!(v.channels().last(), Some(&Channel::Depth));
    let skin = v.voxel(5, 5, 0);
    assert!((skin[0] - 0x40 as f32 / 255.0).abs() < 1e-5, "skin colour at depth 0: {skin:?}");
    let stamped = at(dir.path(), "stamped.exr");
    let run = solidtex(&[
        "stamp", &swept, &seed, "--at", "10,16,12", "--scale", "3", "--rotate", "0,1,0,90", "--color", "0,0,0", "-o",
        &stamped,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let scattered = at(dir.path(), "scattered.exr");
    let run = solidtex(&[
        "scatter",
        &stamped,
        &seed,
        "--count",
        "5",
        "--region",
        "depth:0.3,0.8",
        "--scale",
        "1..1.5",
        "--color",
        "#000000",
        "-o",
        &scattered,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("placed 5 seeds"), "{}", stderr(&run));
    let blurred = at(dir.path(), "blurred.exr");
    let run = solidtex(&["blur", &scattered, "--at", "10,16,12", "--radius", "4", "-o", &blurred]);
    assert!(run.status.success(), "{}", stderr(&run));
}

#[test]
fn hand_made_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (section, seed) = (at(dir.path(), "kiwi.png"), at(dir.path(), "seed.obj"));
    assert!(solidtex(&["draw", "kiwi", "--size", "16x16", "-o", &section]).status.success());
    assert!(solidtex(&["draw", "seed", "-o", &seed]).status.success());
    let other = at(dir.path(), "other.obj");
    assert_usage(&solidtex(&["draw", "seed", "--size", "8x8", "-o", &other]), &["--size 8x8", "seed is a mesh"]);
    assert!(!dir.path().join("other.obj").exists());
    let out = at(dir.path(), "out.exr");
    assert_usage(&solidtex(&["sweep", &section, "--length", "0", "-o", &out]), &["length 0"]);
    assert_usage(
        &solidtex(&["sweep", &section, "--length", "8", "--depth-axis", "x", "-o", &out]),
        &["--depth-axis x", "sweep's --axis"],
    );
    assert_usage(&solidtex(&["sweep", &section, "--length", "8", "--noise", "1", "-o", &out]), &["--noise \"1\""]);
    let vol = at(dir.path(), "v.exr");
    assert!(solidtex(&["sweep", &section, "--length", "8", "-o", &vol]).status.success());
    assert_fails(
        &solidtex(&["stamp", &vol, &seed, "--at", "900,0,0", "--color", "0,0,0", "-o", &out]),
        &["wholly outside"],
    );
    assert_usage(&solidtex(&["stamp", &vol, &seed, "--at", "1,2", "--color", "0,0,0", "-o", &out]), &["--at \"1,2\""]);
    // an output in no volume format is a usage error, as for every command that writes one
    let obj = at(dir.path(), "stamped.obj");
    let run = solidtex(&["stamp", &vol, &seed, "--at", "1,1,1", "--color", "0,0,0", "-o", &obj]);
    assert_usage(&run, &["stamped.obj", "unknown volume extension .obj"]);
    assert_usage(&solidtex(&["draw", "lemon", "-o", &out]), &["lemon", "kiwi"]);
    assert_eq!(listing(dir.path()), ["kiwi.png", "seed.obj", "v.exr"]);
}

#[test]
fn the_default_library_builds_kiwi_carrot_and_trunk() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/library.toml");
    let out = at(dir.path(), "lib");
    let run = solidtex(&["build", manifest, "-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    let kiwi = read_volume(&dir.path().join("lib/kiwi.exr"), 1 << 30).unwrap();
    assert_eq!(kiwi.meta.texture_type, Some(solidtex::TextureType::T2b));
    // Seeds were stamped: very dark voxels inside the seed band, none in the core.
    let depth = kiwi.channel_index(&Channel::Depth).unwrap();
    let dark = |lo: f32, hi: f32| {
        kiwi.data()
            .chunks(kiwi.channel_count())
            .filter(|v| (lo..hi).contains(&v[depth]) && v[0] + v[1] + v[2] < 0.3)
            .count()
    };
    assert!(dark(0.5, 0.8) > 40, "seed voxels: {}", dark(0.5, 0.8));
    assert_eq!(dark(0.9, 1.01), 0);
    for name in ["carrot", "trunk"] {
        assert!(dir.path().join(format!("lib/{name}.sheet.png")).exists());
    }
}

#[test]
fn an_open_seed_is_stamped_with_a_warning_naming_its_boundary_edges() {
    let dir = tempfile::tempdir().unwrap();
    let mut mesh = seed_mesh(12, 12).unwrap();
    mesh.triangles.truncate(mesh.triangles.len() - 2);
    let open = dir.path().join("open.obj");
    solidtex::io::mesh_file::write_obj(&open, &mesh).unwrap();
    let vol = at(dir.path(), "v.exr");
    solidtex::io::write_volume(std::path::Path::new(&vol), &grey_cube(24)).unwrap();
    let out = at(dir.path(), "out.exr");
    let run = solidtex(&[
        "stamp",
        &vol,
        &open.to_string_lossy(),
        "--at",
        "12,12,12",
        "--scale",
        "5",
        "--color",
        "0,0,0",
        "-o",
        &out,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("warning") && stderr(&run).contains("boundary edge"), "{}", stderr(&run));
    let v = read_volume(std::path::Path::new(&out), 1 << 30).unwrap();
    assert_eq!(v.voxel(12, 12, 12), &[0.0, 0.0, 0.0], "the inside is still found");
}

#[test]
fn a_sweep_image_that_does_not_fit_the_asked_size_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let section = at(dir.path(), "s.png");
    assert!(solidtex(&["draw", "carrot", "--size", "16x12", "-o", &section]).status.success());
    let manifest = dir.path().join("lib.toml");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"c\"\nrecipe = \"sweep\"\nimage = \"s.png\"\nlength = 8\naxis = \"x\"\nsize = [8, 16, 16]\n").unwrap();
    let out = at(dir.path(), "lib");
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &out]);
    assert_eq!(run.status.code(), Some(1));
    let err = stderr(&run);
    for needle in ["FAILED c:", "s.png", "16x12 pixels", "[8, 16, 12]", "[8, 16, 16]", "1 exemplar(s) failed: c"] {
        assert!(err.contains(needle), "{needle:?} not in {err}");
    }
    assert!(!dir.path().join("lib/c.exr").exists());
}

/// A kiwi cross-section and a seed mesh in `dir`.
fn section_and_seed(dir: &std::path::Path) -> (String, String) {
    let (section, seed) = (at(dir, "kiwi.png"), at(dir, "seed.obj"));
    assert!(solidtex(&["draw", "kiwi", "--size", "32x24", "-o", &section]).status.success());
    assert!(solidtex(&["draw", "seed", "-o", &seed]).status.success());
    (section, seed)
}

/// A grey image of `w` x `h` pixels, all `value`, written to `dir/name`.
fn grey_image(dir: &std::path::Path, name: &str, (w, h): (usize, usize), value: f32) -> String {
    let image = solidtex::volume::Image2d::from_data(w, h, Channel::grey(), vec![value; w * h]).unwrap();
    solidtex::io::write_image(&dir.join(name), &image).unwrap();
    at(dir, name)
}

fn read(path: &str) -> Volume {
    read_volume(std::path::Path::new(path), 1 << 30).unwrap()
}

/// Seeds drawn smaller than a voxel change nothing: they are not counted as placed, and the
/// run says how many there were and that a larger --scale places them; with none placed
/// it fails and writes nothing (the output would be the input unchanged).
#[test]
fn seeds_smaller_than_a_voxel_are_not_counted_as_placed() {
    let dir = tempfile::tempdir().unwrap();
    let (section, seed) = section_and_seed(dir.path());
    let (vol, out) = (at(dir.path(), "v.exr"), at(dir.path(), "out.exr"));
    assert!(solidtex(&["sweep", &section, "--length", "20", "-o", &vol]).status.success());
    let run = solidtex(&["scatter", &vol, &seed, "--count", "5", "--scale", "0.001", "--color", "0,0,0", "-o", &out]);
    let err = stderr(&run);
    assert_fails(&run, &["placed none of the 5 seeds", "nothing written", "a larger --scale places them"]);
    assert!(err.contains("5 of 5 seeds were smaller than a voxel"), "{err}");
    assert!(!err.contains("no room"), "{err}");
    assert!(!std::path::Path::new(&out).exists());
}

/// A scatter box wholly outside the volume is an error naming the box and the volume's
/// size, and seeds too large for any room fail the run: nothing is written either way.
#[test]
fn a_scatter_that_can_place_nothing_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (section, seed) = section_and_seed(dir.path());
    let (vol, out) = (at(dir.path(), "v.exr"), at(dir.path(), "out.exr"));
    assert!(solidtex(&["sweep", &section, "--length", "20", "-o", &vol]).status.success());
    let scatter = |extra: &[&str]| {
        let base = ["scatter", &vol, &seed, "--count", "5", "--color", "0,0,0", "-o", &out];
        solidtex(&[&base[..], extra].concat())
    };
    let run = scatter(&["--region", "box:100,100,100,200,200,200"]);
    assert_fails(&run, &["v.exr", "the box (100, 100, 100) to (200, 200, 200) lies wholly outside the", "volume"]);
    let run = scatter(&["--scale", "200..300"]);
    assert_fails(&run, &["placed none of the 5 seeds", "a smaller --scale or a larger region"]);
    assert!(!std::path::Path::new(&out).exists());
}

/// A grey volume (one channel) takes the Rec. 709 luminance of a skin or stamp colour,
/// not its red: pure red is 0.2126, pure green 0.7152.
#[test]
fn a_grey_volume_takes_the_luminance_of_a_colour() {
    let dir = tempfile::tempdir().unwrap();
    let (_, seed) = section_and_seed(dir.path());
    let section = grey_image(dir.path(), "grey.png", (32, 24), 0.5);
    let (swept, stamped) = (at(dir.path(), "swept.exr"), at(dir.path(), "stamped.exr"));
    let run = solidtex(&["sweep", &section, "--length", "8", "--depth-axis", "z", "--skin", "#ff0000", "-o", &swept]);
    assert!(run.status.success(), "{}", stderr(&run));
    let v = read(&swept);
    assert_eq!(v.channels(), [Channel::R, Channel::Depth]);
    assert!((v.get(4, 10, 0, 0) - 0.2126).abs() < 1e-4, "skin: {}", v.get(4, 10, 0, 0));
    let run =
        solidtex(&["stamp", &swept, &seed, "--at", "4,16,12", "--scale", "4", "--color", "#00ff00", "-o", &stamped]);
    assert!(run.status.success(), "{}", stderr(&run));
    let centre = read(&stamped).get(4, 16, 12, 0);
    assert!((centre - 0.7152).abs() < 1e-4, "stamp: {centre}");
}

/// A grey skin image over a colour cross-section is refused naming the skin image.
#[test]
fn a_grey_skin_image_is_named_as_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let (section, _) = section_and_seed(dir.path());
    let skin = grey_image(dir.path(), "skin.png", (8, 8), 0.3);
    let out = at(dir.path(), "out.exr");
    let run = solidtex(&["sweep", &section, "--length", "8", "--depth-axis", "z", "--skin", &skin, "-o", &out]);
    assert_fails(&run, &["skin.png", "skin image has 1 channel", "R, G and B"]);
    assert!(!stderr(&run).contains("kiwi.png"), "{}", stderr(&run));
}

/// A depth band in a volume without Depth names the volume, not the seed mesh, and says
/// what makes a Depth channel.
#[test]
fn a_depth_band_in_a_volume_without_depth_names_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    let (section, seed) = section_and_seed(dir.path());
    let (vol, out) = (at(dir.path(), "flat.exr"), at(dir.path(), "out.exr"));
    assert!(solidtex(&["sweep", &section, "--length", "8", "-o", &vol]).status.success());
    let run = solidtex(&[
        "scatter",
        &vol,
        &seed,
        "--count",
        "3",
        "--region",
        "depth:0.2,0.4",
        "--color",
        "0,0,0",
        "-o",
        &out,
    ]);
    assert_fails(&run, &["flat.exr", "has no Depth channel", "R,G,B", "--depth-axis"]);
    assert!(!stderr(&run).contains("seed.obj"), "{}", stderr(&run));
    assert!(!std::path::Path::new(&out).exists());
}

/// A blur of strength 0 says it changes nothing, and writes the volume as it was.
#[test]
fn a_blur_of_strength_0_says_it_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (section, _) = section_and_seed(dir.path());
    let (vol, out) = (at(dir.path(), "v.exr"), at(dir.path(), "out.exr"));
    assert!(solidtex(&["sweep", &section, "--length", "20", "-o", &vol]).status.success());
    let run = solidtex(&["blur", &vol, "--at", "10,10,10", "--radius", "3", "--strength", "0", "-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("warning: --strength 0 blurs nothing") && !err.contains("blurred"), "{err}");
    assert_eq!(read(&out).data(), read(&vol).data());
}

/// A scatter box with a corner past the other, or a depth band upside down, is a usage
/// error naming the value.
#[test]
fn a_reversed_scatter_region_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (section, seed) = section_and_seed(dir.path());
    let (vol, out) = (at(dir.path(), "v.exr"), at(dir.path(), "out.exr"));
    assert!(solidtex(&["sweep", &section, "--length", "20", "-o", &vol]).status.success());
    let scatter = |region: &str| {
        solidtex(&["scatter", &vol, &seed, "--count", "3", "--region", region, "--color", "0,0,0", "-o", &out])
    };
    assert_usage(
        &scatter("box:10,0,0,2,20,20"),
        &["--region box \"10,0,0,2,20,20\"", "corners reversed", "X0 10 is past X1 2", "X0 <= X1"],
    );
    assert_usage(&scatter("box:0,0,9,20,20,3"), &["Z0 9 is past Z1 3"]);
    assert_usage(&scatter("depth:0.8,0.2"), &["--region depth \"0.8,0.2\"", "0 <= FROM <= TO <= 1"]);
    assert!(!std::path::Path::new(&out).exists());
}

/// A scatter region given to the library directly is checked as one in a manifest or on
/// the command line is: a reversed box names the axis and both corners' values alike.
#[test]
fn a_reversed_region_box_reads_alike_wherever_it_is_given() {
    let err = solidtex::stamp::check_region(Region::Box(Vec3::new(0.0, 5.0, 0.0), Vec3::ONE)).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("corners reversed: Y0 5 is past Y1 1") && text.contains("Y0 <= Y1"), "{text}");
}

/// `draw` names every drawing it knows when given another, and says a size is not `WxH`
/// rather than out of range; a stamp's error names both files without running them on.
#[test]
fn draw_and_stamp_say_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let out = at(dir.path(), "x.png");
    let run = solidtex(&["draw", "nothing", "-o", &out]);
    assert_usage(&run, &["unknown drawing \"nothing\"", "kiwi", "bark-skin", "seed, bubble, fruit", "vase, cake"]);
    assert_usage(&solidtex(&["draw", "kiwi", "--size", "64", "-o", &out]), &["--size \"64\" is not WxH", "64x64"]);
    assert_usage(&solidtex(&["draw", "kiwi", "--size", "1x64", "-o", &out]), &["--size \"1x64\" is out of range"]);
    assert!(!std::path::Path::new(&out).exists());
    let (section, _) = section_and_seed(dir.path());
    let vol = at(dir.path(), "v.exr");
    assert!(solidtex(&["sweep", &section, "--length", "20", "-o", &vol]).status.success());
    let flat = at(dir.path(), "flat.obj");
    std::fs::write(&flat, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let run = solidtex(&["stamp", &vol, &flat, "--at", "5,5,5", "--color", "0,0,0", "-o", &at(dir.path(), "s.exr")]);
    let err = stderr(&run);
    assert!(!run.status.success() && err.contains("flat.obj") && err.contains("(stamping into "), "{err}");
    assert!(!err.contains("surface read from"), "{err}");
}
