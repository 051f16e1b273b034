//! Mesh files: OBJ, STL (ascii and binary), PLY (ascii and binary) into [`crate::mesh::Mesh`].
//!
//! | extension | reading                                        | writing            |
//! |-----------|------------------------------------------------|--------------------|
//! | `.obj`    | `v` and `f` lines (`i`, `i/t`, `i//n`, `i/t/n`, negative indices); the rest is ignored | `v`, `f` |
//! | `.stl`    | binary, or ASCII when it starts with `solid` and has no NUL byte; equal corners are welded | binary |
//! | `.ply`    | `ascii` and `binary_little_endian`; `vertex` x, y, z and the `face` list `vertex_indices` (or `vertex_index`); other elements and properties are skipped | ascii |
//!
//! Extensions are matched in any case. Polygons with more than three corners are
//! fan-triangulated. Our own parsers: each format needs a page of code, and the crates
//! differ in how they report errors (we name the file, the line or item, and the problem).

use super::atomic::{read_bytes, write_bytes};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Corners and triangles as read, before [`Mesh::new`] checks them.
#[derive(Default)]
struct Soup {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per-vertex colours in [0, 1] (PLY `red`, `green`, `blue`), when the file has them.
    colours: Option<Vec<[f32; 3]>>,
}

impl Soup {
    /// Add a polygon as a fan of triangles around its first corner.
    fn push_polygon(&mut self, corners: &[u32]) {
        for pair in corners[1..].windows(2) {
            self.triangles.push([corners[0], pair[0], pair[1]]);
        }
    }
}

#[derive(Clone, Copy)]
enum Kind {
    Obj,
    Stl,
    Ply,
}

const ALLOWED: &str = "allowed: .obj, .stl, .ply (any case)";

fn kind_of(path: &Path) -> Result<Kind> {
    match path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()) {
        Some(e) if e == "obj" => Ok(Kind::Obj),
        Some(e) if e == "stl" => Ok(Kind::Stl),
        Some(e) if e == "ply" => Ok(Kind::Ply),
        Some(e) => Err(Error::file(path, format!("unknown mesh extension .{e}; {ALLOWED}"))),
        None => Err(Error::file(path, format!("a mesh file needs an extension; {ALLOWED}"))),
    }
}

/// Read a triangle mesh, choosing the format by the extension (`.obj`, `.stl`, `.ply`).
pub fn read_mesh(path: &Path) -> Result<Mesh> {
    let kind = kind_of(path)?;
    let bytes = read_bytes(path)?;
    let soup = match kind {
        Kind::Obj => parse_obj(&bytes),
        Kind::Stl => parse_stl(&bytes),
        Kind::Ply => parse_ply(&bytes),
    }
    .map_err(|e| e.in_file(path))?;
    let mesh = Mesh::new(soup.vertices, soup.triangles).map_err(|e| e.in_file(path))?;
    let (lo, hi) = mesh.bounds();
    let across = lo.distance(hi);
    if !SIZES.contains(&across) {
        return Err(Error::file(
            path,
            format!(
                "is {across:.3e} units across (the diagonal of its box); solidtex takes meshes {:.0e} to {:.0e} units \
                 across: scale it (e.g. to metres or millimetres)",
                SIZES.start(),
                SIZES.end()
            ),
        ));
    }
    Ok(mesh)
}

/// How large a mesh may be, the diagonal of its box in its own units: far outside, the
/// mesher's and the surface matching's tolerances (near single precision's) break, and a
/// tet mesh or a skin comes out wrong or not at all.
pub const SIZES: std::ops::RangeInclusive<f32> = 1e-6..=1e8;

/// A mesh with one colour per vertex (in [0, 1]).
#[derive(Debug, Clone, PartialEq)]
pub struct ColouredMesh {
    /// The mesh.
    pub mesh: Mesh,
    /// One RGB colour per vertex of `mesh`.
    pub colours: Vec<[f32; 3]>,
}

/// Read a `.ply` whose vertices carry `red`, `green` and `blue`.
pub fn read_coloured_ply(path: &Path) -> Result<ColouredMesh> {
    if !matches!(kind_of(path)?, Kind::Ply) {
        return Err(Error::file(path, "a mesh with vertex colours must be a .ply file"));
    }
    let soup = parse_ply(&read_bytes(path)?).map_err(|e| e.in_file(path))?;
    let colours = soup.colours.ok_or_else(|| {
        Error::file(
            path,
            "the PLY vertices have no colours (properties red, green and blue); solidtex surface writes them",
        )
    })?;
    let mesh = Mesh::new(soup.vertices, soup.triangles).map_err(|e| e.in_file(path))?;
    Ok(ColouredMesh { mesh, colours })
}

/// Write a binary little-endian PLY with vertex colours (`uchar red, green, blue`),
/// atomically.
pub fn write_coloured_ply(path: &Path, coloured: &ColouredMesh) -> Result<()> {
    let ColouredMesh { mesh, colours } = coloured;
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by solidtex {}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        env!("CARGO_PKG_VERSION"),
        mesh.vertices.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    for (v, c) in mesh.vertices.iter().zip(colours) {
        for x in v.to_array() {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
        bytes.extend(c.map(crate::render::to_u8));
    }
    for t in &mesh.triangles {
        bytes.push(3);
        for i in t {
            bytes.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    write_bytes(path, &bytes)
}

/// Write a triangle mesh in the format the extension names: `.obj`, binary `.stl` or
/// ASCII `.ply` (atomically).
pub fn write_mesh(path: &Path, mesh: &Mesh) -> Result<()> {
    match kind_of(path)? {
        Kind::Obj => write_obj(path, mesh),
        Kind::Stl => write_stl(path, mesh),
        Kind::Ply => write_ply(path, mesh),
    }
}

/// Write `mesh` as a Wavefront OBJ (atomically).
pub fn write_obj(path: &Path, mesh: &Mesh) -> Result<()> {
    let mut text = format!(
        "# written by solidtex {}: {} vertices, {} triangles\n",
        env!("CARGO_PKG_VERSION"),
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    for v in &mesh.vertices {
        text.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
    }
    for [a, b, c] in &mesh.triangles {
        text.push_str(&format!("f {} {} {}\n", a + 1, b + 1, c + 1));
    }
    write_bytes(path, text.as_bytes())
}

/// Write `mesh` as a binary STL (atomically); the normals are the unit face normals.
pub fn write_stl(path: &Path, mesh: &Mesh) -> Result<()> {
    let count = u32::try_from(mesh.triangles.len())
        .map_err(|_| Error::file(path, "binary STL holds at most 4294967295 triangles"))?;
    let mut bytes = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    let mut header = *b"binary STL written by solidtex                                                  ";
    header[79] = b'\n';
    bytes.extend_from_slice(&header);
    bytes.extend_from_slice(&count.to_le_bytes());
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        for v in [(b - a).cross(c - a).normalize_or_zero(), a, b, c] {
            for x in v.to_array() {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    write_bytes(path, &bytes)
}

/// Write `mesh` as an ASCII PLY (atomically).
pub fn write_ply(path: &Path, mesh: &Mesh) -> Result<()> {
    let mut text = format!(
        "ply\nformat ascii 1.0\ncomment written by solidtex {}\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        env!("CARGO_PKG_VERSION"),
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    for v in &mesh.vertices {
        text.push_str(&format!("{} {} {}\n", v.x, v.y, v.z));
    }
    for [a, b, c] in &mesh.triangles {
        text.push_str(&format!("3 {a} {b} {c}\n"));
    }
    write_bytes(path, text.as_bytes())
}

// ---------------------------------------------------------------------------------- OBJ

fn parse_obj(bytes: &[u8]) -> Result<Soup> {
    let text = String::from_utf8_lossy(bytes);
    let mut soup = Soup::default();
    for (n, line) in text.lines().enumerate() {
        let data = line.split('#').next().unwrap_or_default();
        let mut words = data.split_whitespace();
        match words.next() {
            Some("v") => soup.vertices.push(obj_vertex(words, n + 1)?),
            Some("f") => {
                let corners = obj_face(words, soup.vertices.len(), n + 1)?;
                soup.push_polygon(&corners);
            }
            _ => {}
        }
    }
    Ok(soup)
}

fn obj_vertex<'a>(mut words: impl Iterator<Item = &'a str>, line: usize) -> Result<Vec3> {
    let mut xyz = [0.0f32; 3];
    for (axis, value) in ["x", "y", "z"].iter().zip(&mut xyz) {
        let word = words.next().ok_or_else(|| {
            Error::invalid(format!("line {line}: a vertex needs three coordinates x y z; {axis} is missing"))
        })?;
        *value = word
            .parse()
            .map_err(|_| Error::invalid(format!("line {line}: vertex coordinate {axis} = {word:?} is not a number")))?;
    }
    Ok(Vec3::from_array(xyz))
}

/// The 0-based corners of a face line; `defined` vertices come before it.
fn obj_face<'a>(words: impl Iterator<Item = &'a str>, defined: usize, line: usize) -> Result<Vec<u32>> {
    let mut corners = Vec::new();
    for word in words {
        let index = word.split('/').next().unwrap_or_default();
        let i: i64 = index.parse().map_err(|_| {
            Error::invalid(format!("line {line}: face corner {word:?} does not start with a vertex index"))
        })?;
        let zero_based = match i {
            0 => {
                return Err(Error::invalid(format!(
                    "line {line}: vertex index 0 is not allowed (OBJ counts from 1, or back from -1)"
                )));
            }
            i if i > 0 => i - 1,
            i => defined as i64 + i,
        };
        let corner = u32::try_from(zero_based).map_err(|_| {
            Error::invalid(format!("line {line}: vertex index {i} is out of range ({defined} vertices defined so far)"))
        })?;
        corners.push(corner);
    }
    if corners.len() < 3 {
        return Err(Error::invalid(format!("line {line}: a face needs at least 3 corners, found {}", corners.len())));
    }
    Ok(corners)
}

// ---------------------------------------------------------------------------------- STL

fn parse_stl(bytes: &[u8]) -> Result<Soup> {
    let text_start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    if bytes[text_start..].starts_with(b"solid") && !bytes.contains(&0) {
        stl_ascii(&String::from_utf8_lossy(bytes))
    } else {
        stl_binary(bytes)
    }
}

fn stl_binary(bytes: &[u8]) -> Result<Soup> {
    if bytes.len() < 84 {
        return Err(Error::invalid(format!(
            "not an ASCII STL (no leading \"solid\") and too short for a binary STL: {} bytes, the header alone is 84",
            bytes.len()
        )));
    }
    let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
    let needed = 84 + 50 * count as u64;
    if (bytes.len() as u64) < needed {
        return Err(Error::invalid(format!(
            "binary STL header promises {count} triangles ({needed} bytes) but the file has only {} bytes (truncated?)",
            bytes.len()
        )));
    }
    let mut welder = Welder::default();
    let mut soup = Soup::default();
    for record in bytes[84..].chunks_exact(50).take(count) {
        let corner = |k: usize| {
            let f = |j: usize| {
                let at = 12 + 12 * k + 4 * j;
                f32::from_le_bytes([record[at], record[at + 1], record[at + 2], record[at + 3]])
            };
            Vec3::new(f(0), f(1), f(2))
        };
        let t = [0, 1, 2].map(|k| welder.index(corner(k), &mut soup.vertices));
        soup.triangles.push(t);
    }
    Ok(soup)
}

fn stl_ascii(text: &str) -> Result<Soup> {
    let mut welder = Welder::default();
    let mut soup = Soup::default();
    let mut corners = Vec::with_capacity(3);
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("vertex") {
            continue;
        }
        let v = obj_vertex(words, n + 1)?;
        corners.push(welder.index(v, &mut soup.vertices));
        if corners.len() == 3 {
            soup.triangles.push([corners[0], corners[1], corners[2]]);
            corners.clear();
        }
    }
    if !corners.is_empty() {
        return Err(Error::invalid(format!(
            "ASCII STL ends inside a facet: the last one has {} vertex line(s), 3 are needed",
            corners.len()
        )));
    }
    Ok(soup)
}

/// Gives bit-identical corners (with -0 equal to 0) one index, numbered by first use.
#[derive(Default)]
struct Welder {
    seen: HashMap<[u32; 3], u32>,
}

impl Welder {
    fn index(&mut self, v: Vec3, vertices: &mut Vec<Vec3>) -> u32 {
        let key = v.to_array().map(|x| if x == 0.0 { 0 } else { x.to_bits() });
        *self.seen.entry(key).or_insert_with(|| {
            vertices.push(v);
            vertices.len() as u32 - 1
        })
    }
}

// ---------------------------------------------------------------------------------- PLY

/// A PLY scalar type.
#[derive(Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Decode little-endian bytes (exactly `size()` of them).
    fn decode(self, b: &[u8]) -> f64 {
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

enum Property {
    Scalar(Scalar, String),
    List { count: Scalar, item: Scalar, name: String },
}

struct Element {
    name: String,
    count: usize,
    line: usize,
    properties: Vec<Property>,
}

impl Element {
    fn scalar(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| matches!(p, Property::Scalar(_, n) if n == name))
    }

    fn list(&self, names: &[&str]) -> Option<usize> {
        self.properties.iter().position(|p| matches!(p, Property::List { name, .. } if names.contains(&name.as_str())))
    }
}

struct PlyHeader {
    binary: bool,
    elements: Vec<Element>,
    body: usize,
}

const PLY_TYPES: &str = "char, uchar, short, ushort, int, uint, float, double (or int8 ... float64)";

fn parse_ply(bytes: &[u8]) -> Result<Soup> {
    let header = ply_header(bytes)?;
    let mut body = match header.binary {
        true => Body::Binary { bytes: &bytes[header.body..], at: 0 },
        false => Body::Ascii { text: String::from_utf8_lossy(&bytes[header.body..]).into_owned(), at: 0 },
    };
    let mut soup = Soup::default();
    for element in &header.elements {
        match element.name.as_str() {
            "vertex" => (soup.vertices, soup.colours) = ply_vertices(element, &mut body, bytes.len())?,
            "face" => ply_faces(element, &mut body, bytes.len(), &mut soup)?,
            _ => skip_element(element, &mut body)?,
        }
    }
    Ok(soup)
}

fn ply_header(bytes: &[u8]) -> Result<PlyHeader> {
    let mut header = PlyHeader { binary: false, elements: Vec::new(), body: 0 };
    let mut format_seen = false;
    let mut at = 0;
    let mut line_no = 0;
    while at < bytes.len() {
        let end = bytes[at..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |p| at + p);
        let line = String::from_utf8_lossy(&bytes[at..end]);
        let line = line.trim();
        at = (end + 1).min(bytes.len());
        line_no += 1;
        let fail = |what: String| Error::invalid(format!("PLY header line {line_no}: {what}"));
        let words: Vec<&str> = line.split_whitespace().collect();
        if line_no == 1 {
            if line != "ply" {
                return Err(fail(format!("{line:?} is not \"ply\", so this is not a PLY file")));
            }
            continue;
        }
        match words.as_slice() {
            ["end_header"] => {
                if !format_seen {
                    return Err(fail("end_header before any format line".into()));
                }
                header.body = at;
                return Ok(header);
            }
            ["format", format, ..] => {
                header.binary = match *format {
                    "ascii" => false,
                    "binary_little_endian" => true,
                    other => {
                        return Err(fail(format!(
                            "format {other} is not supported; allowed: ascii, binary_little_endian"
                        )));
                    }
                };
                format_seen = true;
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count =
                    count.parse().map_err(|_| fail(format!("element count {count:?} is not a whole number")))?;
                header.elements.push(Element { name: name.to_string(), count, line: line_no, properties: Vec::new() });
            }
            ["property", ..] => {
                let property = ply_property(&words[1..]).map_err(fail)?;
                let element = header.elements.last_mut().ok_or_else(|| fail("property before any element".into()))?;
                element.properties.push(property);
            }
            _ => return Err(fail(format!("{line:?} is not a PLY header line"))),
        }
    }
    Err(Error::invalid(format!("PLY header has no end_header line (read {line_no} lines)")))
}

fn ply_property(words: &[&str]) -> Result<Property, String> {
    let scalar =
        |name: &str| Scalar::parse(name).ok_or_else(|| format!("unknown property type {name:?}; allowed: {PLY_TYPES}"));
    match words {
        ["list", count, item, name] => {
            let count = scalar(count)?;
            if !count.is_integer() {
                return Err(format!("list {name} has a floating-point count type; it must be an integer type"));
            }
            Ok(Property::List { count, item: scalar(item)?, name: name.to_string() })
        }
        [ty, name] => Ok(Property::Scalar(scalar(ty)?, name.to_string())),
        _ => Err("a property line is \"property <type> <name>\" or \"property list <type> <type> <name>\"".into()),
    }
}

/// The element data after the header.
enum Body<'a> {
    Ascii { text: String, at: usize },
    Binary { bytes: &'a [u8], at: usize },
}

impl Body<'_> {
    /// The next value of type `ty`, or what went wrong.
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        match self {
            Body::Ascii { text, at } => {
                let rest = &text[*at..];
                let start = rest.find(|c: char| !c.is_ascii_whitespace()).ok_or("the data ends early")?;
                let len = rest[start..].find(|c: char| c.is_ascii_whitespace()).unwrap_or(rest.len() - start);
                let word = &rest[start..start + len];
                *at += start + len;
                word.parse().map_err(|_| format!("value {word:?} is not a number"))
            }
            Body::Binary { bytes, at } => {
                let chunk = bytes.get(*at..*at + ty.size()).ok_or("the data ends early (truncated?)")?;
                *at += ty.size();
                Ok(ty.decode(chunk))
            }
        }
    }

    /// Every value of one item of `element`, with lists flattened after their length.
    fn item(&mut self, element: &Element, index: usize) -> Result<Vec<Vec<f64>>> {
        let fail = |what: String| Error::invalid(format!("PLY element {} item {index}: {what}", element.name));
        let mut values = Vec::with_capacity(element.properties.len());
        for property in &element.properties {
            match property {
                Property::Scalar(ty, _) => values.push(vec![self.next(*ty).map_err(fail)?]),
                Property::List { count, item, name } => {
                    let n = self.next(*count).map_err(fail)?;
                    if !(0.0..=1e6).contains(&n) || n.fract() != 0.0 {
                        return Err(fail(format!("list {name} has length {n}; allowed is a whole number 0..=1000000")));
                    }
                    let list = (0..n as usize).map(|_| self.next(*item)).collect::<Result<Vec<_>, _>>();
                    values.push(list.map_err(fail)?);
                }
            }
        }
        Ok(values)
    }
}

/// Vertex positions and, when the file has them, their colours.
type Vertices = (Vec<Vec3>, Option<Vec<[f32; 3]>>);

/// The vertices and, when the element has `red`, `green` and `blue`, their colours (integer
/// types read as 0-255, floating-point ones as 0-1).
fn ply_vertices(element: &Element, body: &mut Body, file_len: usize) -> Result<Vertices> {
    let find = |axis: &str| {
        element.scalar(axis).ok_or_else(|| {
            Error::invalid(format!("PLY header line {}: element vertex has no property {axis}", element.line))
        })
    };
    let (x, y, z) = (find("x")?, find("y")?, find("z")?);
    let rgb = ["red", "green", "blue"].map(|c| element.scalar(c));
    let rgb = match rgb {
        [Some(r), Some(g), Some(b)] => Some([r, g, b].map(|k| {
            let whole =
                matches!(&element.properties[k], Property::Scalar(t, _) if !matches!(t, Scalar::F32 | Scalar::F64));
            (k, if whole { 1.0 / 255.0 } else { 1.0 })
        })),
        _ => None,
    };
    let mut vertices = Vec::with_capacity(element.count.min(file_len));
    let mut colours = rgb.map(|_| Vec::with_capacity(element.count.min(file_len)));
    for i in 0..element.count {
        let values = body.item(element, i)?;
        vertices.push(Vec3::new(values[x][0] as f32, values[y][0] as f32, values[z][0] as f32));
        if let (Some(rgb), Some(out)) = (rgb, colours.as_mut()) {
            out.push(rgb.map(|(k, unit)| (values[k][0] * unit) as f32));
        }
    }
    Ok((vertices, colours))
}

fn ply_faces(element: &Element, body: &mut Body, file_len: usize, soup: &mut Soup) -> Result<()> {
    let list = element.list(&["vertex_indices", "vertex_index"]).ok_or_else(|| {
        Error::invalid(format!(
            "PLY header line {}: element face has no list property vertex_indices (or vertex_index)",
            element.line
        ))
    })?;
    soup.triangles.reserve(element.count.min(file_len));
    for i in 0..element.count {
        let values = body.item(element, i)?;
        let corners = values[list]
            .iter()
            .map(|&v| {
                if v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0 {
                    Ok(v as u32)
                } else {
                    Err(Error::invalid(format!("PLY face {i}: vertex index {v} is not a whole number >= 0")))
                }
            })
            .collect::<Result<Vec<u32>>>()?;
        if corners.len() < 3 {
            return Err(Error::invalid(format!("PLY face {i} has {} corner(s); at least 3 are needed", corners.len())));
        }
        soup.push_polygon(&corners);
    }
    Ok(())
}

fn skip_element(element: &Element, body: &mut Body) -> Result<()> {
    if element.properties.is_empty() {
        return Ok(());
    }
    for i in 0..element.count {
        body.item(element, i)?;
    }
    Ok(())
}
