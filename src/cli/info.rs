//! `solidtex info`: what a volume file holds.

use crate::io;
use crate::volume::{ChannelStats, ModelGrid, Volume};
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
struct Report<'a> {
    file: String,
    dims: [usize; 3],
    channels: Vec<&'a str>,
    texture_type: Option<String>,
    provenance: Vec<(String, String)>,
    /// Where the volume sits in model space (a bake's grid), when recorded.
    #[serde(skip_serializing_if = "Option::is_none")]
    model_grid: Option<Placed>,
    stats: Vec<ChannelStats>,
}

/// A volume's place in model space: voxel (0, 0, 0)'s centre, the voxel side and the box
/// the voxels cover.
#[derive(Serialize)]
struct Placed {
    origin: [f32; 3],
    voxel: f32,
    box_min: [f32; 3],
    box_max: [f32; 3],
}

impl Placed {
    fn of(grid: ModelGrid, dims: [usize; 3]) -> Placed {
        let (box_min, box_max) = grid.box_of(dims);
        Placed { origin: grid.origin, voxel: grid.voxel, box_min, box_max }
    }
}

/// Print the report of `file`, as text or JSON.
pub fn run(file: &Path, json: bool) -> crate::Result<()> {
    let volume = io::read_volume(file, io::budget_from_env()?)?;
    let report = report(file, &volume);
    if json {
        let text = serde_json::to_string_pretty(&report).expect("a report always serializes");
        say!("{text}");
    } else {
        say!("{}", text(&report).trim_end());
    }
    Ok(())
}

fn report<'a>(file: &Path, volume: &'a Volume) -> Report<'a> {
    Report {
        file: file.display().to_string(),
        dims: volume.dims(),
        channels: volume.channels().iter().map(|c| c.name()).collect(),
        texture_type: volume.meta.texture_type.map(|t| t.to_string()),
        provenance: volume.meta.provenance.clone(),
        model_grid: volume.model_grid.map(|g| Placed::of(g, volume.dims())),
        stats: volume.channel_stats(16),
    }
}

fn text(r: &Report) -> String {
    let [x, y, z] = r.dims;
    let mut out = format!("{}\n  dims      {x} x {y} x {z} ({} voxels)\n", r.file, x * y * z);
    out += &format!("  channels  {}\n", r.channels.join(", "));
    out += &format!("  type      {}\n", r.texture_type.as_deref().unwrap_or("not set"));
    if let Some(p) = &r.model_grid {
        let [x, y, z] = p.origin;
        out += &format!("  origin    {x} {y} {z} (model-space centre of voxel 0 0 0)\n");
        out += &format!("  voxel     {} (side, model units)\n", p.voxel);
        let ([a, b, c], [d, e, f]) = (p.box_min, p.box_max);
        out += &format!("  box       {a} {b} {c} to {d} {e} {f} (the voxels' cells, model units)\n");
    }
    let width = r.provenance.iter().map(|(k, _)| k.len()).max().unwrap_or(0).max(9);
    for (k, v) in &r.provenance {
        out += &format!("  {k:<width$} {v}\n");
    }
    out += "  channel        mean     std     min     max  histogram (16 bins over 0..1)\n";
    for s in &r.stats {
        out += &format!(
            "  {:<12} {:>6.3}  {:>6.3}  {:>6.3}  {:>6.3}  {}\n",
            s.channel,
            s.mean,
            s.std,
            s.min,
            s.max,
            sparkline(&s.histogram)
        );
    }
    out
}

/// A histogram as block characters.
fn sparkline(histogram: &[u64]) -> String {
    const BARS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];
    let max = histogram.iter().copied().max().unwrap_or(0).max(1);
    histogram.iter().map(|&c| if c == 0 { ' ' } else { BARS[((c * 7) / max) as usize] }).collect()
}
