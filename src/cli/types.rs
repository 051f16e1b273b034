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
    let [gx, gy, gz] = c.gradient_energy;
    let [lx, ly, lz] = c.layering;
    say!("  gradient energy / variance   x {gx:.4}  y {gy:.4}  z {gz:.4}   (alike within a factor 1.8)");
    say!("  within-slice variance share  x {lx:.3}  y {ly:.3}  z {lz:.3}   (layered below 0.45)");
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
