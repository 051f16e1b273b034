//! Snapshot tests: every default library exemplar (procedural ones at 16³), and the
//! `solidtex snapshot` command.

use crate::support::{assert_fails, at, solidtex, stderr};
use solidtex::io::manifest::{Source, read_plan};
use solidtex::io::snapshot_file::assert_snapshot;
use std::path::Path;

#[test]
fn every_default_library_exemplar_matches_its_snapshot() {
    let plan = read_plan(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/library.toml"))).unwrap();
    for mut entry in plan.entries {
        if matches!(entry.source, Source::Procedural(_)) {
            entry.dims = Some([16; 3]);
        }
        let volume = solidtex::library::recipe::make(&entry).unwrap();
        assert_snapshot(&format!("library-{}", entry.name), &volume, 0.0);
    }
}

#[test]
fn the_snapshot_command_writes_checks_and_names_differences() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (at(dir.path(), "a.exr"), at(dir.path(), "b.exr"));
    assert!(solidtex(&["make", "marble", "--size", "12", "--seed", "1", "-o", &a]).status.success());
    assert!(solidtex(&["make", "marble", "--size", "12", "--seed", "2", "-o", &b]).status.success());
    let snap = at(dir.path(), "a.snap");
    assert!(solidtex(&["snapshot", &a, "-o", &snap]).status.success());
    let text = std::fs::read_to_string(&snap).unwrap();
    assert!(text.starts_with("solidtex-snapshot 1\ndims 12 12 12\nchannels R,G,B\ntype 0\nhash "), "{text}");
    let same = solidtex(&["snapshot", &a, "--check", &snap]);
    assert!(same.status.success(), "{}", stderr(&same));
    assert_fails(&solidtex(&["snapshot", &b, "--check", &snap]), &["a.snap", "content hash"]);
    let loose = solidtex(&["snapshot", &b, "--check", &snap, "--tolerance", "0.9"]);
    assert!(loose.status.success(), "{}", stderr(&loose));
    crate::support::assert_usage(&solidtex(&["snapshot", &a]), &["either -o NAME.snap", "--check NAME.snap"]);
    let other = at(dir.path(), "other.snap");
    let ignored = solidtex(&["snapshot", &a, "-o", &other, "--tolerance", "5"]);
    crate::support::assert_usage(&ignored, &["--tolerance belongs to --check"]);
    assert!(!std::path::Path::new(&other).exists(), "nothing written");
}

/// A snapshot file keeps its figures rounded (stats to 6 decimals, thumbnails to 4): the
/// volume it was written of matches it at every tolerance, however small.
#[test]
fn a_volume_matches_its_own_snapshot_at_any_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let (a, snap) = (at(dir.path(), "a.exr"), at(dir.path(), "a.snap"));
    assert!(solidtex(&["make", "marble", "--size", "12", "--seed", "1", "-o", &a]).status.success());
    assert!(solidtex(&["snapshot", &a, "-o", &snap]).status.success());
    for tolerance in ["0", "1e-12", "1e-6", "1e-5", "0.00004", "0.0001", "0.01"] {
        let run = solidtex(&["snapshot", &a, "--check", &snap, "--tolerance", tolerance]);
        assert!(run.status.success(), "tolerance {tolerance}: {}", stderr(&run));
    }
}

/// A mismatch names dims and types as plain values: `12x12x12`, `0`, `none`.
#[test]
fn a_snapshot_mismatch_names_plain_values() {
    let dir = tempfile::tempdir().unwrap();
    let (a, small) = (at(dir.path(), "a.exr"), at(dir.path(), "small.exr"));
    assert!(solidtex(&["make", "marble", "--size", "12", "-o", &a]).status.success());
    assert!(solidtex(&["make", "marble", "--size", "10", "-o", &small]).status.success());
    let snap = dir.path().join("a.snap");
    assert!(solidtex(&["snapshot", &a, "-o", &snap.to_string_lossy()]).status.success());
    let untyped = dir.path().join("untyped.snap");
    let text = std::fs::read_to_string(&snap).unwrap();
    std::fs::write(&untyped, text.replace("\ntype 0\n", "\ntype -\n")).unwrap();
    let typed = solidtex(&["snapshot", &a, "--check", &untyped.to_string_lossy(), "--tolerance", "0.01"]);
    assert_fails(&typed, &["untyped.snap", "channels R,G,B type 0, expected R,G,B type none"]);
    let sized = solidtex(&["snapshot", &small, "--check", &snap.to_string_lossy()]);
    assert_fails(&sized, &["a.snap", "dims 10x10x10, expected 12x12x12"]);
    for run in [&typed, &sized] {
        let err = stderr(run);
        assert!(!err.contains("Some(") && !err.contains("None") && !err.contains('['), "{err}");
    }
}
