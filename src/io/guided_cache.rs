//! The cache of guided synthesis: the 8³ bricks of every level that earlier cuts computed,
//! kept between cuts of the same model, field, exemplars and seed. A cut reads the voxels
//! it finds there instead of computing them (and so the coarser voxels they came from).
//!
//! ```text
//!  file  DIR/guided-<key as 16 hex digits>.cache
//!  "solidtex guided cache 5\n"  key u64  levels u32  finest dims 3 x u32  whole u32
//!  (little-endian; whole: 1 when the levels below the finest that make corrections hold
//!  every voxel a cut of the model can need, else 0)
//!  checksum: blake3 of the header above and the body below, 32 bytes
//!  per brick: level u32, brick coordinates 3 x u32, 64 bytes of flags (row y + 8 z,
//!  bit x: the voxels held), then per voxel held, x fastest: its centre slot per plane,
//!  3 x u32, and the plane it shows, u8 (3: the mean of the three)
//! ```
//!
//! The solid cube synthesized from plain exemplars is kept beside it, under a key of the
//! exemplars, seed and cube settings:
//!
//! ```text
//!  file  DIR/guided-cube-<key as 16 hex digits>.cache
//!  "solidtex guided cube 2\n"  key u64  side u32  channels u32   (little-endian)
//!  checksum: blake3 of the header above and the body below, 32 bytes
//!  per voxel, x fastest: its colours, channels x f32
//! ```
//!
//! A file of either name that does not hold its key is not overwritten: the run stops and
//! names it. A file that holds its key (solidtex wrote it) but whose checksum, size or
//! values are wrong, or that an older solidtex wrote (an earlier version of the format),
//! is [`Cached::Stale`]: the caller rebuilds and rewrites it.

use super::atomic;
use crate::error::{Error, Result};
use crate::synth::coords::{Held, MEAN};
use crate::synth::region::{BRICK, Bits, Sparse};
use rayon::prelude::*;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8] = b"solidtex guided cache 5\n";
const OLD_MAGICS: &[&[u8]] = &[
    b"solidtex guided cache 1\n",
    b"solidtex guided cache 2\n",
    b"solidtex guided cache 3\n",
    b"solidtex guided cache 4\n",
];
const HEADER: usize = 24 + 8 + 4 + 12 + 4;
const PER_VOXEL: usize = 13;

const CUBE_MAGIC: &[u8] = b"solidtex guided cube 2\n";
const OLD_CUBE_MAGICS: &[&[u8]] = &[b"solidtex guided cube 1\n"];
const CUBE_HEADER: usize = 23 + 8 + 4 + 4;

/// Bytes of the checksum that follows a header.
const CHECKSUM: usize = 32;

/// What a cache file at a key's name holds.
#[derive(Debug, PartialEq)]
pub enum Cached<T> {
    /// There is no file.
    Missing,
    /// The file solidtex wrote under this key, intact.
    Good(T),
    /// A file solidtex wrote under this key that cannot be used (what is wrong, e.g.
    /// "damaged (its checksum does not match its contents)"): rebuild and rewrite it.
    Stale(String),
}

impl<T> Cached<T> {
    /// `f` of a good file's contents; a missing or stale file stays so.
    fn and_then<U>(self, f: impl FnOnce(T) -> Cached<U>) -> Cached<U> {
        match self {
            Cached::Missing => Cached::Missing,
            Cached::Good(found) => f(found),
            Cached::Stale(why) => Cached::Stale(why),
        }
    }
}

/// How long a cache file must be.
enum Size {
    /// Its header, checksum and a body of exactly this many bytes.
    Body(usize),
    /// At most this many bytes in all (a cap; longer is stale, not damaged).
    AtMost(u64),
}

/// The bytes of a cache file whose `header` bytes `ours` accepts, whose size fits `size`
/// and whose checksum holds; `None` when the file is not ours (another magic, key or size
/// in its header).
fn read_checked(
    path: &Path,
    header: usize,
    size: Size,
    ours: impl Fn(&[u8]) -> Option<Owner>,
) -> Result<Option<Cached<Vec<u8>>>> {
    let found = match std::fs::metadata(path) {
        Ok(meta) => meta.len(),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Some(Cached::Missing)),
        Err(e) => return Err(Error::io(path, e)),
    };
    let file = atomic::open_regular(path, u64::MAX)?;
    let mut head = Vec::with_capacity(header + CHECKSUM);
    file.take((header + CHECKSUM) as u64).read_to_end(&mut head).map_err(|e| Error::io(path, e))?;
    let Some(owner) = head.get(..header).and_then(&ours) else { return Ok(None) };
    if owner == Owner::Older {
        return Ok(Some(Cached::Stale("from an older solidtex (an earlier format)".to_string())));
    }
    let least = (header + CHECKSUM) as u64;
    let most = match size {
        Size::Body(body) if found != least + body as u64 => {
            return Ok(Some(damaged(format!("it holds {found} bytes, not {}", least + body as u64))));
        }
        Size::Body(body) => least + body as u64,
        Size::AtMost(cap) if found > cap => {
            return Ok(Some(Cached::Stale(format!("larger ({found} bytes) than the cache's cap of {cap} bytes"))));
        }
        Size::AtMost(cap) => cap,
    };
    let bytes = atomic::read_bytes_within(path, most)?;
    if (bytes.len() as u64) < least {
        return Ok(Some(damaged(format!("it holds {} bytes, fewer than its header", bytes.len()))));
    }
    let (fields, rest) = bytes.split_at(header);
    let (sum, content) = rest.split_at(CHECKSUM);
    if checksum(fields, content) != sum {
        return Ok(Some(damaged("its checksum does not match its contents".to_string())));
    }
    Ok(Some(Cached::Good(bytes)))
}

/// Who wrote a cache file whose header holds the key asked for.
#[derive(Debug, PartialEq)]
enum Owner {
    /// This version of the format.
    Current,
    /// An earlier version of the format.
    Older,
}

/// Which version of the format (`magic`, or one of the earlier `old`) `header` starts with.
fn owner(header: &[u8], magic: &[u8], old: &[&[u8]]) -> Option<Owner> {
    if header.starts_with(magic) {
        Some(Owner::Current)
    } else if old.iter().any(|o| header.starts_with(o)) {
        Some(Owner::Older)
    } else {
        None
    }
}

fn damaged<T>(why: String) -> Cached<T> {
    Cached::Stale(format!("damaged ({why})"))
}

/// The blake3 hash of a header's fields and the body.
fn checksum(fields: &[u8], body: &[u8]) -> [u8; CHECKSUM] {
    let mut hasher = blake3::Hasher::new();
    hasher.update(fields);
    hasher.update(body);
    *hasher.finalize().as_bytes()
}

/// Write a header's `fields`, their checksum with `body`, and `body` to `path`.
fn write_checked(path: &Path, fields: &[u8], body: &[u8]) -> Result<()> {
    let sum = checksum(fields, body);
    atomic::write_file(path, |w| {
        [fields, &sum[..], body].iter().try_for_each(|part| w.write_all(part)).map_err(|e| Error::io(path, e))
    })
}

fn le_u32(bytes: &[u8], at: usize) -> usize {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes")) as usize
}

fn le_u64(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("eight bytes"))
}

/// The error for a file at a cache's name that is not `what` solidtex wrote there (an empty
/// file said as such): it is left as it is.
fn not_ours(path: &Path, what: &str, hint: &str) -> Error {
    let empty = std::fs::metadata(path).is_ok_and(|m| m.len() == 0);
    let is = if empty { format!("is empty, not {what}") } else { format!("is not {what}") };
    Error::file(path, format!("{is}; solidtex does not overwrite it ({hint})"))
}

/// What to do about a file in a `--cache` folder that is not solidtex's.
pub const CACHE_HINT: &str = "move it away or give another --cache folder";

/// The cube file of `key` in `folder`.
pub fn cube_path(folder: &Path, key: u64) -> PathBuf {
    folder.join(format!("guided-cube-{key:016x}.cache"))
}

/// The cube's colours cached under `key` (`side`³ voxels of `channels`, each colour
/// within `range`), or an error naming the file when it is not solidtex's cube of `key`
/// (`hint`: what the user can do about it).
pub fn read_cube(
    path: &Path,
    key: u64,
    (side, channels): (usize, usize),
    range: (f32, f32),
    hint: &str,
) -> Result<Cached<Vec<f32>>> {
    let ours = |h: &[u8]| {
        let fits = le_u64(h, 23) == key && le_u32(h, 31) == side && le_u32(h, 35) == channels;
        owner(h, CUBE_MAGIC, OLD_CUBE_MAGICS).filter(|_| fits)
    };
    let found = read_checked(path, CUBE_HEADER, Size::Body(4 * side * side * side * channels), ours)?
        .ok_or_else(|| not_ours(path, "the solid cube of these exemplars", hint))?;
    Ok(found.and_then(|bytes| colours_within(&bytes[CUBE_HEADER + CHECKSUM..], range)))
}

/// The colours of a cube file's body, unless one lies outside `range`.
fn colours_within(body: &[u8], range: (f32, f32)) -> Cached<Vec<f32>> {
    let colours: Vec<f32> =
        body.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("four bytes"))).collect();
    match colours.iter().position(|c| !(range.0..=range.1).contains(c)) {
        Some(i) => damaged(format!("value {i} is {}, outside {} to {}", colours[i], range.0, range.1)),
        None => Cached::Good(colours),
    }
}

/// Write the cube's colours (`side`³ voxels of `channels`) under `key`.
pub fn write_cube(path: &Path, key: u64, side: usize, channels: usize, colours: &[f32]) -> Result<()> {
    let mut fields = Vec::with_capacity(CUBE_HEADER);
    fields.extend_from_slice(CUBE_MAGIC);
    fields.extend_from_slice(&key.to_le_bytes());
    fields.extend_from_slice(&(side as u32).to_le_bytes());
    fields.extend_from_slice(&(channels as u32).to_le_bytes());
    let body: Vec<u8> = colours.iter().flat_map(|c| c.to_le_bytes()).collect();
    write_checked(path, &fields, &body)
}

/// How many solid cubes a folder keeps: each edit of a model's photos makes a new one
/// (about 1 MB for three colours), so the least recently used go beyond this many.
pub const CUBES_KEPT: usize = 8;

/// How many brick caches a folder keeps: each edit of a model, spec, exemplar or seed makes
/// a new one, up to `--cache-mb` large (40-46 MB for the log at `--res 1024`).
pub const BRICKS_KEPT: usize = 4;

/// One kind of file solidtex keeps in a cache folder: its name's prefix (then the key as
/// 16 hex digits and `.cache`), its header's magics, length and where the key lies.
pub struct Kind {
    prefix: &'static str,
    magic: &'static [u8],
    old: &'static [&'static [u8]],
    header: usize,
    key_at: usize,
    /// How many a folder keeps.
    pub kept: usize,
}

/// Solid cubes.
pub const CUBES: Kind = Kind {
    prefix: "guided-cube-",
    magic: CUBE_MAGIC,
    old: OLD_CUBE_MAGICS,
    header: CUBE_HEADER,
    key_at: 23,
    kept: CUBES_KEPT,
};
/// Brick caches.
pub const BRICK_CACHES: Kind =
    Kind { prefix: "guided-", magic: MAGIC, old: OLD_MAGICS, header: 24 + 8, key_at: 24, kept: BRICKS_KEPT };

impl Kind {
    /// The key a file's name gives.
    fn key_of(&self, name: &str) -> Option<u64> {
        let hex = name.strip_prefix(self.prefix)?.strip_suffix(".cache")?;
        (hex.len() == 16).then(|| u64::from_str_radix(hex, 16).ok()).flatten()
    }

    /// Whether the file at `path` (not followed if a link) is one solidtex wrote under
    /// `key`: a regular file whose header is this kind's, of this or an earlier format,
    /// holding `key`.
    fn is_ours(&self, path: &Path, key: u64) -> bool {
        if !std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file()) {
            return false;
        }
        let mut head = vec![0u8; self.header];
        let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
        read.is_ok() && owner(&head, self.magic, self.old).is_some() && le_u64(&head, self.key_at) == key
    }
}

/// Marks the file at `path` as used now, so that [`prune`] keeps it longer (where the
/// file cannot be written to, nothing changes).
pub fn mark_used(path: &Path) {
    if let Ok(file) = std::fs::File::options().write(true).open(path) {
        // a file that cannot be marked is only pruned sooner
        let _ = file.set_modified(std::time::SystemTime::now());
    }
}

/// Removes the files of `kind` solidtex wrote in `folder` beyond the `kind.kept` most
/// recently used (by modification time), never `current`: only regular files named as
/// that kind whose header is that kind's of the key the name gives; anything else there
/// is left as it is. The files removed.
pub fn prune(folder: &Path, current: &Path, kind: &Kind) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(folder) else { return Vec::new() };
    let mut found: Vec<(std::time::SystemTime, PathBuf)> = entries
        .flatten()
        .filter_map(|entry| {
            let key = kind.key_of(entry.file_name().to_str()?)?;
            let path = entry.path();
            let used = std::fs::symlink_metadata(&path).and_then(|m| m.modified()).ok()?;
            (path != current && kind.is_ours(&path, key)).then_some((used, path))
        })
        .collect();
    // newest first; the name decides between equal times, so the choice does not depend on
    // the order the folder lists its files in
    found.sort_by(|a, b| b.0.cmp(&a.0).then_with(|| a.1.cmp(&b.1)));
    let stale = found.into_iter().skip(kind.kept.saturating_sub(1)).map(|(_, path)| path);
    stale.filter(|path| std::fs::remove_file(path).is_ok()).collect()
}

/// The cache file of `key` in `folder`.
pub fn path(folder: &Path, key: u64) -> PathBuf {
    folder.join(format!("guided-{key:016x}.cache"))
}

/// Bytes of a brick's entry before its voxels: level, coordinates and flags.
const BRICK_HEAD: usize = 16 + BRICK * BRICK;

/// The most bytes a cache file of `bricks` bricks (every voxel of each held) takes.
pub fn file_bytes(bricks: usize) -> u64 {
    (HEADER + CHECKSUM + bricks * (BRICK_HEAD + BRICK * BRICK * BRICK * PER_VOXEL)) as u64
}

/// The bricks cached under `key` for a grid whose levels have `dims` (coarsest first), one
/// store per level, or an error naming the file when it is not solidtex's cache of `key`.
/// A file over `most` bytes is stale (made under a larger cap). Every slot is checked
/// against `slots[level][plane]` (the exemplar centre counts).
pub fn read(path: &Path, key: u64, dims: &[[usize; 3]], slots: &[[usize; 3]], most: u64) -> Result<Cached<Bricks>> {
    let finest = dims.last().copied().unwrap_or_default();
    let ours = |h: &[u8]| {
        let fits =
            le_u64(h, 24) == key && le_u32(h, 32) == dims.len() && [36, 40, 44].map(|at| le_u32(h, at)) == finest;
        let flag = h.get(48..52).is_some_and(|_| le_u32(h, 48) <= 1);
        owner(h, MAGIC, OLD_MAGICS).filter(|o| fits && (flag || *o == Owner::Older))
    };
    let found = read_checked(path, HEADER, Size::AtMost(most), ours)?
        .ok_or_else(|| not_ours(path, "the guided-synthesis cache of these inputs", CACHE_HINT))?;
    Ok(found.and_then(|bytes| match bricks(&bytes[HEADER + CHECKSUM..], dims, slots) {
        Ok(levels) => Cached::Good(Bricks { levels, whole: le_u32(&bytes, 48) == 1 }),
        Err(why) => damaged(why),
    }))
}

/// What a cache holds: the bricks of each level, coarsest first, and whether its levels
/// below the finest that make corrections hold every voxel a cut of the model can need.
#[derive(Debug)]
pub struct Bricks {
    /// One store per level.
    pub levels: Vec<Sparse<Held>>,
    /// Whether the coarse levels are whole over the model.
    pub whole: bool,
}

/// A brick read back: its coordinates, flags and values.
type Brick = ([usize; 3], Bits, Vec<Held>);

/// A cache body's bricks, one store per level; what is wrong otherwise. The bricks' places
/// are found in one pass over their heads, their voxels decoded in parallel.
fn bricks(
    mut body: &[u8],
    dims: &[[usize; 3]],
    slots: &[[usize; 3]],
) -> std::result::Result<Vec<Sparse<Held>>, String> {
    let mut found: Vec<(usize, [usize; 3], &[u8])> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    while !body.is_empty() {
        if body.len() < BRICK_HEAD {
            return Err("a brick is cut short".to_string());
        }
        let level = le_u32(body, 0);
        let brick = [4, 8, 12].map(|at| le_u32(body, at));
        let Some(level_dims) = dims.get(level) else { return Err(format!("a brick of level {level}")) };
        let inside = (0..3).all(|a| brick[a] * BRICK < level_dims[a]);
        if !inside || !seen.insert((level, brick)) {
            return Err(format!("brick {brick:?} of level {level} lies outside the grid or comes twice"));
        }
        let held: usize = body[16..BRICK_HEAD].iter().map(|r| r.count_ones() as usize).sum();
        let end = BRICK_HEAD + held * PER_VOXEL;
        if body.len() < end {
            return Err("a brick is cut short".to_string());
        }
        found.push((level, brick, &body[..end]));
        body = &body[end..];
    }
    let decoded: Vec<(usize, Brick)> = found
        .into_par_iter()
        .map(|(level, brick, bytes)| Ok((level, decoded(bytes, brick, slots[level])?)))
        .collect::<std::result::Result<_, String>>()?;
    let mut levels: Vec<Vec<Brick>> = vec![Vec::new(); dims.len()];
    for (level, brick) in decoded {
        levels[level].push(brick);
    }
    Ok(levels.into_iter().zip(dims).map(|(bricks, d)| Sparse::from_bricks(*d, bricks)).collect())
}

/// One brick's entry (`bytes`, its head included) read back: its place, flags
/// and voxels, each slot checked against `slots` (the exemplar centre counts per plane).
fn decoded(bytes: &[u8], brick: [usize; 3], slots: [usize; 3]) -> std::result::Result<Brick, String> {
    let bits: Bits = bytes[16..BRICK_HEAD].try_into().expect("a brick's flags");
    let mut values = vec![Held::default(); BRICK * BRICK * BRICK];
    let mut at = BRICK_HEAD;
    for (k, value) in values.iter_mut().enumerate().filter(|(k, _)| bits[k / BRICK] >> (k % BRICK) & 1 == 1) {
        let slot = [0, 4, 8].map(|o| le_u32(bytes, at + o) as u32);
        let shown = bytes[at + 12];
        if (0..3).any(|a| slot[a] as usize >= slots[a]) {
            return Err(format!("voxel {k} of brick {brick:?} holds a pixel outside the exemplar"));
        }
        if shown > MEAN {
            return Err(format!("voxel {k} of brick {brick:?} shows plane {shown}, not 0-{MEAN}"));
        }
        *value = Held { slot, shown };
        at += PER_VOXEL;
    }
    Ok((brick, bits, values))
}

/// Write every level's bricks (`levels`, coarsest first, the finest of `levels.len()`
/// levels last) under `key`; `whole` as [`Bricks::whole`].
pub fn write(path: &Path, key: u64, levels: &[Sparse<Held>], whole: bool) -> Result<()> {
    let mut fields = Vec::with_capacity(HEADER);
    fields.extend_from_slice(MAGIC);
    fields.extend_from_slice(&key.to_le_bytes());
    fields.extend_from_slice(&(levels.len() as u32).to_le_bytes());
    for d in levels.last().map_or([0; 3], |l| l.dims) {
        fields.extend_from_slice(&(d as u32).to_le_bytes());
    }
    fields.extend_from_slice(&u32::from(whole).to_le_bytes());
    let mut body = Vec::new();
    for (level, values) in levels.iter().enumerate() {
        for (brick, bits, voxels) in values.bricks() {
            for c in [level, brick[0], brick[1], brick[2]] {
                body.extend_from_slice(&(c as u32).to_le_bytes());
            }
            body.extend_from_slice(bits);
            for (_, v) in voxels.iter().enumerate().filter(|(k, _)| bits[k / BRICK] >> (k % BRICK) & 1 == 1) {
                v.slot.iter().for_each(|s| body.extend_from_slice(&s.to_le_bytes()));
                body.push(v.shown);
            }
        }
    }
    write_checked(path, &fields, &body)
}

#[cfg(test)]
mod tests {
    use super::*;

    const RANGE: (f32, f32) = (-1.0, 2.0);

    fn stale_why<T: std::fmt::Debug>(found: Cached<T>) -> String {
        match found {
            Cached::Stale(why) => why,
            other => panic!("not stale: {other:?}"),
        }
    }

    /// Past the cubes kept, the least recently used of solidtex's own go; the current one,
    /// a user's file named as a cube, a cube under another key's name and a link stay.
    #[test]
    fn old_cubes_are_pruned_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let at = |key: u64| cube_path(dir.path(), key);
        let start = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
        for key in 1..=CUBES_KEPT as u64 + 3 {
            write_cube(&at(key), key, 1, 1, &[0.5]).unwrap();
            let file = std::fs::File::options().write(true).open(at(key)).unwrap();
            file.set_modified(start + std::time::Duration::from_secs(key * 60)).unwrap();
        }
        // key 1 is the oldest but the one in use; key 2 was read a moment ago
        mark_used(&at(2));
        std::fs::write(at(100), b"my notes").unwrap();
        std::fs::copy(at(4), at(101)).unwrap();
        let old_time = std::fs::metadata(at(3)).unwrap().modified().unwrap();
        std::fs::File::options().write(true).open(at(101)).unwrap().set_modified(old_time).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(at(5), at(102)).unwrap();
        let removed = prune(dir.path(), &at(1), &CUBES);
        // ten of ours besides key 1: the seven used last stay with it (2 and 6 to 11)
        assert_eq!(removed, vec![at(5), at(4), at(3)]);
        for key in [1, 2, 6, 7, 8, 9, 10, 11, 100, 101] {
            assert!(at(key).exists(), "{key}");
        }
        assert!(std::fs::symlink_metadata(at(102)).is_ok());
        assert_eq!(std::fs::read(at(100)).unwrap(), b"my notes");
        assert!(prune(dir.path(), &at(1), &CUBES).is_empty(), "nothing more to prune");
        // brick caches in the same folder: the three used last stay with the current one,
        // and pruning them leaves the cubes alone
        let bricks = |key: u64| path(dir.path(), key);
        let level = Sparse::compute(&crate::synth::region::Mask::full([2, 2, 2]), |_| Held::default());
        for key in 1..=6u64 {
            write(&bricks(key), key, std::slice::from_ref(&level), false).unwrap();
            let file = std::fs::File::options().write(true).open(bricks(key)).unwrap();
            file.set_modified(start + std::time::Duration::from_secs(key * 60)).unwrap();
        }
        assert_eq!(prune(dir.path(), &bricks(1), &BRICK_CACHES), vec![bricks(3), bricks(2)]);
        assert!([1, 4, 5, 6].iter().all(|&k| bricks(k).exists()));
        assert!([1, 2, 6, 7, 8, 9, 10, 11].iter().all(|&k| at(k).exists()), "the cubes stay");
    }

    /// A cube reads back as written; a missing file is `Missing`; a file with another
    /// key, side or channel count, or another magic, is refused by name, an empty one said
    /// to be empty.
    #[test]
    fn a_cube_reads_back_and_a_foreign_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = cube_path(dir.path(), 7);
        assert_eq!(read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap(), Cached::Missing);
        let colours: Vec<f32> = (0..24).map(|i| i as f32 / 24.0).collect();
        write_cube(&path, 7, 2, 3, &colours).unwrap();
        assert_eq!(read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap(), Cached::Good(colours));
        for (key, side, channels) in [(8, 2, 3), (7, 3, 3), (7, 2, 1)] {
            let err = read_cube(&path, key, (side, channels), RANGE, CACHE_HINT).unwrap_err().to_string();
            assert!(err.contains("guided-cube-") && err.contains("does not overwrite"), "{err}");
        }
        std::fs::write(&path, b"my notes").unwrap();
        assert!(
            read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap_err().to_string().contains("is not the solid cube")
        );
        std::fs::write(&path, b"").unwrap();
        let err = read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap_err().to_string();
        assert!(err.contains("is empty, not the solid cube") && err.contains("does not overwrite"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), b"", "left as it was");
    }

    /// A cube file of the key whose samples were overwritten (zeros, -1e30, one flipped
    /// bit), that was cut short, whose values lie outside the range, or that an older
    /// solidtex wrote, is stale; writing it again makes it good.
    #[test]
    fn a_damaged_cube_is_stale_and_rewritten() {
        let dir = tempfile::tempdir().unwrap();
        let path = cube_path(dir.path(), 7);
        let colours: Vec<f32> = (0..24).map(|i| i as f32 / 24.0).collect();
        write_cube(&path, 7, 2, 3, &colours).unwrap();
        let good = std::fs::read(&path).unwrap();
        let body = CUBE_HEADER + CHECKSUM;
        let mut zeros = good.clone();
        zeros[body..].fill(0);
        let mut huge = good.clone();
        huge[body + 8..body + 12].copy_from_slice(&(-1e30f32).to_le_bytes());
        let mut flipped = good.clone();
        flipped[body + 41] ^= 1;
        for (bytes, why) in
            [(zeros, "checksum"), (huge, "checksum"), (flipped, "checksum"), (good[..60].to_vec(), "bytes")]
        {
            std::fs::write(&path, bytes).unwrap();
            let found = stale_why(read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap());
            assert!(found.starts_with("damaged (") && found.contains(why), "{found}");
        }
        for bad in [-1e30, f32::NAN, 2.5] {
            let mut wild = colours.clone();
            wild[5] = bad;
            write_cube(&path, 7, 2, 3, &wild).unwrap();
            let found = stale_why(read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap());
            assert!(found.contains("value 5") && found.contains("outside -1 to 2"), "{found}");
        }
        let mut old = good.clone();
        old[..OLD_CUBE_MAGICS[0].len()].copy_from_slice(OLD_CUBE_MAGICS[0]);
        old.drain(CUBE_HEADER..body);
        std::fs::write(&path, old).unwrap();
        assert!(stale_why(read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap()).contains("older solidtex"));
        write_cube(&path, 7, 2, 3, &colours).unwrap();
        assert_eq!(read_cube(&path, 7, (2, 3), RANGE, CACHE_HINT).unwrap(), Cached::Good(colours));
    }

    /// Bricks of two levels read back as written, the plane each voxel shows with them;
    /// another key or grid is refused by name; a flipped byte, a slot outside the exemplar,
    /// a shown plane past the mean, a brick cut short, a file over the cap or the format
    /// before it makes it stale.
    #[test]
    fn bricks_read_back_and_damaged_ones_are_stale() {
        use crate::synth::region::Mask;
        let dir = tempfile::tempdir().unwrap();
        let path = path(dir.path(), 9);
        let dims = [[5, 4, 4], [10, 8, 7]];
        let voxel = |_: usize, slot: [u32; 3], shown: u8| Held { slot, shown };
        let read = |key, dims: &[[usize; 3]], slots: &[[usize; 3]], most| read(&path, key, dims, slots, most);
        let slots = [[40; 3], [40; 3]];
        assert!(matches!(read(9, &dims, &slots, 1 << 20).unwrap(), Cached::Missing));
        let value = |v: [usize; 3]| voxel(0, [v[0] as u32, v[1] as u32 + 4, v[2] as u32 + 8], (v[0] % 4) as u8);
        let mut fine = Mask::empty(dims[1]);
        [[9, 7, 6], [0, 0, 0], [3, 5, 1]].into_iter().for_each(|v| fine.insert(v));
        let levels = [Sparse::compute(&Mask::full(dims[0]), value), Sparse::compute(&fine, value)];
        write(&path, 9, &levels, true).unwrap();
        let Cached::Good(Bricks { levels: back, whole: true }) = read(9, &dims, &slots, 1 << 20).unwrap() else {
            panic!("not good, or not whole")
        };
        for (level, (b, l)) in back.iter().zip(&levels).enumerate() {
            let every = (0..dims[level].iter().product()).map(|i| crate::synth::region::grid_voxel(dims[level], i));
            for v in every {
                assert_eq!(b.holds(v), l.holds(v), "level {level} voxel {v:?}");
                assert_eq!(b.at(v.map(|c| c as i64)), l.at(v.map(|c| c as i64)), "level {level} voxel {v:?}");
            }
        }
        for (key, dims) in [(8, &dims[..]), (9, &[[5, 4, 4], [10, 8, 8]][..]), (9, &dims[1..])] {
            let err = read(key, dims, &slots, 1 << 20).unwrap_err().to_string();
            assert!(err.contains("guided-") && err.contains("does not overwrite"), "{err}");
        }
        assert!(stale_why(read(9, &dims, &[[40; 3], [40, 40, 9]], 1 << 20).unwrap()).contains("outside the exemplar"));
        let good = std::fs::read(&path).unwrap();
        assert!(stale_why(read(9, &dims, &slots, 1000).unwrap()).contains("cap of 1000 bytes"));
        let resealed = |bytes: &mut Vec<u8>| {
            let sum = checksum(&bytes[..HEADER], &bytes[HEADER + CHECKSUM..]);
            bytes[HEADER..HEADER + CHECKSUM].copy_from_slice(&sum);
        };
        let mut past = good.clone();
        past[HEADER + CHECKSUM + BRICK_HEAD + 12] = MEAN + 1;
        resealed(&mut past);
        std::fs::write(&path, &past).unwrap();
        assert!(stale_why(read(9, &dims, &slots, 1 << 20).unwrap()).contains("shows plane 4"));
        let mut short = good[..good.len() - 3].to_vec();
        resealed(&mut short);
        std::fs::write(&path, &short).unwrap();
        assert!(stale_why(read(9, &dims, &slots, 1 << 20).unwrap()).contains("cut short"));
        let mut older = good.clone();
        older[..MAGIC.len()].copy_from_slice(OLD_MAGICS[2]);
        std::fs::write(&path, older).unwrap();
        assert!(stale_why(read(9, &dims, &slots, 1 << 20).unwrap()).contains("older solidtex"));
        let mut flipped = good.clone();
        flipped[HEADER + CHECKSUM + 5] ^= 0x80;
        std::fs::write(&path, flipped).unwrap();
        assert!(stale_why(read(9, &dims, &slots, 1 << 20).unwrap()).contains("checksum"));
    }
}
