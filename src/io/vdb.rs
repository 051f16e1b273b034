//! OpenVDB (`.vdb`, file format 224, uncompressed): the volume format of Blender,
//! Houdini and Unreal Engine.
//!
//! Written: a float grid `density` (the alpha channel, or 1 everywhere inside the box
//! where the volume has no alpha), a vec3s grid `color` (R, G, B; a grey volume's one
//! channel three times), and every other channel (Depth, Displacement, named ones) as a
//! float grid of its name. Every voxel of the box is active; the background is 0. The
//! transform of a volume placed in model space (a bake) is a uniform scale of its voxel
//! side and a translation to its voxel (0, 0, 0)'s centre, so it lands on its model;
//! otherwise a uniform scale of `1 / longest side` (the volume spans one unit along its
//! longest side, index (0, 0, 0) at the origin). The volume's description (dims,
//! channels, type, origin and voxel, provenance) rides in file metadata as
//! `solidtex.<field>` strings.
//!
//! Read: files this module writes, and other uncompressed files of float and vec3s grids
//! without active tiles (zlib or blosc compression, half floats and other grid types are
//! refused by name). Without solidtex's description, `color` becomes R, G, B, `density`
//! A (or the one grey channel when there is no colour) and other float grids named
//! channels. Every count and size is checked against the bytes left before anything is
//! allocated. Layout: docs/formats.md.

use super::fields;
use crate::error::{Error, Result};
use crate::volume::{Channel, Volume};
use std::collections::BTreeMap;
use std::path::Path;

const MAGIC: [u8; 8] = [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0];
const FILE_VERSION: u32 = 224;
const FLOAT_TREE: &str = "Tree_float_5_4_3";
const VEC3_TREE: &str = "Tree_vec3s_5_4_3";
/// A node's values stored whole (OpenVDB's `NO_MASK_AND_ALL_VALS`).
const ALL_VALUES: u8 = 6;
/// Bits of the leaf, lower internal and upper internal node masks.
const LEAF_BITS: usize = 512;
const LOWER_BITS: usize = 4096;
const UPPER_BITS: usize = 32768;

/// Write `volume` as an OpenVDB file (atomically).
pub fn write(path: &Path, volume: &Volume) -> Result<()> {
    super::atomic::write_bytes(path, &to_bytes(volume, &uuid_for(volume)))
}

/// Read an OpenVDB file within `budget` bytes of voxels.
pub fn read(path: &Path, budget: u64) -> Result<Volume> {
    let bytes = super::atomic::read_bytes_within(path, super::atomic::file_cap(budget))?;
    parse(&bytes, budget).map_err(|e| e.in_file(path))
}

/// One grid to write: its name and, per voxel (x fastest), 1 or 3 samples.
struct Grid {
    name: String,
    components: usize,
    samples: Vec<f32>,
}

/// The grids `volume` is written as (see the module notes).
fn grids(volume: &Volume) -> Vec<Grid> {
    let channels = volume.channels();
    let find = |role: &Channel| channels.iter().position(|c| c == role);
    let column = |c: usize| volume.data().iter().skip(c).step_by(volume.channel_count()).copied();
    let voxels = volume.data().len() / volume.channel_count();
    let density = match find(&Channel::A) {
        Some(a) => column(a).collect(),
        None => vec![1.0; voxels],
    };
    let mut out = vec![Grid { name: "density".into(), components: 1, samples: density }];
    let rgb = match (find(&Channel::R), find(&Channel::G), find(&Channel::B)) {
        (Some(r), Some(g), Some(b)) => Some([r, g, b]),
        (Some(r), None, None) => Some([r, r, r]),
        _ => None,
    };
    if let Some(rgb) = rgb {
        let samples = volume.data().chunks_exact(volume.channel_count()).flat_map(|v| rgb.map(|c| v[c])).collect();
        out.push(Grid { name: "color".into(), components: 3, samples });
    }
    for (c, channel) in channels.iter().enumerate() {
        if !matches!(channel, Channel::R | Channel::G | Channel::B | Channel::A) {
            out.push(Grid { name: channel.name().to_string(), components: 1, samples: column(c).collect() });
        }
    }
    out
}

/// A UUID-shaped identifier derived from the volume's content, so the same volume gives
/// the same file.
fn uuid_for(volume: &Volume) -> String {
    let mut hasher = blake3::Hasher::new();
    volume.data().iter().for_each(|v| {
        hasher.update(&v.to_le_bytes());
    });
    let hex = hasher.finalize().to_hex();
    format!("{}-{}-{}-{}-{}", &hex[0..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..32])
}

/// The file's bytes: header, file metadata, then each grid with its descriptor.
pub fn to_bytes(volume: &Volume, uuid: &str) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&MAGIC);
    for v in [FILE_VERSION, 10, 0] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.push(1); // grid offsets follow each descriptor
    out.extend_from_slice(uuid.as_bytes());
    let mut meta: Vec<(String, Value)> =
        vec![("creator".into(), Value::Text(format!("solidtex {}", env!("CARGO_PKG_VERSION"))))];
    meta.extend(fields::fields(volume).into_iter().map(|(k, v)| (format!("solidtex.{k}"), Value::Text(v))));
    put_meta(&mut out, meta);
    let grids = grids(volume);
    out.extend_from_slice(&(grids.len() as i32).to_le_bytes());
    for grid in &grids {
        put_grid(&mut out, grid, volume);
    }
    out
}

/// A metadata value.
enum Value {
    Text(String),
    Int3([i32; 3]),
    Int64(i64),
}

fn put_string(out: &mut Vec<u8>, text: &str) {
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(text.as_bytes());
}

/// A metadata map: count, then entries sorted by name (as OpenVDB writes them).
fn put_meta(out: &mut Vec<u8>, mut entries: Vec<(String, Value)>) {
    entries.sort_by(|a, b| a.0.cmp(&b.0));
    out.extend_from_slice(&(entries.len() as u32).to_le_bytes());
    for (name, value) in entries {
        put_string(out, &name);
        let (kind, bytes): (&str, Vec<u8>) = match value {
            Value::Text(t) => ("string", t.into_bytes()),
            Value::Int3(v) => ("vec3i", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
            Value::Int64(v) => ("int64", v.to_le_bytes().to_vec()),
        };
        put_string(out, kind);
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(&bytes);
    }
}

/// One grid: descriptor, its three offsets, flags, metadata, transform, topology, buffers.
fn put_grid(out: &mut Vec<u8>, grid: &Grid, volume: &Volume) {
    let dims = volume.dims();
    put_string(out, &grid.name);
    put_string(out, if grid.components == 3 { VEC3_TREE } else { FLOAT_TREE });
    put_string(out, "");
    let offsets = out.len();
    out.extend_from_slice(&[0; 24]);
    let grid_pos = out.len();
    out.extend_from_slice(&0u32.to_le_bytes()); // no compression
    let top = dims.map(|d| d as i32 - 1);
    let voxels = dims.iter().map(|d| *d as i64).product();
    let mut meta = vec![
        ("name".to_string(), Value::Text(grid.name.clone())),
        ("file_bbox_min".to_string(), Value::Int3([0; 3])),
        ("file_bbox_max".to_string(), Value::Int3(top)),
        ("file_compression".to_string(), Value::Text("none".into())),
        ("file_voxel_count".to_string(), Value::Int64(voxels)),
    ];
    if grid.name == "density" {
        meta.push(("class".to_string(), Value::Text("fog volume".into())));
    }
    if grid.components == 3 {
        meta.push(("vector_type".to_string(), Value::Text("invariant".into())));
    }
    put_meta(out, meta);
    put_transform(out, index_to_model(volume));
    let leaves = put_topology(out, grid, dims);
    let block_pos = out.len();
    for origin in &leaves {
        put_leaf_buffer(out, grid, dims, *origin);
    }
    let end_pos = out.len();
    for (k, pos) in [grid_pos, block_pos, end_pos].into_iter().enumerate() {
        out[offsets + 8 * k..offsets + 8 * k + 8].copy_from_slice(&(pos as i64).to_le_bytes());
    }
}

/// The scale and translation from index space (a voxel's centre at its index) to the
/// world: the volume's place in model space when it has one, else `1 / longest side` and
/// no translation.
fn index_to_model(volume: &Volume) -> (f64, [f64; 3]) {
    match volume.model_grid {
        Some(g) => (f64::from(g.voxel), g.origin.map(f64::from)),
        None => (1.0 / *volume.dims().iter().max().expect("three dims") as f64, [0.0; 3]),
    }
}

/// `UniformScaleTranslateMap` with scale `s` and translation `t`: translation, scale,
/// voxel size, 1/s, (1/s)², 1/(2s), each three doubles.
fn put_transform(out: &mut Vec<u8>, (s, t): (f64, [f64; 3])) {
    put_string(out, "UniformScaleTranslateMap");
    for v in t {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let inverse = 1.0 / s;
    for v in [s, s.abs(), inverse, inverse * inverse, inverse / 2.0] {
        for _ in 0..3 {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
}

/// The leaves (8³ blocks) holding the box, grouped under their lower (128³) and upper
/// (4096³) internal nodes, each level in OpenVDB's order: upper nodes by origin (x, then
/// y, then z), children by bit index.
type Tree = BTreeMap<[i32; 3], BTreeMap<usize, Vec<(usize, [i32; 3])>>>;

fn tree(dims: [usize; 3]) -> Tree {
    let mut tree = Tree::new();
    for x in (0..dims[0]).step_by(8) {
        for y in (0..dims[1]).step_by(8) {
            for z in (0..dims[2]).step_by(8) {
                let leaf = [x, y, z].map(|c| c as i32);
                let upper = leaf.map(|c| c & !4095);
                let lower = lower_bit(leaf);
                tree.entry(upper).or_default().entry(lower).or_default().push((leaf_bit(leaf), leaf));
            }
        }
    }
    tree.values_mut().flat_map(|lowers| lowers.values_mut()).for_each(|leaves| leaves.sort_unstable());
    tree
}

fn lower_bit([x, y, z]: [i32; 3]) -> usize {
    ((((x & 4095) >> 7) << 10) | (((y & 4095) >> 7) << 5) | ((z & 4095) >> 7)) as usize
}

fn leaf_bit([x, y, z]: [i32; 3]) -> usize {
    ((((x & 127) >> 3) << 8) | (((y & 127) >> 3) << 4) | ((z & 127) >> 3)) as usize
}

fn mask(bits: impl Iterator<Item = usize>, size: usize) -> Vec<u8> {
    let mut words = vec![0u64; size / 64];
    bits.for_each(|b| words[b / 64] |= 1 << (b % 64));
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// The topology: buffer count, background, no tiles, the upper nodes with their lower
/// nodes and leaf masks. Returns the leaf origins in the order written.
fn put_topology(out: &mut Vec<u8>, grid: &Grid, dims: [usize; 3]) -> Vec<[i32; 3]> {
    let value = 4 * grid.components;
    let tree = tree(dims);
    out.extend_from_slice(&1i32.to_le_bytes());
    out.extend(std::iter::repeat_n(0u8, value)); // background 0
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&(tree.len() as u32).to_le_bytes());
    let mut leaves = Vec::new();
    for (origin, lowers) in &tree {
        origin.iter().for_each(|c| out.extend_from_slice(&c.to_le_bytes()));
        out.extend(mask(lowers.keys().copied(), UPPER_BITS));
        out.extend(mask(std::iter::empty(), UPPER_BITS));
        out.push(ALL_VALUES);
        out.extend(std::iter::repeat_n(0u8, UPPER_BITS * value));
        for children in lowers.values() {
            out.extend(mask(children.iter().map(|c| c.0), LOWER_BITS));
            out.extend(mask(std::iter::empty(), LOWER_BITS));
            out.push(ALL_VALUES);
            out.extend(std::iter::repeat_n(0u8, LOWER_BITS * value));
            for (_, leaf) in children {
                out.extend(leaf_mask(*leaf, dims));
                leaves.push(*leaf);
            }
        }
    }
    leaves
}

/// Which voxels of the leaf at `origin` lie inside the box (bit `x << 6 | y << 3 | z`).
fn leaf_mask(origin: [i32; 3], dims: [usize; 3]) -> Vec<u8> {
    let inside = |n: usize| {
        let local = [n >> 6, (n >> 3) & 7, n & 7];
        (0..3).all(|a| (origin[a] as usize + local[a]) < dims[a])
    };
    mask((0..LEAF_BITS).filter(|n| inside(*n)), LEAF_BITS)
}

fn put_leaf_buffer(out: &mut Vec<u8>, grid: &Grid, dims: [usize; 3], origin: [i32; 3]) {
    out.extend(leaf_mask(origin, dims));
    out.push(ALL_VALUES);
    for n in 0..LEAF_BITS {
        let p = [n >> 6, (n >> 3) & 7, n & 7];
        let at = [0, 1, 2].map(|a| origin[a] as usize + p[a]);
        let inside = (0..3).all(|a| at[a] < dims[a]);
        for c in 0..grid.components {
            let v = if inside {
                grid.samples[((at[2] * dims[1] + at[1]) * dims[0] + at[0]) * grid.components + c]
            } else {
                0.0
            };
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
}

/// Reads the little-endian fields of a file, every read checked against its length.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        match self.at.checked_add(n).filter(|end| *end <= self.bytes.len()) {
            Some(end) => {
                let out = &self.bytes[self.at..end];
                self.at = end;
                Ok(out)
            }
            None => Err(Error::invalid(format!(
                "truncated at byte {}: {what} needs {n} bytes, {} are left",
                self.at,
                self.left()
            ))),
        }
    }

    fn left(&self) -> usize {
        self.bytes.len() - self.at
    }

    fn u8(&mut self, what: &str) -> Result<u8> {
        Ok(self.take(1, what)?[0])
    }

    fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }

    fn i32(&mut self, what: &str) -> Result<i32> {
        Ok(i32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }

    fn i64(&mut self, what: &str) -> Result<i64> {
        Ok(i64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes")))
    }

    fn f64(&mut self, what: &str) -> Result<f64> {
        Ok(f64::from_le_bytes(self.take(8, what)?.try_into().expect("8 bytes")))
    }

    /// A length-prefixed string of at most `cap` bytes.
    fn string(&mut self, cap: usize, what: &str) -> Result<String> {
        let n = self.u32(what)? as usize;
        if n > cap {
            return Err(Error::invalid(format!("{what} is {n} bytes long; at most {cap} are allowed")));
        }
        Ok(String::from_utf8_lossy(self.take(n, what)?).into_owned())
    }

    fn seek(&mut self, to: i64, what: &str) -> Result<()> {
        if to < 0 || to as u64 > self.bytes.len() as u64 {
            return Err(Error::invalid(format!("{what} {to} lies outside the file ({} bytes)", self.bytes.len())));
        }
        self.at = to as usize;
        Ok(())
    }
}

/// Most metadata entries, grids and upper nodes a file may hold.
const MAX_ENTRIES: usize = 1024;
const MAX_GRIDS: usize = 256;
const MAX_NAME: usize = 4096;
const MAX_TEXT: usize = 1 << 20;

/// One grid read back: name, components, and its leaves (origin, active mask, values).
struct ReadGrid {
    name: String,
    components: usize,
    leaves: Vec<([i32; 3], [u64; 8], Vec<f32>)>,
}

fn parse(bytes: &[u8], budget: u64) -> Result<Volume> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(8, "the magic number")? != MAGIC {
        return Err(Error::invalid("not an OpenVDB file (its first 8 bytes are not \" BDV\" and zeros)"));
    }
    let version = r.u32("the file version")?;
    if !(222..=225).contains(&version) {
        return Err(Error::invalid(format!("OpenVDB file version {version} is not supported; allowed: 222 to 225")));
    }
    r.take(8, "the library version")?;
    if r.u8("the grid-offsets flag")? != 1 {
        return Err(Error::invalid("grids without offsets (a streamed file) are not supported"));
    }
    r.take(36, "the UUID")?;
    let described = meta_map(&mut r)?;
    let count = r.i32("the grid count")?;
    if !(0..=MAX_GRIDS as i32).contains(&count) {
        return Err(Error::invalid(format!("grid count {count} is out of range 0 to {MAX_GRIDS}")));
    }
    let mut grids: Vec<ReadGrid> = Vec::new();
    let mut last_end = 0;
    for k in 0..count {
        let grid = grid(&mut r, &mut last_end).map_err(|e| Error::invalid(format!("grid {k}: {e}")))?;
        if !grids.iter().any(|g| g.name == grid.name) {
            grids.push(grid);
        }
    }
    assemble(&grids, &described, budget)
}

/// A metadata map; string entries are returned, others skipped by their size.
fn meta_map(r: &mut Reader) -> Result<Vec<(String, String)>> {
    let count = r.u32("the metadata count")? as usize;
    if count > MAX_ENTRIES {
        return Err(Error::invalid(format!("{count} metadata entries; at most {MAX_ENTRIES} are allowed")));
    }
    let mut out = Vec::new();
    for _ in 0..count {
        let name = r.string(MAX_NAME, "a metadata name")?;
        let kind = r.string(MAX_NAME, "a metadata type")?;
        let size = r.u32("a metadata size")? as usize;
        let value = r.take(size, "a metadata value")?;
        if kind == "string" {
            if size > MAX_TEXT {
                return Err(Error::invalid(format!(
                    "metadata {name:?} is {size} bytes; at most {MAX_TEXT} are allowed"
                )));
            }
            out.push((name, String::from_utf8_lossy(value).into_owned()));
        } else if kind == "bool" && name == "is_saved_as_half_float" && value.first().is_some_and(|b| *b != 0) {
            out.push((name, "true".into()));
        }
    }
    Ok(out)
}

fn grid(r: &mut Reader, last_end: &mut i64) -> Result<ReadGrid> {
    let name = r.string(MAX_NAME, "the grid name")?;
    let kind = r.string(MAX_NAME, "the grid type")?;
    let parent = r.string(MAX_NAME, "the instance parent")?;
    let components = match kind.as_str() {
        FLOAT_TREE => 1,
        VEC3_TREE => 3,
        other => {
            return Err(Error::invalid(format!(
                "{name:?} is a {other} grid; allowed: {FLOAT_TREE} and {VEC3_TREE} (full floats, no half floats)"
            )));
        }
    };
    if !parent.is_empty() {
        return Err(Error::invalid(format!(
            "{name:?} is an instance of {parent:?}; instanced grids are not supported"
        )));
    }
    let (grid_pos, block_pos, end_pos) =
        (r.i64("the grid position")?, r.i64("the block position")?, r.i64("the end position")?);
    if !(grid_pos >= r.at as i64 && grid_pos < block_pos && block_pos <= end_pos && end_pos > *last_end) {
        return Err(Error::invalid(format!(
            "{name:?}: its offsets {grid_pos}, {block_pos}, {end_pos} are out of order"
        )));
    }
    *last_end = end_pos;
    r.seek(grid_pos, "the grid position")?;
    let flags = r.u32("the compression flags")?;
    if flags & !2 != 0 {
        return Err(Error::invalid(format!(
            "{name:?} is compressed (flags {flags}: zlib or blosc); only uncompressed grids are read: \
             save it uncompressed (e.g. pyopenvdb's write with compression off, or Houdini's \"none\")"
        )));
    }
    let meta = meta_map(r)?;
    if meta.iter().any(|(k, v)| k == "is_saved_as_half_float" && v == "true") {
        return Err(Error::invalid(format!("{name:?} is saved as half floats; only full floats are read")));
    }
    let name = meta.iter().find(|(k, _)| k == "name").map_or(name, |(_, v)| v.clone());
    transform(r)?;
    let value = 4 * components;
    let origins = topology(r, value, flags)?;
    if r.at as i64 != block_pos {
        return Err(Error::invalid(format!("{name:?}: its topology ends at byte {}, not at {block_pos}", r.at)));
    }
    let per_leaf = 64 + 1 + if flags & 2 == 0 { LEAF_BITS * value } else { 0 };
    if origins.len().saturating_mul(per_leaf) > r.left() {
        return Err(Error::invalid(format!("{name:?}: {} leaves cannot fit in the bytes left", origins.len())));
    }
    let mut leaves = Vec::with_capacity(origins.len());
    for (origin, topology_mask) in origins {
        let mask = node_mask::<8>(r)?;
        if mask != topology_mask {
            return Err(Error::invalid(format!("{name:?}: a leaf's mask differs between topology and buffers")));
        }
        let values = node_values(r, &mask, LEAF_BITS, components, flags)?;
        leaves.push((origin, mask, values));
    }
    if r.at as i64 != end_pos {
        return Err(Error::invalid(format!("{name:?}: its data ends at byte {}, not at {end_pos}", r.at)));
    }
    Ok(ReadGrid { name, components, leaves })
}

/// Skips a linear transform, checking its map type and numbers.
fn transform(r: &mut Reader) -> Result<()> {
    let map = r.string(MAX_NAME, "the transform's map type")?;
    let doubles = match map.as_str() {
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => 18,
        "UniformScaleMap" | "ScaleMap" => 15,
        "TranslationMap" => 3,
        other => {
            return Err(Error::invalid(format!(
                "transform {other:?} is not supported; allowed: (Uniform)ScaleTranslateMap, (Uniform)ScaleMap, TranslationMap"
            )));
        }
    };
    for _ in 0..doubles {
        if !r.f64("a transform number")?.is_finite() {
            return Err(Error::invalid("the transform holds a number that is not finite"));
        }
    }
    Ok(())
}

/// A node mask of `WORDS` 64-bit words.
fn node_mask<const WORDS: usize>(r: &mut Reader) -> Result<[u64; WORDS]> {
    let bytes = r.take(WORDS * 8, "a node mask")?;
    Ok(std::array::from_fn(|w| u64::from_le_bytes(bytes[w * 8..w * 8 + 8].try_into().expect("8 bytes"))))
}

fn bits(words: &[u64]) -> impl Iterator<Item = usize> + '_ {
    words.iter().enumerate().flat_map(|(w, &word)| (0..64).filter(move |b| word >> b & 1 == 1).map(move |b| w * 64 + b))
}

/// The root and internal nodes; returns each leaf's origin and active mask in file order.
fn topology(r: &mut Reader, value: usize, flags: u32) -> Result<Vec<([i32; 3], [u64; 8])>> {
    if r.i32("the buffer count")? != 1 {
        return Err(Error::invalid("a tree must have one buffer"));
    }
    r.take(value, "the background")?;
    let tiles = r.u32("the tile count")? as usize;
    let children = r.u32("the child count")? as usize;
    if tiles.saturating_add(children) > MAX_ENTRIES || tiles.saturating_mul(13 + value) > r.left() {
        return Err(Error::invalid(format!("{tiles} tiles and {children} children are more than allowed")));
    }
    for _ in 0..tiles {
        r.take(12 + value, "a root tile")?;
        if r.u8("a root tile's state")? != 0 {
            return Err(Error::invalid("active tiles (constant regions) are not supported; voxelize them first"));
        }
    }
    let mut leaves = Vec::new();
    let mut previous: Option<[i32; 3]> = None;
    for _ in 0..children {
        let origin = [r.i32("a node origin")?, r.i32("a node origin")?, r.i32("a node origin")?];
        if origin.iter().any(|c| c & 4095 != 0) || previous.is_some_and(|p| p >= origin) {
            return Err(Error::invalid(format!("upper node origin {origin:?} is not a new multiple of 4096 in order")));
        }
        previous = Some(origin);
        let upper = internal::<512>(r, value, flags, UPPER_BITS)?;
        for n5 in bits(&upper) {
            let lower_origin = [n5 >> 10, (n5 >> 5) & 31, n5 & 31].map(|i| i as i32 * 128);
            let lower = internal::<64>(r, value, flags, LOWER_BITS)?;
            for n4 in bits(&lower) {
                let local = [n4 >> 8, (n4 >> 4) & 15, n4 & 15].map(|i| i as i32 * 8);
                let leaf = [0, 1, 2].map(|a| origin[a] + lower_origin[a] + local[a]);
                leaves.push((leaf, node_mask::<8>(r)?));
            }
        }
    }
    Ok(leaves)
}

/// An internal node: child mask, value mask (no active tiles allowed), its values skipped.
fn internal<const WORDS: usize>(r: &mut Reader, value: usize, flags: u32, size: usize) -> Result<[u64; WORDS]> {
    let children = node_mask::<WORDS>(r)?;
    let active = node_mask::<WORDS>(r)?;
    if active.iter().any(|w| *w != 0) {
        return Err(Error::invalid("active tiles (constant regions) are not supported; voxelize them first"));
    }
    let all: [u64; WORDS] = [!0; WORDS];
    skip_values(r, if flags & 2 != 0 { &active } else { &all }, size, value)?;
    Ok(children)
}

/// The per-node value block: a metadata byte, inactive values and a selection mask as it
/// says, then the stored values.
fn value_block(r: &mut Reader, stored_mask: &[u64], size: usize, value: usize) -> Result<(u8, usize)> {
    let meta = r.u8("a node's value metadata")?;
    if meta > ALL_VALUES {
        return Err(Error::invalid(format!("value metadata {meta} is unknown; allowed: 0 to 6")));
    }
    if matches!(meta, 2 | 4 | 5) {
        r.take(value, "an inactive value")?;
    }
    if meta == 5 {
        r.take(value, "an inactive value")?;
    }
    if matches!(meta, 3..=5) {
        r.take(size / 8, "a selection mask")?;
    }
    let stored = if meta == ALL_VALUES { size } else { bits(stored_mask).count() };
    Ok((meta, stored))
}

fn skip_values(r: &mut Reader, stored_mask: &[u64], size: usize, value: usize) -> Result<()> {
    let (_, stored) = value_block(r, stored_mask, size, value)?;
    r.take(stored * value, "a node's values")?;
    Ok(())
}

/// A leaf's values, expanded to all 512 voxels (inactive ones 0: only active voxels are
/// kept in the volume).
fn node_values(r: &mut Reader, mask: &[u64; 8], size: usize, components: usize, flags: u32) -> Result<Vec<f32>> {
    let value = 4 * components;
    let all = [!0u64; 8];
    let (_, stored) = value_block(r, if flags & 2 != 0 { mask } else { &all }, size, value)?;
    let raw = r.take(stored * value, "a leaf's values")?;
    let floats: Vec<f32> = raw.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes"))).collect();
    if stored == size {
        return Ok(floats);
    }
    let mut out = vec![0.0; size * components];
    for (k, n) in bits(mask).enumerate() {
        out[n * components..(n + 1) * components].copy_from_slice(&floats[k * components..(k + 1) * components]);
    }
    Ok(out)
}

/// The volume of the grids' active voxels (their common bounding box).
fn assemble(grids: &[ReadGrid], described: &[(String, String)], budget: u64) -> Result<Volume> {
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for grid in grids {
        for (origin, mask, _) in &grid.leaves {
            for n in bits(mask) {
                let p = [n >> 6, (n >> 3) & 7, n & 7];
                for a in 0..3 {
                    let c = origin[a] as i64 + p[a] as i64;
                    lo[a] = lo[a].min(c);
                    hi[a] = hi[a].max(c);
                }
            }
        }
    }
    if lo[0] > hi[0] {
        return Err(Error::invalid("the file holds no active voxel"));
    }
    let extent = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as u64);
    let ours: Vec<(String, String)> =
        described.iter().filter_map(|(k, v)| k.strip_prefix("solidtex.").map(|k| (k.to_string(), v.clone()))).collect();
    let description = fields::parse(&ours)?;
    let find = |name: &str| grids.iter().find(|g| g.name == name);
    let channels = match description.channels {
        Some(channels) => channels,
        None => guessed_channels(grids)?,
    };
    let sources: Vec<(&ReadGrid, usize)> = channels
        .iter()
        .map(|c| {
            let (grid, component) = match c {
                Channel::R => (find("color").or_else(|| find("density")), 0),
                Channel::G => (find("color"), 1),
                Channel::B => (find("color"), 2),
                Channel::A => (find("density"), 0),
                other => (find(other.name()), 0),
            };
            let grid = grid.ok_or_else(|| Error::invalid(format!("no grid holds channel {}", c.name())))?;
            Ok((grid, component.min(grid.components - 1)))
        })
        .collect::<Result<_>>()?;
    let dims = extent.map(|e| e as usize);
    crate::volume::check_size(dims, channels.len(), budget)?;
    let mut volume = Volume::new(dims, channels.clone())?;
    let count = channels.len();
    for (c, (grid, component)) in sources.into_iter().enumerate() {
        for (origin, mask, values) in &grid.leaves {
            for n in bits(mask) {
                let p = [n >> 6, (n >> 3) & 7, n & 7];
                let at = [0, 1, 2].map(|a| (origin[a] as i64 + p[a] as i64 - lo[a]) as usize);
                let index = (at[2] * dims[1] + at[1]) * dims[0] + at[0];
                volume.data_mut()[index * count + c] = values[n * grid.components + component];
            }
        }
    }
    volume.meta = description.meta;
    volume.model_grid = description.model_grid;
    Ok(volume)
}

/// Channels of a file solidtex did not write: colour, then density (as alpha, or as the
/// grey channel without colour), then other float grids by name.
fn guessed_channels(grids: &[ReadGrid]) -> Result<Vec<Channel>> {
    let has = |name: &str| grids.iter().any(|g| g.name == name);
    let mut channels = Vec::new();
    if has("color") {
        channels.extend(Channel::rgb());
        if has("density") {
            channels.push(Channel::A);
        }
    } else if has("density") {
        channels.push(Channel::R);
    }
    for grid in grids.iter().filter(|g| g.name != "color" && g.name != "density") {
        if grid.components != 1 {
            return Err(Error::invalid(format!("vector grid {:?} has no channel to go to", grid.name)));
        }
        channels.push(Channel::parse(&grid.name)?);
    }
    if channels.is_empty() {
        return Err(Error::invalid("the file holds no grid"));
    }
    Ok(channels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Volume {
        let mut channels = Channel::rgba();
        channels.push(Channel::Depth);
        let mut v = Volume::from_fn([11, 9, 20], channels, |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 10.0, y as f32 / 8.0, z as f32 / 19.0, 0.5, (x + y + z) as f32]);
        })
        .unwrap();
        v.meta.set("seed", "7");
        v
    }

    #[test]
    fn a_volume_round_trips_with_its_description() {
        let v = sample();
        let back = parse(&to_bytes(&v, &uuid_for(&v)), u64::MAX).unwrap();
        assert_eq!(back.dims(), v.dims());
        assert_eq!(back.channels(), v.channels());
        assert_eq!(back.data(), v.data());
        assert_eq!(back.meta.get("seed"), Some("7"));
    }

    #[test]
    fn a_grey_volume_without_alpha_is_coloured_grey_and_dense() {
        let v = Volume::from_fn([8, 8, 8], Channel::grey(), |x, _, _, o| o[0] = x as f32).unwrap();
        let bytes = to_bytes(&v, &uuid_for(&v));
        let names: Vec<String> = grids(&v).into_iter().map(|g| g.name).collect();
        assert_eq!(names, ["density", "color"]);
        assert_eq!(grids(&v)[0].samples, vec![1.0; 512], "density 1 inside without alpha");
        assert_eq!(parse(&bytes, u64::MAX).unwrap().data(), v.data());
    }

    /// Every truncation and every single-byte change is an error or a volume, never a
    /// panic; a file too big for the budget is refused before allocating.
    #[test]
    fn damaged_files_are_refused_cleanly() {
        let v =
            Volume::from_fn([9, 8, 8], Channel::rgb(), |x, y, z, o| o.copy_from_slice(&[x as f32, y as f32, z as f32]))
                .unwrap();
        let bytes = to_bytes(&v, &uuid_for(&v));
        for cut in (0..bytes.len()).step_by(97) {
            assert!(parse(&bytes[..cut], u64::MAX).is_err(), "truncated at {cut}");
        }
        for at in (0..bytes.len()).step_by(53) {
            let mut damaged = bytes.clone();
            damaged[at] ^= 0xA5;
            let _ = parse(&damaged, u64::MAX);
        }
        let err = parse(&bytes, 100).unwrap_err().to_string();
        assert!(err.contains("budget") || err.contains("bytes"), "{err}");
    }
}
