//! Classification and masks from the command line, with their bad input.

use crate::support::{assert_fails, assert_usage, at, listing, solidtex, stderr};
use solidtex::io::{read_volume, write_volume};
use solidtex::volume::{Channel, Volume};
use std::path::Path;

#[test]
fn classify_reports_type_axes_and_measurements() {
    let dir = tempfile::tempdir().unwrap();
    let strata = at(dir.path(), "strata.exr");
    assert!(solidtex(&["make", "strata", "--size", "24", "-o", &strata]).status.success());
    let run = solidtex(&["classify", &strata, "--json"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(json["texture_type"], "1-b");
    assert_eq!(json["depth_axis"], "z");
    assert!(json["within_slice_share"][2].as_f64().unwrap() < 0.45);
    // the JSON carries the figure the text prints: the slice means' share, large along depth
    let means = json["slice_means_share"][2].as_f64().unwrap();
    let text = String::from_utf8(solidtex(&["classify", &strata]).stdout).unwrap();
    assert!(means > 0.55 && text.contains(&format!("z {means:.3}")), "{means} against {text}");
    assert!(text.contains("1-b (anisotropy 1, variation 1)") && text.contains("depth axis  z"), "{text}");
    // 24 voxels a side: lag 8 is over a quarter of it, not measured, printed as "-" and null
    assert!(json["variogram"][0][3].is_null() && json["variogram"][0][2].is_f64(), "{json}");
    let x_row = text.lines().find(|l| l.trim_start().starts_with("x  ")).unwrap();
    assert!(x_row.trim_end().ends_with('-'), "{text}");
}

#[test]
fn a_borderline_volume_gets_its_two_nearest_types_with_scores() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("stretched.exr");
    // Noise cells 4 along x and 6 along y and z: stretched by 1.5, near the alike factor 1.8.
    let volume = Volume::from_fn([24; 3], Channel::grey(), |x, y, z, o| {
        let p = glam::Vec3::new(x as f32, y as f32, z as f32) / 24.0;
        o[0] = 0.5 + 0.4 * solidtex::noise::fbm(1, p * glam::Vec3::new(4.0, 6.0, 6.0), [4, 6, 6], 3);
    })
    .unwrap();
    write_volume(&file, &volume).unwrap();
    let run = solidtex(&["classify", &file.to_string_lossy(), "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let confidence = json["confidence"].as_f64().unwrap();
    assert!(confidence < 0.6, "{json}");
    let names: Vec<&str> =
        json["nearest"].as_array().unwrap().iter().map(|n| n["texture_type"].as_str().unwrap()).collect();
    assert_eq!(&names[..2], ["0", "1-a"], "{json}");
    let text = String::from_utf8(solidtex(&["classify", &file.to_string_lossy()]).stdout).unwrap();
    assert!(text.contains(&format!("nearest     0 ({confidence:.2}), 1-a (")), "{text}");
}

#[test]
fn classify_refuses_small_volumes_and_explains_constant_ones() {
    let dir = tempfile::tempdir().unwrap();
    let small = dir.path().join("small.exr");
    write_volume(&small, &Volume::new([8, 8, 5], Channel::rgb()).unwrap()).unwrap();
    assert_fails(
        &solidtex(&["classify", &small.to_string_lossy()]),
        &["small.exr", "axis z has 5 voxels", "at least 8"],
    );
    let flat = dir.path().join("flat.exr");
    write_volume(&flat, &Volume::from_fn([8; 3], Channel::grey(), |_, _, _, o| o[0] = 0.4).unwrap()).unwrap();
    let text = String::from_utf8(solidtex(&["classify", &flat.to_string_lossy()]).stdout).unwrap();
    assert!(text.contains("type        0") && text.contains("constant"), "{text}");
}

#[test]
fn masks_are_built_measured_and_reproducible() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (at(dir.path(), "a.exr"), at(dir.path(), "b.exr"));
    let run = solidtex(&["mask", "splotch", "--size", "32", "--falloff", "0.1", "--seed", "4", "-o", &a]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("fall-off") && stderr(&run).contains("tetrahedron"), "{}", stderr(&run));
    assert!(
        solidtex(&["mask", "splotch", "--size", "32", "--falloff", "0.1", "--seed", "4", "-o", &b]).status.success()
    );
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let layers = at(dir.path(), "layers");
    assert!(solidtex(&["mask", "layered", "--size", "24", "-o", &layers]).status.success());
    let names = ["inner.exr", "middle.exr", "outer.exr", "solidtex-folder.txt"];
    assert_eq!(listing(&dir.path().join("layers")), names);
    let outer = read_volume(&dir.path().join("layers/outer.exr"), 1 << 30).unwrap();
    let opaque = (0..24 * 24).filter(|i| outer.get(i % 24, i / 24, 0, 0) == 1.0).count();
    assert!(
        opaque >= 24 * 24 / 4 && outer.get(12, 12, 0, 0) == 1.0,
        "the outer mask covers the depth-0 face: {opaque}"
    );
    assert!(
        (0..24).all(|k| outer.get(0, k, 0, 0) == 0.0 && outer.get(k, 23, 0, 0) == 0.0),
        "and fades before its edges"
    );
}

#[test]
fn a_mesh_mask_follows_the_mesh_and_refuses_open_ones() {
    let dir = tempfile::tempdir().unwrap();
    let seed = at(dir.path(), "seed.obj");
    assert!(solidtex(&["draw", "seed", "-o", &seed]).status.success());
    let m = at(dir.path(), "m.exr");
    let run = solidtex(&["mask", "mesh", &seed, "--size", "24", "--falloff", "0.1", "-o", &m]);
    assert!(run.status.success(), "{}", stderr(&run));
    let v = read_volume(Path::new(&m), 1 << 30).unwrap();
    assert_eq!(v.get(12, 12, 12, 0), 1.0);
    assert_eq!(v.get(0, 0, 0, 0), 0.0);
    let mut mesh = solidtex::sections::seed_mesh(8, 8).unwrap();
    mesh.triangles.pop();
    let open = dir.path().join("open.obj");
    solidtex::io::mesh_file::write_obj(&open, &mesh).unwrap();
    let out = at(dir.path(), "o.exr");
    assert_fails(
        &solidtex(&["mask", "mesh", &open.to_string_lossy(), "--size", "16", "-o", &out]),
        &["open.obj", "boundary edge", "closed"],
    );
}

#[test]
fn mask_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = at(dir.path(), "m.exr");
    for f in ["0", "0.5", "0.7", "-0.1"] {
        let arg = format!("--falloff={f}");
        assert_usage(&solidtex(&["mask", "splotch", &arg, "-o", &out]), &["over 0 and under 0.5"]);
    }
    assert_usage(&solidtex(&["mask", "splotch", "--size", "2", "-o", &out]), &["size 2", "6 to 512"]);
    let preset = dir.path().join("p.toml");
    std::fs::write(&preset, "kind = \"cloud\"\n").unwrap();
    assert_fails(
        &solidtex(&["mask", "preset", &preset.to_string_lossy()]),
        &["p.toml", "cloud", "splotch, layered, mesh"],
    );
    assert_eq!(listing(dir.path()), ["p.toml"]);
}

/// The least mask size makes masks that are opaque somewhere, for every layer; smaller
/// sizes are usage errors naming the range; a fall-off that leaves no opaque voxel at all
/// is refused rather than written.
#[test]
fn the_least_mask_size_is_opaque_and_smaller_sizes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (splotch, layers) = (at(dir.path(), "s.exr"), at(dir.path(), "layers"));
    let run = solidtex(&["mask", "splotch", "--size", "6", "-o", &splotch]);
    assert!(run.status.success() && !stderr(&run).contains("opaque 0.0 %"), "{}", stderr(&run));
    let run = solidtex(&["mask", "layered", "--size", "6", "-o", &layers]);
    assert!(run.status.success(), "{}", stderr(&run));
    for file in
        [splotch.clone(), format!("{layers}/outer.exr"), format!("{layers}/middle.exr"), format!("{layers}/inner.exr")]
    {
        let mask = read_volume(Path::new(&file), 1 << 30).unwrap();
        assert!(mask.data().iter().any(|a| *a >= 0.999), "{file} is opaque nowhere");
    }
    for size in ["4", "5"] {
        let out = at(dir.path(), &format!("m{size}.exr"));
        assert_usage(&solidtex(&["mask", "splotch", "--size", size, "-o", &out]), &["--size", size, "6 to 512"]);
    }
    let wide = at(dir.path(), "wide.exr");
    let run = solidtex(&["mask", "splotch", "--size", "64", "--falloff", "0.45", "-o", &wide]);
    assert_fails(&run, &["opaque nowhere", "fall-off 0.45", "smaller fall-off"]);
    assert!(!Path::new(&wide).exists());
    // a handful of opaque voxels is written, with a warning that its patches cover thinly
    let run = solidtex(&["mask", "splotch", "--size", "64", "--falloff", "0.4", "-o", &wide]);
    assert!(run.status.success() && Path::new(&wide).exists(), "{}", stderr(&run));
    assert!(stderr(&run).contains("wide.exr is opaque in under 1 %") && stderr(&run).contains("smaller --falloff"));
    let run = solidtex(&["mask", "splotch", "--size", "6", "-o", &splotch]);
    assert!(!stderr(&run).contains("warning"), "{}", stderr(&run));
}
