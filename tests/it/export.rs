//! `solidtex export`: glTF binaries of filled models (and skins) that the Khronos glTF
//! validator accepts, whose vertex colours and atlas texels are the colours `view` shows
//! at those points.

use crate::fill::{TRUNK, fill, filled, kiwi_fruit};
use crate::support::{assert_fails, assert_usage, at, solidtex, stderr};
use glam::Vec3;
use serde_json::Value;
use solidtex::fill::render::{self, Textures};
use solidtex::io::gltf;
use std::path::Path;
use std::process::Command;

/// Runs the Khronos glTF validator (tests/gltf, `npm ci --prefix tests/gltf`) on `files`:
/// every one must have no error. Under CI a missing validator fails the test.
fn validated(files: &[&str]) {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/gltf");
    if !folder.join("node_modules/gltf-validator").exists() {
        assert!(std::env::var_os("CI").is_none(), "the glTF validator is not installed: npm ci --prefix tests/gltf");
        eprintln!("skipping the glTF validator (not installed: npm ci --prefix tests/gltf)");
        return;
    }
    let run = Command::new("node").arg(folder.join("validate.js")).args(files).output().expect("node runs");
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "the glTF validator found errors:\n{said}{}", String::from_utf8_lossy(&run.stderr));
    assert_eq!(said.lines().count(), files.len(), "{said}");
}

/// A parsed `.glb`: its JSON and binary chunk.
struct Glb {
    doc: Value,
    bin: Vec<u8>,
}

impl Glb {
    fn read(path: &str) -> Glb {
        let (doc, bin) = gltf::parse_glb(&std::fs::read(path).unwrap()).unwrap();
        Glb { doc, bin }
    }

    /// The bytes of a buffer view.
    fn view(&self, index: u64) -> &[u8] {
        let view = &self.doc["bufferViews"][index as usize];
        let (offset, length) = (view["byteOffset"].as_u64().unwrap_or(0), view["byteLength"].as_u64().unwrap());
        &self.bin[offset as usize..(offset + length) as usize]
    }

    /// Accessor `index` as little-endian 4-byte values (floats or u32 bits).
    fn words(&self, index: &Value) -> Vec<[u8; 4]> {
        let accessor = &self.doc["accessors"][index.as_u64().unwrap() as usize];
        assert!(matches!(accessor["componentType"].as_u64(), Some(5126 | 5125)));
        let bytes = self.view(accessor["bufferView"].as_u64().unwrap());
        bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
    }

    fn floats(&self, index: &Value) -> Vec<f32> {
        self.words(index).into_iter().map(f32::from_le_bytes).collect()
    }

    fn vec3(&self, index: &Value) -> Vec<Vec3> {
        self.floats(index).chunks_exact(3).map(Vec3::from_slice).collect()
    }

    fn triangles(&self, primitive: &Value) -> Vec<[u32; 3]> {
        let words: Vec<u32> = self.words(&primitive["indices"]).into_iter().map(u32::from_le_bytes).collect();
        words.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
    }

    fn primitive(&self, mesh: usize) -> &Value {
        &self.doc["meshes"][mesh]["primitives"][0]
    }
}

/// The sRGB-encoded value of a linear glTF colour.
fn srgb(linear: f32) -> f32 {
    if linear <= 0.003_130_8 { linear * 12.92 } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 }
}

/// A model's textures, read as the command line reads them.
fn textures(model: &str) -> (solidtex::fill::LstModel, Textures) {
    let lst = solidtex::io::lst_file::read_lst(Path::new(model)).unwrap();
    let base = Path::new(model).parent().unwrap();
    let colour: Vec<solidtex::Volume> =
        lst.sources.iter().map(|s| solidtex::io::read_volume(&base.join(&s.volume), u64::MAX).unwrap()).collect();
    let masks: Vec<solidtex::Volume> =
        lst.sources.iter().map(|s| solidtex::library::fill::load_mask(&s.mask, base).unwrap()).collect();
    let textures = Textures::new(&colour, &masks);
    (lst, textures)
}

/// The largest difference, over the channels, between the view's colour at `p` and `rgb`.
fn off(model: &solidtex::fill::LstModel, textures: &Textures, p: Vec3, rgb: [f32; 3]) -> f32 {
    let shown = render::shade_point(model, textures, p).expect("a surface point is located");
    (0..3).map(|c| (shown[c] - rgb[c]).abs()).fold(0.0, f32::max)
}

#[test]
fn an_exported_model_has_the_views_colours_at_its_vertices_and_passes_the_validator() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // marble: a texture whose colour changes everywhere on the surface
    let model = filled(d, "fruit", "marble", "exemplar = \"marble\"\nseed = 1\ntets = 3000\n");
    let out = at(d, "marble.glb");
    let run = solidtex(&["export", &model, "-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("vertex colours"), "{}", stderr(&run));
    let glb = Glb::read(&out);
    assert_eq!(glb.doc["asset"]["extras"]["models"][0]["exemplars"][0], "marble");
    let primitive = glb.primitive(0);
    let (positions, colours) =
        (glb.vec3(&primitive["attributes"]["POSITION"]), glb.vec3(&primitive["attributes"]["COLOR_0"]));
    let triangles = glb.triangles(primitive);
    assert_eq!(positions.len(), colours.len());
    assert!(triangles.len() > 50_000, "split to about two pixels of a 512 view: {} triangles", triangles.len());
    // edges about the stated length: none longer than 4/3 of it
    let edge = glb.doc["asset"]["extras"]["edge"].as_f64().unwrap() as f32;
    let length = |t: &[u32; 3], k: usize| positions[t[k] as usize].distance(positions[t[(k + 1) % 3] as usize]);
    let lengths: Vec<f32> = triangles.iter().flat_map(|t| (0..3).map(move |k| length(t, k))).collect();
    let longest = lengths.iter().copied().fold(0.0, f32::max);
    let mean = lengths.iter().sum::<f32>() / lengths.len() as f32;
    assert!(
        longest <= edge * 4.0 / 3.0 * 1.001 && mean > 0.5 * edge,
        "edges {mean} on average, {longest} at most; {edge} asked"
    );
    // the fruit is smooth and closed: split and merged, every edge joins two triangles
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    let runs: Vec<usize> = edges.chunk_by(|a, b| a == b).map(<[_]>::len).collect();
    assert!(
        runs.iter().all(|n| *n == 2),
        "{} edges not shared by two triangles",
        runs.iter().filter(|n| **n != 2).count()
    );
    // the colours are the view's at the vertices (stored linear, as glTF asks)
    let (lst, textures) = textures(&model);
    let mut worst = 0.0f32;
    for (p, c) in positions.iter().zip(&colours).step_by(97) {
        worst = worst.max(off(&lst, &textures, *p, c.to_array().map(srgb)));
    }
    assert!(worst <= 2.0 / 255.0, "a vertex colour is {:.1}/255 off the view's", worst * 255.0);
    let stored_as_is = positions.iter().zip(&colours).step_by(97).map(|(p, c)| off(&lst, &textures, *p, c.to_array()));
    assert!(stored_as_is.fold(0.0, f32::max) > 8.0 / 255.0, "the colours are stored linear, not as sRGB");
    // the vertices lie on the input surface
    let surface = &lst.surface;
    let on_surface = |p: Vec3| {
        (surface.triangles.iter())
            .map(|t| p.distance(solidtex::mesh::closest_on_triangle(p, t.map(|v| surface.vertices[v as usize]))))
            .fold(f32::INFINITY, f32::min)
    };
    assert!(positions.iter().step_by(997).all(|p| on_surface(*p) < 1e-5));
    // an atlas: each texel is the view's colour at the surface point it maps to
    let atlas = at(d, "atlas.glb");
    let run = solidtex(&["export", &model, "--atlas", "2048", "-o", &atlas]);
    assert!(run.status.success(), "{}", stderr(&run));
    atlas_matches_the_view(&Glb::read(&atlas), &lst, &textures);
    validated(&[&out, &atlas]);
}

/// Every 7th triangle of an atlas export: the texels at two points inside it hold the
/// view's colour at the surface points the texels' centres map to.
fn atlas_matches_the_view(glb: &Glb, lst: &solidtex::fill::LstModel, textures: &Textures) {
    let primitive = glb.primitive(0);
    assert!(primitive["attributes"].get("COLOR_0").is_none(), "an atlas replaces vertex colours");
    let positions = glb.vec3(&primitive["attributes"]["POSITION"]);
    let uvs: Vec<[f32; 2]> =
        glb.floats(&primitive["attributes"]["TEXCOORD_0"]).chunks_exact(2).map(|c| [c[0], c[1]]).collect();
    let image = &glb.doc["images"][0];
    assert_eq!(image["mimeType"], "image/png");
    let picture = image::load_from_memory(glb.view(image["bufferView"].as_u64().unwrap())).unwrap().to_rgb8();
    let side = picture.width() as f32;
    let triangles = glb.triangles(primitive);
    assert_eq!(triangles.len(), lst.surface.triangles.len(), "--atlas alone keeps the input triangles");
    let mut worst = 0.0f32;
    for (t, inside) in triangles.iter().step_by(7).flat_map(|t| [[0.6, 0.3, 0.1], [0.15, 0.25, 0.6]].map(|b| (t, b))) {
        let (p, uv) = (t.map(|v| positions[v as usize]), t.map(|v| uvs[v as usize]));
        // the texel holding a point inside the triangle, and where its centre lies in it
        let point_uv = [0, 1].map(|k| (uv[0][k] * inside[0] + uv[1][k] * inside[1] + uv[2][k] * inside[2]) * side);
        let texel = point_uv.map(|c| c.floor());
        let q = texel.map(|c| (c + 0.5) / side);
        let (e1, e2) = ([uv[1][0] - uv[0][0], uv[1][1] - uv[0][1]], [uv[2][0] - uv[0][0], uv[2][1] - uv[0][1]]);
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        let r = [q[0] - uv[0][0], q[1] - uv[0][1]];
        let (s, w) = ((r[0] * e2[1] - r[1] * e2[0]) / det, (e1[0] * r[1] - e1[1] * r[0]) / det);
        let point = p[0] + (p[1] - p[0]) * s + (p[2] - p[0]) * w;
        let stored = picture.get_pixel(texel[0] as u32, texel[1] as u32).0.map(|c| c as f32 / 255.0);
        worst = worst.max(off(lst, textures, point, stored));
    }
    assert!(worst <= 2.0 / 255.0, "an atlas texel is {:.1}/255 off the view's colour", worst * 255.0);
}

#[test]
fn several_models_a_relief_and_a_skin_export_and_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let log = filled(d, "log", "trunk", TRUNK);
    let (fruit, kiwi) = kiwi_fruit(d);
    fill(d, &fruit, &kiwi, "kiwi.lst");
    let kiwi = at(d, "kiwi.lst");
    // two models: two meshes, named after their files
    let both = at(d, "both.glb");
    let run = solidtex(&["export", &log, &kiwi, "--edge", "0.05", "-o", &both]);
    assert!(run.status.success(), "{}", stderr(&run));
    let glb = Glb::read(&both);
    let names: Vec<&str> = (0..2).map(|i| glb.doc["nodes"][i]["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["trunk", "kiwi"]);
    assert_eq!(glb.doc["meshes"].as_array().unwrap().len(), 2);
    // --edge 0 keeps the input triangles, and says so rather than an edge of length 0
    let kept = at(d, "kept.glb");
    let run = solidtex(&["export", &kiwi, "--edge", "0", "-o", &kept]);
    assert!(run.status.success() && stderr(&run).contains("the input surface's own triangles"), "{}", stderr(&run));
    let run = solidtex(&["export", &kiwi, "--edge", "1e30", "-o", &kept]);
    assert!(stderr(&run).contains("own triangles (none longer than --edge"), "{}", stderr(&run));
    // the relief moves the log's vertices along their normals by at most half the scale
    let (flat, raised) = (at(d, "flat.glb"), at(d, "raised.glb"));
    assert!(solidtex(&["export", &log, "--edge", "0.05", "-o", &flat]).status.success());
    let run = solidtex(&["export", &log, "--edge", "0.05", "--displacement", "0.1", "-o", &raised]);
    assert!(run.status.success(), "{}", stderr(&run));
    let (a, b) = (Glb::read(&flat), Glb::read(&raised));
    let (p, q) = (a.vec3(&a.primitive(0)["attributes"]["POSITION"]), b.vec3(&b.primitive(0)["attributes"]["POSITION"]));
    assert_eq!(p.len(), q.len(), "the same split surface");
    let moved: Vec<f32> = p.iter().zip(&q).map(|(x, y)| x.distance(*y)).collect();
    assert!(moved.iter().all(|m| *m <= 0.05 + 1e-5), "moved {}", moved.iter().fold(0.0f32, |a, b| a.max(*b)));
    let share = moved.iter().filter(|m| **m > 0.005).count() as f64 / moved.len() as f64;
    assert!(share > 0.3, "{share} of the vertices moved by more than a tenth of the relief");
    // a skin exports as it is
    let skin = at(d, "skin.ply");
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    assert!(solidtex(&["surface", &fruit, "--exemplar", photo, "--points", "2000", "-o", &skin]).status.success());
    let skin_glb = at(d, "skin.glb");
    let run = solidtex(&["export", &skin, "-o", &skin_glb]);
    assert!(run.status.success(), "{}", stderr(&run));
    validated(&[&both, &flat, &raised, &skin_glb]);
    // bad input: a clear error, nothing written
    let bad = at(d, "bad.glb");
    assert_fails(&solidtex(&["export", &kiwi, "--displacement", "0.1", "-o", &bad]), &["kiwi.exr", "Displacement"]);
    assert_usage(&solidtex(&["export", &kiwi, "--edge", "-1", "-o", &bad]), &["--edge", "-1", "positive length"]);
    assert_usage(&solidtex(&["export", &kiwi, "--edge", "0.00001", "-o", &bad]), &["--edge", "triangles"]);
    assert_usage(&solidtex(&["export", &kiwi, "--atlas", "10", "-o", &bad]), &["--atlas"]);
    assert_usage(&solidtex(&["export", &kiwi, "--atlas", "64", "--edge", "0.02", "-o", &bad]), &["atlas"]);
    assert_usage(&solidtex(&["export", &skin, "--edge", "0.1", "-o", &bad]), &["skin"]);
    assert_usage(&solidtex(&["export", &skin, "--crease", "10", "-o", &bad]), &["skin", "--crease"]);
    assert_usage(&solidtex(&["export", &skin, &kiwi, "-o", &bad]), &["skin.ply", "a skin (.ply) is exported alone"]);
    assert_usage(&solidtex(&["export", &kiwi, "-o", &at(d, "kiwi.png")]), &[".glb"]);
    let before = std::fs::read(&kiwi).unwrap();
    let renamed = at(d, "model.glb");
    std::fs::copy(&kiwi, &renamed).unwrap();
    assert_usage(&solidtex(&["export", &renamed, "-o", &renamed]), &["input"]);
    assert_eq!(std::fs::read(&renamed).unwrap(), before, "the input named as the output is kept as it was");
    assert_eq!(std::fs::read(&kiwi).unwrap(), before);
    assert!(!Path::new(&bad).exists());
}
