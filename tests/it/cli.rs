//! The commands a designer runs, checked by their outputs.

use crate::support::{at, listing, random_volume, solidtex, stderr};
use solidtex::io::{read_volume, write_volume};
use solidtex::volume::{Axis, Channel};

#[test]
fn sheet_of_a_64_cube_shows_slices_and_the_cut_away() {
    let dir = tempfile::tempdir().unwrap();
    let vol = at(dir.path(), "strata.exr");
    let run = solidtex(&["make", "strata", "--size", "64", "--seed", "9", "-o", &vol]);
    assert!(run.status.success(), "{}", stderr(&run));
    let png = at(dir.path(), "sheet.png");
    let run = solidtex(&["sheet", &vol, "-o", &png]);
    assert!(run.status.success(), "{}", stderr(&run));
    let sheet = image::open(&png).unwrap().to_rgb8();
    assert_eq!(sheet.dimensions(), (560, 644));
    let volume = read_volume(dir.path().join("strata.exr").as_path(), 1 << 30).unwrap();
    // The XY panel is the z = 32 slice at 4x: its voxel (10, 20) sits at panel pixel (40, 80).
    let expect = volume.voxel(10, 20, 32);
    let got = sheet.get_pixel(16 + 40 + 1, 52 + 24 + 80 + 1).0;
    for c in 0..3 {
        assert!((got[c] as f32 / 255.0 - expect[c]).abs() <= 0.5 / 255.0 + 1e-6);
    }
    // The cut-away panel holds the solid: many non-background pixels of many colours.
    let mut colours = std::collections::HashSet::new();
    for y in 52 + 24 + 256 + 16 + 24..644 - 16 {
        for x in 16 + 256 + 16..560 - 16 {
            colours.insert(sheet.get_pixel(x, y).0);
        }
    }
    assert!(colours.len() > 500, "{} colours", colours.len());
}

#[test]
fn slice_writes_the_requested_cut() {
    let dir = tempfile::tempdir().unwrap();
    let v = random_volume([6, 5, 4], Channel::rgb(), 3);
    let vol = dir.path().join("v.nrrd");
    write_volume(&vol, &v).unwrap();
    let png = at(dir.path(), "cut.png");
    let run = solidtex(&["slice", &vol.to_string_lossy(), "--axis", "y", "--index", "2", "-o", &png]);
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (6, 4));
    let want = v.slice(Axis::Y, 2).unwrap();
    let got = img.get_pixel(5, 3).0;
    assert_eq!(got[1], (want.pixel(5, 3)[1] * 255.0).round() as u8);
    let bad = solidtex(&["slice", &vol.to_string_lossy(), "--axis", "w", "-o", &png]);
    assert!(stderr(&bad).contains("unknown axis \"w\"; allowed: x, y, z"));
    let bad = solidtex(&["slice", &vol.to_string_lossy(), "--axis", "z", "--index", "4", "-o", &png]);
    assert!(stderr(&bad).contains("index 4 is outside axis z"), "{}", stderr(&bad));
}

#[test]
fn info_reports_dims_type_and_stats_as_json() {
    let dir = tempfile::tempdir().unwrap();
    let vol = at(dir.path(), "m.exr");
    assert!(solidtex(&["make", "marble", "--size", "16x8x4", "-o", &vol]).status.success());
    let run = solidtex(&["info", &vol, "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(json["dims"], serde_json::json!([16, 8, 4]));
    assert_eq!(json["texture_type"], "0");
    assert_eq!(json["channels"], serde_json::json!(["R", "G", "B"]));
    let mean = json["stats"][0]["mean"].as_f64().unwrap();
    assert!(mean > 0.5 && mean < 1.0, "marble is mostly light: {mean}");
    let text = String::from_utf8(solidtex(&["info", &vol]).stdout).unwrap();
    assert!(text.contains("16 x 8 x 4") && text.contains("procedural:marble"), "{text}");
}

#[test]
fn convert_chains_keep_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    let first = at(dir.path(), "w.exr");
    assert!(solidtex(&["make", "wood", "--size", "12", "-o", &first]).status.success());
    let mut previous = first.clone();
    for next in ["w.nrrd", "w.vol", "w2.exr"] {
        let target = at(dir.path(), next);
        let run = solidtex(&["convert", &previous, &target]);
        assert!(run.status.success(), "{}", stderr(&run));
        previous = target;
    }
    let a = read_volume(std::path::Path::new(&first), 1 << 30).unwrap();
    let b = read_volume(std::path::Path::new(&previous), 1 << 30).unwrap();
    assert_eq!(a.data(), b.data());
}

#[test]
fn build_makes_the_default_library() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/library.toml");
    let out = at(dir.path(), "lib");
    let run = solidtex(&["build", manifest, "-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("built  wood 64x64x64"), "{}", stderr(&run));
    assert!(stderr(&run).contains("13 built, 0 cached, 0 failed"), "{}", stderr(&run));
    let names = listing(&dir.path().join("lib"));
    for name in [
        "marble",
        "strata",
        "wood",
        "kiwi",
        "carrot",
        "trunk",
        "gravel",
        "grass",
        "brick",
        "sponge",
        "cream",
        "chocolate",
    ] {
        assert!(names.contains(&format!("{name}.exr")) && names.contains(&format!("{name}.sheet.png")), "{names:?}");
    }
    for extra in ["marble-synth.mask.exr", "marble-synth.nrrd", "kiwi.masks", "report.md", "report.html"] {
        assert!(names.contains(&extra.to_string()), "{extra} missing from {names:?}");
    }
    // Every entry reads as the type its manifest (or recipe) declares.
    let report = std::fs::read_to_string(dir.path().join("lib/report.md")).unwrap();
    let rows: Vec<Vec<&str>> = report
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| exemplar"))
        .map(|l| l.split(" | ").collect())
        .collect();
    assert_eq!(rows.len(), 13, "{report}");
    for row in rows {
        assert_eq!(row[2], row[3], "{}: declared {}, classified {}", row[0], row[2], row[3]);
    }
    let strata = read_volume(&dir.path().join("lib/strata.exr"), 1 << 30).unwrap();
    assert_eq!(strata.meta.texture_type, Some(solidtex::TextureType::T1b));
    assert_eq!(strata.meta.get("name"), Some("strata"));
    // The gravel solid is as sharp as its photo and its stones about their size.
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let gravel = at(dir.path(), "lib/gravel.exr");
    let run = solidtex(&["quality", &gravel, "--exemplar", photo, "--max-exemplar", "128", "--json"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    for axis in report["sharpness"].as_array().unwrap() {
        let (gradient, length) = (axis["gradient_ratio"].as_f64().unwrap(), axis["length_ratio"].as_f64().unwrap());
        assert!((0.8..=1.2).contains(&gradient) && length <= 1.5, "{axis}");
    }
}

/// A volume synthesized from shrunk exemplars is measured against the same shrunk
/// exemplars when `quality` is not told `--max-exemplar` (the volume records it), and
/// says so.
#[test]
fn quality_measures_against_the_exemplars_the_volume_was_made_from() {
    let dir = tempfile::tempdir().unwrap();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let volume = at(dir.path(), "gravel.exr");
    let run = solidtex(&["synth", photo, "--max-exemplar", "48", "--size", "24", "-o", &volume]);
    assert!(run.status.success(), "{}", stderr(&run));
    let told = solidtex(&["quality", &volume, "--exemplar", photo, "--max-exemplar", "48", "--json"]);
    let recorded = solidtex(&["quality", &volume, "--exemplar", photo, "--json"]);
    assert!(told.status.success() && recorded.status.success(), "{}", stderr(&recorded));
    assert_eq!(String::from_utf8_lossy(&told.stdout), String::from_utf8_lossy(&recorded.stdout));
    assert!(stderr(&recorded).contains("--max-exemplar 48"), "{}", stderr(&recorded));
}

/// An output named in no format solidtex writes is a usage error (exit 2), said before any
/// work, with the formats allowed, and nothing is written.
#[test]
fn an_output_in_no_known_format_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = at(dir.path(), "marble.txt");
    let run = solidtex(&["make", "marble", "--size", "8", "-o", &out]);
    crate::support::assert_usage(&run, &["marble.txt", ".txt", ".exr", ".vdb"]);
    assert!(!dir.path().join("marble.txt").exists());
}

#[test]
fn build_rejects_a_bad_manifest_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("lib.toml");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"x\"\nrecipe = \"procedural:lava\"\nsize = 8\n").unwrap();
    let out = at(dir.path(), "lib");
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &out]);
    crate::support::assert_fails(&run, &["lib.toml", "entry 1 (x)", "lava", "allowed"]);
    assert!(!dir.path().join("lib").exists());
}

/// `quality --labels` gives the materials statistics of a label volume as JSON: slabs two
/// voxels thick along z have half of each phase, S2 along z of 0 at a lag of 2, and every
/// pair along x in the phase.
#[test]
fn quality_of_a_label_volume_reports_phase_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let slabs =
        solidtex::Volume::from_fn([4, 4, 8], solidtex::Channel::grey(), |_, _, z, o| o[0] = ((z / 2) % 2) as f32)
            .unwrap();
    let path = dir.path().join("slabs.nrrd");
    solidtex::io::write_volume(&path, &slabs).unwrap();
    let run = solidtex(&["quality", &path.to_string_lossy(), "--labels", "--json"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let phase = &json["phases"][0];
    assert_eq!(phase["share"], 0.5);
    assert_eq!(phase["two_point"][2][2], 0.0);
    assert_eq!(phase["two_point"][0][3], 0.5);
    let neither = solidtex(&["quality", &path.to_string_lossy()]);
    assert_eq!(neither.status.code(), Some(2), "no exemplar and no --labels is a usage error");
}

/// `help --help` and `help -h` print the help subcommand's own help and succeed, like
/// `--help` anywhere else; `help synth --help` prints synth's.
#[test]
fn help_takes_its_own_help_flag() {
    for args in [&["help", "--help"][..], &["help", "-h"], &["help", "synth", "--help"]] {
        let run = solidtex(args);
        assert_eq!(run.status.code(), Some(0), "{args:?}: {}", stderr(&run));
        let out = String::from_utf8_lossy(&run.stdout).into_owned();
        let usage = if args[1] == "synth" { "Usage: solidtex synth" } else { "Usage: solidtex help" };
        assert!(out.contains(usage), "{args:?}: {out}");
    }
}

/// A closed error stream (a reader that went away) does not turn a command's notes or its
/// error line into a panic: the command still writes its file and exits with its own code.
#[test]
fn a_closed_error_stream_keeps_the_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stderr.take());
        child.wait().unwrap().code()
    };
    let out = at(dir.path(), "m.exr");
    assert_eq!(run(&["make", "marble", "--size", "8", "-o", &out]), Some(0), "the note 'wrote ...' is dropped");
    assert!(std::path::Path::new(&out).exists());
    assert_eq!(run(&["info", &at(dir.path(), "missing.exr")]), Some(1), "the error line is dropped, the code kept");
}

/// A plane through voxel positions samples voxels, in the plane as along its normal: the
/// cut through z = 32 is the axis slice at index 32, pixel for pixel. A point out of range
/// is named as such.
#[test]
fn a_plane_through_a_voxel_slice_is_that_slice() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let vol = at(d, "m.exr");
    assert!(solidtex(&["make", "marble", "--size", "64", "-o", &vol]).status.success());
    let (axis, plane) = (at(d, "axis.png"), at(d, "plane.png"));
    assert!(solidtex(&["slice", &vol, "--axis", "z", "--index", "32", "-o", &axis]).status.success());
    let run = solidtex(&["slice", &vol, "--plane", "32,32,32,0,0,1", "-o", &plane]);
    assert!(run.status.success(), "{}", stderr(&run));
    let (a, p) = (image::open(&axis).unwrap().to_rgb8(), image::open(&plane).unwrap().to_rgb8());
    assert_eq!(a.dimensions(), p.dimensions());
    assert!(a == p, "the plane through z = 32 differs from the axis slice");
    let run = solidtex(&["slice", &vol, "--plane", "1e7,0,0,1,0,0", "-o", &at(d, "far.png")]);
    crate::support::assert_usage(&run, &["--plane", "out of range", "1000000"]);
}
