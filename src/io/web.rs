//! `solidtex web` pages: one self-contained HTML file (WebGL2, no network, no external
//! script) that shows volumes, filled models or a skin in 3D.
//!
//! The page is `web/viewer.html` with `web/viewer.js` inlined and the scene's data in a
//! JSON script element: grids as 8-bit planes (x fastest, then y, then z, one plane per
//! channel), zlib-compressed and base64-encoded; meshes as little-endian f32 positions and
//! u32 triangle indices, compressed the same way. The browser inflates them with its own
//! `DecompressionStream`. See docs/viewer.md.

use crate::error::{Error, Result};
use crate::fill::LstModel;
use crate::fill::render::{self, Textures};
use crate::mesh::Mesh;
use crate::render::to_u8;
use crate::volume::{Channel, Volume};
use base64::Engine;
use glam::Vec3;
use serde_json::{Value, json};
use std::io::Write;

/// The page around the viewer.
const TEMPLATE: &str = include_str!("web/viewer.html");

/// The viewer's script.
const SCRIPT: &str = include_str!("web/viewer.js");

/// One named volume of a page.
pub struct NamedVolume<'a> {
    /// What the page calls it.
    pub name: String,
    /// Its voxels.
    pub volume: &'a Volume,
}

/// Filled models baked into one grid, with the surfaces they were filled from.
pub struct ModelScene<'a> {
    /// R, G, B, then A (1 inside a model), as `render::bake` makes it.
    pub baked: &'a Volume,
    /// The model-space corner of voxel (0, 0, 0)'s cell.
    pub lo: Vec3,
    /// One voxel's side in model units.
    pub step: f32,
    /// Each model's name and input surface.
    pub surfaces: Vec<(String, &'a Mesh)>,
}

/// The largest grid side a page holds: WebGL2 promises 3D textures up to 256 per side.
pub const MAX_SIDE: usize = 256;

/// The grid side of the 3D view a library report shows of each exemplar.
pub const PREVIEW_SIDE: usize = 128;

/// `volume` at every k-th voxel along each axis, k the smallest whole number that brings
/// its longest side to `most` or below (k = 1: the volume itself): (volume, k).
pub fn within_side(volume: &Volume, most: usize) -> Result<(std::borrow::Cow<'_, Volume>, usize)> {
    let dims = volume.dims();
    let k = dims.iter().max().copied().unwrap_or(1).div_ceil(most.max(1)).max(1);
    if k == 1 {
        return Ok((std::borrow::Cow::Borrowed(volume), 1));
    }
    let small = dims.map(|d| d.div_ceil(k));
    let mut data = Vec::with_capacity(small.iter().product::<usize>() * volume.channel_count());
    for z in 0..small[2] {
        for y in 0..small[1] {
            for x in 0..small[0] {
                data.extend_from_slice(volume.voxel(x * k, y * k, z * k));
            }
        }
    }
    Ok((std::borrow::Cow::Owned(Volume::from_data(small, volume.channels().to_vec(), data)?), k))
}

/// The page a library build writes beside each exemplar: its volume at up to
/// [`PREVIEW_SIDE`] voxels per side.
pub fn preview_page(name: &str, volume: &Volume) -> Result<String> {
    let (shown, k) = within_side(volume, PREVIEW_SIDE)?;
    let title = if k == 1 { name.to_string() } else { format!("{name} (one voxel in {k} along each axis)") };
    volumes_page(&title, &[NamedVolume { name: name.to_string(), volume: &shown }])
}

/// A page of one or more volumes (a picker chooses among them).
pub fn volumes_page(title: &str, volumes: &[NamedVolume]) -> Result<String> {
    let items = volumes.iter().map(|v| grid(&v.name, v.volume)).collect::<Result<Vec<_>>>()?;
    page(title, json!({ "kind": "volumes", "volumes": items }))
}

/// A page of filled models.
pub fn models_page(title: &str, scene: &ModelScene) -> Result<String> {
    let mut baked = grid("models", scene.baked)?;
    baked["lo"] = json!(scene.lo.to_array());
    baked["step"] = json!(scene.step);
    let meshes: Vec<Value> =
        scene.surfaces.iter().map(|(name, mesh)| mesh_entry(name, mesh, None)).collect::<Result<_>>()?;
    page(title, json!({ "kind": "models", "grid": baked, "meshes": meshes }))
}

/// Voxels along the longest side of a fill's baked 3D texture, unless asked otherwise.
pub const FILL_RES: usize = 128;

/// The page of filled models, each (name, model, colour textures), baked at `res` voxels
/// along the longest side of their box: (page, the baked grid's dims).
pub fn fill_page(
    title: &str,
    models: &[(&str, &LstModel, &Textures)],
    res: usize,
    budget: u64,
) -> Result<(String, [usize; 3])> {
    let pairs: Vec<(&LstModel, &Textures)> = models.iter().map(|(_, m, t)| (*m, *t)).collect();
    let baked = render::bake(&pairs, &[], res, budget)?;
    let (lo, step) = render::bake_grid(&pairs, res);
    let surfaces = models.iter().map(|(name, m, _)| (name.to_string(), &m.surface)).collect();
    let page = models_page(title, &ModelScene { baked: &baked, lo, step, surfaces })?;
    Ok((page, baked.dims()))
}

/// A page of one skin: a mesh with a colour per vertex.
pub fn skin_page(title: &str, mesh: &Mesh, colours: &[[f32; 3]]) -> Result<String> {
    if colours.len() != mesh.vertices.len() {
        return Err(Error::invalid(format!(
            "the skin has {} colours for {} vertices",
            colours.len(),
            mesh.vertices.len()
        )));
    }
    let skin = mesh_entry(title, mesh, Some(colours))?;
    page(title, json!({ "kind": "skin", "meshes": [skin] }))
}

/// The HTML page: the template with the title, the script and the data filled in.
fn page(title: &str, data: Value) -> Result<String> {
    let data = json!({ "title": title, "scene": data });
    // Inside a script element "</script" would end it; JSON may spell "<" as \u003c.
    let text = serde_json::to_string(&data).map_err(|e| Error::invalid(e.to_string()))?.replace('<', "\\u003c");
    let escaped = title.replace('&', "&amp;").replace('<', "&lt;");
    Ok(filled(TEMPLATE, &[("{{TITLE}}", &escaped), ("{{DATA}}", &text), ("{{SCRIPT}}", SCRIPT)]))
}

/// `template` with each marker replaced, in order, by its text; a marker is looked for
/// only in the template, never in text already put in.
fn filled(template: &str, parts: &[(&str, &str)]) -> String {
    let mut out = String::with_capacity(template.len() + parts.iter().map(|(_, t)| t.len()).sum::<usize>());
    let mut rest = template;
    for (marker, text) in parts {
        let (before, after) = rest.split_once(marker).expect("the viewer template holds each marker once, in order");
        out += before;
        out += text;
        rest = after;
    }
    out + rest
}

/// A grid's description and data: its layers (RGB together, every other channel alone).
fn grid(name: &str, volume: &Volume) -> Result<Value> {
    let channels = volume.channels();
    let names: Vec<&str> = channels.iter().map(Channel::name).collect();
    let rgb = [Channel::R, Channel::G, Channel::B].map(|c| channels.iter().position(|x| *x == c));
    let mut layers = Vec::new();
    if let [Some(r), Some(g), Some(b)] = rgb {
        layers.push(json!({ "name": "RGB", "planes": [r, g, b] }));
    }
    for (i, name) in names.iter().enumerate() {
        if !rgb.contains(&Some(i)) {
            layers.push(json!({ "name": name, "planes": [i] }));
        }
    }
    Ok(json!({
        "name": name,
        "dims": volume.dims(),
        "channels": names,
        "layers": layers,
        "data": base64(&packed(&planes(volume))?),
    }))
}

/// The volume's samples as bytes, one plane per channel.
fn planes(volume: &Volume) -> Vec<u8> {
    let n = volume.channel_count();
    let voxels = volume.data().len() / n.max(1);
    let mut out = vec![0u8; volume.data().len()];
    for (v, samples) in volume.data().chunks_exact(n).enumerate() {
        for (c, s) in samples.iter().enumerate() {
            out[c * voxels + v] = to_u8(*s);
        }
    }
    out
}

/// A mesh's description and data: positions (f32 x, y, z), triangles (u32), and for a
/// skin a colour per vertex (u8 r, g, b).
fn mesh_entry(name: &str, mesh: &Mesh, colours: Option<&[[f32; 3]]>) -> Result<Value> {
    let mut bytes = Vec::with_capacity(mesh.vertices.len() * 15 + mesh.triangles.len() * 12);
    for v in &mesh.vertices {
        v.to_array().iter().for_each(|c| bytes.extend_from_slice(&c.to_le_bytes()));
    }
    for t in &mesh.triangles {
        t.iter().for_each(|i| bytes.extend_from_slice(&i.to_le_bytes()));
    }
    if let Some(colours) = colours {
        colours.iter().for_each(|c| bytes.extend(c.map(to_u8)));
    }
    Ok(json!({
        "name": name,
        "vertices": mesh.vertices.len(),
        "triangles": mesh.triangles.len(),
        "coloured": colours.is_some(),
        "data": base64(&packed(&bytes)?),
    }))
}

/// zlib at the best compression.
fn packed(bytes: &[u8]) -> Result<Vec<u8>> {
    let mut encoder = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    encoder.write_all(bytes).and_then(|_| encoder.finish()).map_err(|e| Error::invalid(format!("compressing: {e}")))
}

fn base64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    fn unpacked(text: &str) -> Vec<u8> {
        let bytes = base64::engine::general_purpose::STANDARD.decode(text).unwrap();
        let mut out = Vec::new();
        flate2::read::ZlibDecoder::new(&bytes[..]).read_to_end(&mut out).unwrap();
        out
    }

    /// The JSON the page embeds.
    fn data_of(page: &str) -> Value {
        let start = page.find("id=solidtex-data>").unwrap() + "id=solidtex-data>".len();
        let end = start + page[start..].find("</script>").unwrap();
        serde_json::from_str(&page[start..end]).unwrap()
    }

    #[test]
    fn a_volume_page_holds_each_channel_as_a_plane_of_bytes() {
        let dims = [3, 2, 2];
        let data: Vec<f32> = (0..12).flat_map(|i| [i as f32 / 11.0, 0.5, 1.0, 0.25]).collect();
        let channels = vec![Channel::R, Channel::G, Channel::B, Channel::Depth];
        let volume = Volume::from_data(dims, channels, data).unwrap();
        let page = volumes_page("a <b>", &[NamedVolume { name: "v".into(), volume: &volume }]).unwrap();
        assert!(page.contains("<title>a &lt;b></title>"), "the title is escaped");
        let data = data_of(&page);
        let grid = &data["scene"]["volumes"][0];
        assert_eq!(grid["dims"], json!([3, 2, 2]));
        assert_eq!(grid["layers"], json!([{ "name": "RGB", "planes": [0, 1, 2] }, { "name": "Depth", "planes": [3] }]));
        let bytes = unpacked(grid["data"].as_str().unwrap());
        assert_eq!(bytes.len(), 48);
        let red: Vec<u8> = (0..12).map(|i| to_u8(i as f32 / 11.0)).collect();
        assert_eq!(&bytes[..12], &red[..]);
        assert!(bytes[12..24].iter().all(|b| *b == 128) && bytes[36..].iter().all(|b| *b == 64));
    }

    #[test]
    fn a_large_volume_is_shown_at_every_kth_voxel() {
        let data = (0..5 * 3 * 2).map(|i| i as f32).collect();
        let volume = Volume::from_data([5, 3, 2], vec![Channel::R], data).unwrap();
        let (same, k) = within_side(&volume, 5).unwrap();
        assert_eq!((same.dims(), k), ([5, 3, 2], 1));
        let (small, k) = within_side(&volume, 2).unwrap();
        assert_eq!((small.dims(), k), ([2, 1, 1], 3));
        assert_eq!(small.data(), [0.0, 3.0]);
    }

    #[test]
    fn a_name_cannot_end_the_data_script() {
        let volume = Volume::from_data([1, 1, 1], vec![Channel::R], vec![0.0]).unwrap();
        let page = volumes_page("t", &[NamedVolume { name: "</script><b>".into(), volume: &volume }]).unwrap();
        assert_eq!(data_of(&page)["scene"]["volumes"][0]["name"], "</script><b>");
    }

    #[test]
    fn a_skin_carries_a_colour_per_vertex() {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        let colours = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let page = skin_page("s", &mesh, &colours).unwrap();
        let skin = &data_of(&page)["scene"]["meshes"][0];
        let bytes = unpacked(skin["data"].as_str().unwrap());
        assert_eq!(bytes.len(), 36 + 12 + 9);
        assert_eq!(f32::from_le_bytes(bytes[12..16].try_into().unwrap()), 1.0);
        assert_eq!(u32::from_le_bytes(bytes[44..48].try_into().unwrap()), 2);
        assert_eq!(&bytes[48..], &[255, 0, 0, 0, 255, 0, 0, 0, 255]);
        assert!(skin_page("s", &mesh, &colours[..2]).is_err());
    }
}
