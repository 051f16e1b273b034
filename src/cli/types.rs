//! `solidtex classify` and `solidtex types`: the seven LST texture types.

use crate::error::Result;
use crate::io;
use std::path::Path;

/// Run `solidtex classify FILE [--json]`.
pub fn classify(file: &Path, json: bool) -> Result<()> {
    let volume = io::read_volume(file, io::budget_from_env()?)?;
    let c = crate::classify::classify(&volume).map_err(|e| e.in_file(file))?;
    if json {
        say!("{}", serde_json::to_string_pretty(&c).expect("a classification always serializes"));
        return Ok(());
    }
    let t = c.texture_type;
    say!("{}\n  type        {t} (anisotropy {}, variation {})", file.display(), t.anisotropy(), t.variation());
    say!("  primary     {}", c.primary_axis.as_deref().unwrap_or("none (isotropic)"));
    say!("  depth axis  {}", c.depth_axis.as_deref().unwrap_or("none (homogeneous)"));
    say!("  confidence  {:.2}", c.confidence);
    if c.confidence < crate::classify::LOW_CONFIDENCE {
        let [a, b] = [&c.nearest[0], &c.nearest[1]].map(|n| format!("{} ({:.2})", n.texture_type, n.score));
        say!("  nearest     {a}, {b}: the measurements sit near a threshold; look at the cuts");
    }
    let [lx, ly, lz] = c.slice_means_share;
    say!(
        "  slice means' share of the variance  x {lx:.3}  y {ly:.3}  z {lz:.3}   (a depth axis: >= {} and {}x the others)",
        crate::classify::MIN_BETWEEN,
        crate::classify::STANDS_OUT
    );
    let lags = crate::classify::LAGS.map(|l| l.to_string()).join(", ");
    let within = if c.depth_axis.is_some() { ", within the depth slices" } else { "" };
    say!("  variogram at lags {lags}{within}   (axes alike within a factor 1.8 at every lag)");
    for (axis, v) in ["x", "y", "z"].iter().zip(&c.variogram_measured) {
        say!("    {axis}  {}", v.map(|g| g.map_or_else(|| "    -".to_string(), |g| format!("{g:.3}"))).join("  "));
    }
    if let Some(declared) = volume.meta.texture_type.filter(|d| *d != t) {
        say!("  note        the file declares type {declared}");
    }
    for note in &c.notes {
        say!("  note        {note}");
    }
    Ok(())
}

/// Print the table of the seven types.
pub fn types() {
    for t in crate::TextureType::ALL {
        let tiles = ["in no direction", "along one axis", "in a plane", "in 3D"][t.tiling_dimensions() as usize];
        say!("type {:<4} anisotropy {}  variation {}  tiles {tiles}", t.name(), t.anisotropy(), t.variation());
        say!("          tensor field: {}", t.tensor_field());
        say!("          filling:      {}", t.filling());
        say!("          examples:     {}", t.examples());
    }
}
