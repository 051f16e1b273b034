//! `solidtex snapshot`: write or check a text snapshot of a volume.

use super::commands::usage;
use crate::error::{Error, Result};
use crate::io;
use std::path::Path;

/// Run `solidtex snapshot VOLUME (-o NAME.snap | --check NAME.snap [--tolerance T])`.
pub fn run(volume: &Path, output: Option<&Path>, check: Option<&Path>, tolerance: Option<f64>) -> Result<()> {
    if tolerance.is_some() && check.is_none() {
        return Err(Error::usage("--tolerance belongs to --check NAME.snap (a comparison); -o writes a snapshot"));
    }
    let tolerance = tolerance.unwrap_or(0.0);
    io::values::within("--tolerance", tolerance, 0.0, 1.0e6).map_err(usage)?;
    if let Some(out) = output {
        io::guard::file_output(out, &[volume], &["snap"], "a text snapshot")?;
    }
    let v = io::read_volume(volume, io::budget_from_env()?)?;
    match (output, check) {
        (Some(out), None) => {
            io::snapshot_file::write(out, &v)?;
            tell!("wrote {}", out.display());
            Ok(())
        }
        (None, Some(snap)) => {
            io::snapshot_file::check(snap, &v, tolerance)?;
            tell!("{} matches {}", volume.display(), snap.display());
            Ok(())
        }
        _ => Err(Error::usage("give either -o NAME.snap (write) or --check NAME.snap (compare)")),
    }
}
