//! Snapshot files, and `assert_snapshot` for tests in the spirit of insta: the first run
//! writes the snapshot, later runs compare; a mismatch writes the actual volume, its sheet
//! and the new snapshot to `target/snapshot-failures/` and panics with their paths.

use crate::error::{Error, Result};
use crate::snapshot::Snapshot;
use crate::volume::Volume;
use std::path::{Path, PathBuf};

/// Write the snapshot of `volume` to `path` (atomically).
pub fn write(path: &Path, volume: &Volume) -> Result<()> {
    super::atomic::write_bytes(path, Snapshot::of(volume).to_text().as_bytes())
}

/// Read a snapshot file.
pub fn read(path: &Path) -> Result<Snapshot> {
    let text = super::atomic::read_text(path, "snapshot")?;
    Snapshot::parse(&text).map_err(|e| e.in_file(path))
}

/// Compare `volume` with the snapshot at `path`; the error lists every difference.
pub fn check(path: &Path, volume: &Volume, tolerance: f64) -> Result<()> {
    let expected = read(path)?;
    let differences = Snapshot::of(volume).differences(&expected, tolerance);
    if differences.is_empty() {
        Ok(())
    } else {
        Err(Error::file(path, format!("the volume differs from the snapshot: {}", differences.join("; "))))
    }
}

/// Folder of the snapshots: `SOLIDTEX_SNAPSHOTS`, else `tests/snapshots` under the current
/// folder (cargo runs tests from the package root).
pub fn snapshot_folder() -> PathBuf {
    std::env::var_os("SOLIDTEX_SNAPSHOTS").map(PathBuf::from).unwrap_or_else(|| PathBuf::from("tests/snapshots"))
}

/// Assert that `volume` matches the snapshot `name` (exactly when `tolerance` is 0).
///
/// The first run writes `tests/snapshots/NAME.snap` (review and commit it). With `CI` set,
/// a missing snapshot is a failure, never created. On a mismatch the actual volume
/// (`NAME.exr`), its contact sheet (`NAME.png`) and snapshot (`NAME.snap`) are written to
/// `target/snapshot-failures/` and the panic message names them.
pub fn assert_snapshot(name: &str, volume: &Volume, tolerance: f64) {
    let path = snapshot_folder().join(format!("{name}.snap"));
    if !path.exists() {
        if std::env::var_os("CI").is_some() {
            panic!("no snapshot {}: CI never creates snapshots; run the tests locally and commit it", path.display());
        }
        std::fs::create_dir_all(snapshot_folder()).expect("the snapshot folder can be created");
        write(&path, volume).expect("the new snapshot can be written");
        eprintln!("wrote new snapshot {} (review and commit it)", path.display());
        return;
    }
    if let Err(e) = check(&path, volume, tolerance) {
        let failures = PathBuf::from("target/snapshot-failures");
        let _ = std::fs::create_dir_all(&failures);
        let _ = super::write_volume(&failures.join(format!("{name}.exr")), volume);
        let _ = super::write_rgb8(&failures.join(format!("{name}.png")), &crate::render::sheet(volume, name));
        let _ = write(&failures.join(format!("{name}.snap")), volume);
        panic!("{e}\nactual volume, sheet and snapshot written to {}/{name}.{{exr,png,snap}}", failures.display());
    }
}
