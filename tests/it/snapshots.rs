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
}
