//! glTF 2.0 binary files (`.glb`) of coloured triangle meshes: one JSON chunk, one binary
//! chunk, each mesh its own node (a cake's models stay apart).
//!
//! | attribute    | stored as                         | from                                |
//! |--------------|-----------------------------------|-------------------------------------|
//! | `POSITION`   | float x 3, with min and max       | model units, written as metres      |
//! | `NORMAL`     | float x 3, unit length            | the smooth normals `view` shades by |
//! | `COLOR_0`    | float x 3, **linear** (glTF's rule) | the sRGB colours `view` shows     |
//! | `TEXCOORD_0` | float x 2 (with an atlas, instead of `COLOR_0`) | the atlas cell corners |
//! | indices      | unsigned int                      | outward, counter-clockwise          |
//!
//! An atlas is embedded as a PNG (sRGB, as glTF's base colour textures are), sampled
//! linearly without mipmaps (a lower mip level would blend neighbouring cells). Axes are
//! the models' own: solidtex's up is +y, as glTF's.

use crate::error::{Error, Result};
use crate::fill::export::Exported;
use serde_json::{Value, json};
use std::path::Path;

/// One mesh of the file.
pub struct Part<'a> {
    /// The node's and mesh's name.
    pub name: String,
    /// The mesh.
    pub mesh: &'a Exported,
}

const MAGIC: u32 = 0x4654_6C67; // "glTF"
const JSON_CHUNK: u32 = 0x4E4F_534A; // "JSON"
const BIN_CHUNK: u32 = 0x004E_4942; // "BIN\0"
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const LINEAR: u32 = 9729;
const CLAMP_TO_EDGE: u32 = 33071;

/// The glTF colour of an sRGB-encoded value (0–1): linear, as `COLOR_0` holds.
pub fn linear(srgb: f32) -> f32 {
    if srgb <= 0.04045 { srgb / 12.92 } else { ((srgb + 0.055) / 1.055).powf(2.4) }
}

/// The binary chunk and the JSON lists that point into it.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// Appends `bytes` (4-byte aligned) as a buffer view; its index.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(view);
        self.views.len() - 1
    }

    /// A float accessor of `width` components (`kind`: "VEC2", "VEC3"), with min and max
    /// when `bounds`; its index.
    fn floats(&mut self, values: &[f32], width: usize, kind: &str, bounds: bool) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ARRAY_BUFFER));
        let mut accessor =
            json!({ "bufferView": view, "componentType": FLOAT, "count": values.len() / width, "type": kind });
        if bounds {
            let (lo, hi): (Vec<f32>, Vec<f32>) = (0..width)
                .map(|k| {
                    let column = values.iter().skip(k).step_by(width);
                    column.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)))
                })
                .unzip();
            accessor["min"] = json!(lo);
            accessor["max"] = json!(hi);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    fn indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = triangles.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        let count = 3 * triangles.len();
        self.accessors
            .push(json!({ "bufferView": view, "componentType": UNSIGNED_INT, "count": count, "type": "SCALAR" }));
        self.accessors.len() - 1
    }
}

/// The `.glb` bytes of `parts`, with `extras` (name, provenance) in the asset.
pub fn glb(parts: &[Part], extras: Value) -> Result<Vec<u8>> {
    let mut b = Builder::default();
    let (mut meshes, mut materials, mut textures, mut images) = (vec![], vec![], vec![], vec![]);
    for part in parts {
        let mesh = part.mesh;
        let flat = |v: &[glam::Vec3]| -> Vec<f32> { v.iter().flat_map(|p| p.to_array()).collect() };
        let mut attributes = json!({
            "POSITION": b.floats(&flat(&mesh.positions), 3, "VEC3", true),
            "NORMAL": b.floats(&flat(&mesh.normals), 3, "VEC3", false),
        });
        let mut material = json!({
            "name": part.name,
            "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9 },
        });
        match &mesh.atlas {
            None => {
                let colours: Vec<f32> = mesh.colours.iter().flatten().map(|c| linear(*c)).collect();
                attributes["COLOR_0"] = json!(b.floats(&colours, 3, "VEC3", false));
            }
            Some(atlas) => {
                let uvs: Vec<f32> = atlas.uvs.iter().flatten().copied().collect();
                attributes["TEXCOORD_0"] = json!(b.floats(&uvs, 2, "VEC2", false));
                let png = super::png_file::rgb8_bytes(&atlas.picture)?;
                images.push(json!({ "bufferView": b.view(&png, None), "mimeType": "image/png", "name": part.name }));
                textures.push(json!({ "sampler": 0, "source": images.len() - 1 }));
                material["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": textures.len() - 1 });
            }
        }
        let indices = b.indices(&mesh.triangles);
        materials.push(material);
        let primitive =
            json!({ "attributes": attributes, "indices": indices, "material": materials.len() - 1, "mode": 4 });
        meshes.push(json!({ "name": part.name, "primitives": [primitive] }));
    }
    let nodes: Vec<Value> = parts.iter().enumerate().map(|(i, p)| json!({ "mesh": i, "name": p.name })).collect();
    let generator = format!("solidtex {}", env!("CARGO_PKG_VERSION"));
    let mut document = json!({
        "asset": { "version": "2.0", "generator": generator, "extras": extras },
        "scene": 0,
        "scenes": [{ "nodes": (0..parts.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{ "byteLength": b.bin.len() }],
    });
    if !images.is_empty() {
        document["images"] = json!(images);
        document["textures"] = json!(textures);
        document["samplers"] =
            json!([{ "magFilter": LINEAR, "minFilter": LINEAR, "wrapS": CLAMP_TO_EDGE, "wrapT": CLAMP_TO_EDGE }]);
    }
    container(document.to_string().into_bytes(), b.bin)
}

/// The `.glb` container around a JSON text and a binary buffer.
fn container(mut text: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>> {
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let length = u32::try_from(total)
        .map_err(|_| Error::invalid(format!("a .glb holds at most 4 GiB; these meshes need {total} bytes")))?;
    let mut out = Vec::new();
    out.try_reserve_exact(total).map_err(|_| Error::invalid(format!("no memory for a {total}-byte .glb")))?;
    for word in [MAGIC, 2, length, text.len() as u32, JSON_CHUNK] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&text);
    for word in [bin.len() as u32, BIN_CHUNK] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&bin);
    Ok(out)
}

/// Writes `parts` to `path` as a `.glb` (atomically).
pub fn write_glb(path: &Path, parts: &[Part], extras: Value) -> Result<()> {
    super::atomic::write_bytes(path, &glb(parts, extras)?)
}

/// The JSON document and the binary chunk of a `.glb`'s bytes.
pub fn parse_glb(bytes: &[u8]) -> Result<(Value, Vec<u8>)> {
    let bad = |why: &str| Error::invalid(format!("not a glTF binary: {why}"));
    let word = |at: usize| -> Result<u32> {
        let four = bytes.get(at..at + 4).ok_or_else(|| bad("it ends early"))?;
        Ok(u32::from_le_bytes([four[0], four[1], four[2], four[3]]))
    };
    if word(0)? != MAGIC || word(4)? != 2 {
        return Err(bad("no glTF 2 header"));
    }
    let (json_length, json_type) = (word(12)? as usize, word(16)?);
    let text =
        bytes.get(20..20 + json_length).filter(|_| json_type == JSON_CHUNK).ok_or_else(|| bad("no JSON chunk"))?;
    let document: Value = serde_json::from_slice(text).map_err(|e| bad(&format!("its JSON: {e}")))?;
    let at = 20 + json_length;
    let bin = match bytes.len() > at {
        true if word(at + 4)? == BIN_CHUNK => {
            bytes.get(at + 8..at + 8 + word(at)? as usize).ok_or_else(|| bad("the binary chunk ends early"))?.to_vec()
        }
        _ => Vec::new(),
    };
    Ok((document, bin))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn triangle() -> Exported {
        Exported {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            colours: vec![[0.0; 3], [0.5; 3], [1.0, 0.2, 0.04]],
            triangles: vec![[0, 1, 2]],
            atlas: None,
        }
    }

    #[test]
    fn a_glb_holds_the_mesh_in_linear_colours_and_reads_back() {
        let mesh = triangle();
        let parts = [Part { name: "a".into(), mesh: &mesh }, Part { name: "b".into(), mesh: &mesh }];
        let bytes = glb(&parts, json!({ "model": "x.lst" })).unwrap();
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize, bytes.len());
        let (doc, bin) = parse_glb(&bytes).unwrap();
        assert_eq!(doc["asset"]["version"], "2.0");
        assert_eq!(doc["asset"]["extras"]["model"], "x.lst");
        assert_eq!(doc["meshes"].as_array().unwrap().len(), 2, "one mesh per part");
        assert_eq!(doc["accessors"][0]["max"], json!([1.0, 1.0, 0.0]));
        let colour =
            &doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"].as_u64().unwrap() as usize];
        let view = &doc["bufferViews"][colour["bufferView"].as_u64().unwrap() as usize];
        let at = view["byteOffset"].as_u64().unwrap() as usize + 24;
        let red = f32::from_le_bytes(bin[at..at + 4].try_into().unwrap());
        assert!((red - 1.0).abs() < 1e-6);
        let green = f32::from_le_bytes(bin[at + 4..at + 8].try_into().unwrap());
        assert!((green - linear(0.2)).abs() < 1e-7 && green < 0.05, "stored linear: {green}");
        assert!(parse_glb(&bytes[..30]).is_err());
        assert!(parse_glb(b"not a glb at all, not at all").is_err());
    }
}
