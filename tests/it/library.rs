//! The library build: caching, partial failure, reports.

use crate::support::{at, solidtex, stderr};
use std::path::Path;

/// A small library: two procedural entries and one sweep reading `section.png`.
fn library(dir: &Path) -> String {
    let section = at(dir, "section.png");
    assert!(solidtex(&["draw", "carrot", "--size", "16x16", "-o", &section]).status.success());
    let manifest = dir.join("lib.toml");
    std::fs::write(
        &manifest,
        "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 12\nseed = 1\n\
         [[exemplar]]\nname = \"b\"\nrecipe = \"procedural:strata\"\nsize = 12\n\
         [[exemplar]]\nname = \"c\"\nrecipe = \"sweep\"\nimage = \"section.png\"\nlength = 12\naxis = \"x\"\ndepth_axis = \"z\"\n",
    )
    .unwrap();
    manifest.to_string_lossy().into_owned()
}

#[test]
fn a_second_build_rebuilds_nothing_and_a_touched_input_rebuilds_only_its_exemplar() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let out = at(dir.path(), "out");
    let first = solidtex(&["build", &manifest, "-o", &out]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(stderr(&first).contains("3 built, 0 cached"), "{}", stderr(&first));
    let c_before = std::fs::read(dir.path().join("out/c.exr")).unwrap();
    let second = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&second).contains("0 built, 3 cached"), "{}", stderr(&second));
    assert!(
        solidtex(&["draw", "carrot", "--size", "16x16", "--seed", "2", "-o", &at(dir.path(), "section.png")])
            .status
            .success()
    );
    let third = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&third).contains("1 built, 2 cached") && stderr(&third).contains("built  c "), "{}", stderr(&third));
    assert_ne!(std::fs::read(dir.path().join("out/c.exr")).unwrap(), c_before);
    let forced = solidtex(&["build", &manifest, "-o", &out, "--force", "--only", "a"]);
    assert!(stderr(&forced).contains("1 built, 0 cached"), "{}", stderr(&forced));
    let report = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
    assert!(report.contains("| a | 12x12x12 | 0 |"), "{report}");
    assert!(std::fs::read_to_string(dir.path().join("out/report.html")).unwrap().contains("<img src=\"a.sheet.png\""));
}

#[test]
fn a_failing_exemplar_does_not_stop_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    std::fs::remove_file(dir.path().join("section.png")).unwrap();
    let out = at(dir.path(), "out");
    let run = solidtex(&["build", &manifest, "-o", &out]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("FAILED c:") && err.contains("section.png"), "{err}");
    assert!(err.contains("2 built, 0 cached, 1 failed"), "{err}");
    assert!(err.contains("error: 1 exemplar(s) failed: c"), "{err}");
    assert!(dir.path().join("out/a.exr").exists() && dir.path().join("out/b.exr").exists());
    assert!(!dir.path().join("out/c.exr").exists());
    let unknown = solidtex(&["build", &manifest, "-o", &out, "--only", "zz"]);
    assert!(stderr(&unknown).contains("--only \"zz\" is not in the manifest; it has a, b, c"), "{}", stderr(&unknown));
}
