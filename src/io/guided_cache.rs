//! The cache of guided synthesis: a coarse level computed over the whole grid, kept
//! between cuts of the same model, field, exemplars and seed.
//!
//! ```text
//!  file  DIR/guided-<key as 16 hex digits>.cache
//!  "solidtex guided cache 1\n"  key u64  level u32  dims 3 x u32   (little-endian)
//!  per voxel, x fastest: its centre slot per plane, 3 x u32
//! ```
//!
//! The solid cube synthesized from plain exemplars is kept beside it, under a key of the
//! exemplars, seed and cube settings:
//!
//! ```text
//!  file  DIR/guided-cube-<key as 16 hex digits>.cache
//!  "solidtex guided cube 1\n"  key u64  side u32  channels u32   (little-endian)
//!  per voxel, x fastest: its colours, channels x f32
//! ```
//!
//! A file of either name that does not hold its key is not overwritten: the run stops and
//! names it.

use super::atomic;
use crate::error::{Error, Result};
use crate::guided::region::{Mask, Sparse};
use crate::guided::synth::Voxel;
use std::io::Write;
use std::path::{Path, PathBuf};

const MAGIC: &[u8] = b"solidtex guided cache 1\n";
const HEADER: usize = 24 + 8 + 4 + 12;
const PER_VOXEL: usize = 12;

const CUBE_MAGIC: &[u8] = b"solidtex guided cube 1\n";
const CUBE_HEADER: usize = 23 + 8 + 4 + 4;

/// The cube file of `key` in `folder`.
pub fn cube_path(folder: &Path, key: u64) -> PathBuf {
    folder.join(format!("guided-cube-{key:016x}.cache"))
}

/// The cube's colours cached under `key` (`side`³ voxels of `channels`), if the file exists.
pub fn read_cube(path: &Path, key: u64, side: usize, channels: usize) -> Result<Option<Vec<f32>>> {
    if !path.exists() {
        return Ok(None);
    }
    let count = side * side * side * channels;
    let foreign = || {
        Error::file(
            path,
            "is not the solid cube of these exemplars; solidtex does not overwrite it (move it away or give another \
             --cache folder)",
        )
    };
    let bytes = sized(path, CUBE_HEADER + 4 * count).ok_or_else(foreign)??;
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes")) as usize;
    let matches = bytes.starts_with(CUBE_MAGIC)
        && u64::from_le_bytes(bytes[23..31].try_into().expect("eight bytes")) == key
        && word(31) == side
        && word(35) == channels;
    if !matches {
        return Err(foreign());
    }
    let colours: Vec<f32> =
        bytes[CUBE_HEADER..].chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("four bytes"))).collect();
    if let Some(i) = colours.iter().position(|c| !c.is_finite()) {
        return Err(Error::file(path, format!("value {i} is not a finite number; the cache is damaged")));
    }
    Ok(Some(colours))
}

/// Write the cube's colours (`side`³ voxels of `channels`) under `key`.
pub fn write_cube(path: &Path, key: u64, side: usize, channels: usize, colours: &[f32]) -> Result<()> {
    let mut bytes = Vec::with_capacity(CUBE_HEADER + 4 * colours.len());
    bytes.extend_from_slice(CUBE_MAGIC);
    bytes.extend_from_slice(&key.to_le_bytes());
    bytes.extend_from_slice(&(side as u32).to_le_bytes());
    bytes.extend_from_slice(&(channels as u32).to_le_bytes());
    colours.iter().for_each(|c| bytes.extend_from_slice(&c.to_le_bytes()));
    atomic::write_file(path, |w| w.write_all(&bytes).map_err(|e| Error::io(path, e)))
}

/// The cache file of `key` in `folder`.
pub fn path(folder: &Path, key: u64) -> PathBuf {
    folder.join(format!("guided-{key:016x}.cache"))
}

/// The level cached under `key`, if the file exists: `(level, values)`. Every slot is
/// checked against `slots[plane]` (the level's exemplar centre counts); `voxel` makes a
/// voxel of its slots.
pub fn read(
    path: &Path,
    key: u64,
    dims: [usize; 3],
    slots: [usize; 3],
    voxel: impl Fn([u32; 3]) -> Voxel + Sync,
) -> Result<Option<(usize, Sparse<Voxel>)>> {
    if !path.exists() {
        return Ok(None);
    }
    let count: usize = dims.iter().product();
    let foreign = || {
        Error::file(
            path,
            "is not the guided-synthesis cache of these inputs; solidtex does not overwrite it (move it away or \
             give another --cache folder)",
        )
    };
    let bytes = sized(path, HEADER + count * PER_VOXEL).ok_or_else(foreign)??;
    if !bytes.starts_with(MAGIC) {
        return Err(foreign());
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes"));
    let stored_key = u64::from_le_bytes(bytes[24..32].try_into().expect("eight bytes"));
    let stored_dims = [word(36), word(40), word(44)].map(|d| d as usize);
    if stored_key != key || stored_dims != dims {
        return Err(foreign());
    }
    let level = word(32) as usize;
    let body = &bytes[HEADER..];
    let value = |i: usize| {
        let at = i * PER_VOXEL;
        [0, 4, 8].map(|o| u32::from_le_bytes(body[at + o..at + o + 4].try_into().expect("four bytes")))
    };
    let bad = (0..count).map(value).position(|v| (0..3).any(|a| v[a] as usize >= slots[a]));
    if let Some(i) = bad {
        return Err(Error::file(path, format!("voxel {i} holds a pixel outside the exemplar; the cache is damaged")));
    }
    let mask = Mask::full(dims);
    Ok(Some((level, Sparse::compute(&mask, |v| voxel(value(mask.index(v)))))))
}

/// The bytes of `path` if it holds exactly `size` of them (`None` when it holds another
/// number: not the file asked for).
fn sized(path: &Path, size: usize) -> Option<Result<Vec<u8>>> {
    match std::fs::metadata(path) {
        Ok(m) if m.len() != size as u64 => None,
        Ok(_) => Some(atomic::read_bytes_within(path, size as u64)),
        Err(e) => Some(Err(Error::io(path, e))),
    }
}

/// Write `values` (the whole grid of `level`) under `key`.
pub fn write(path: &Path, key: u64, level: usize, values: &Sparse<Voxel>) -> Result<()> {
    let dims = values.dims;
    let count: usize = dims.iter().product();
    let mut bytes = Vec::with_capacity(HEADER + count * PER_VOXEL);
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&key.to_le_bytes());
    bytes.extend_from_slice(&(level as u32).to_le_bytes());
    for d in dims {
        bytes.extend_from_slice(&(d as u32).to_le_bytes());
    }
    let mask = Mask::full(dims);
    for i in 0..count {
        let v = values.at(mask.voxel(i).map(|c| c as i64));
        for s in v.slot {
            bytes.extend_from_slice(&s.to_le_bytes());
        }
    }
    atomic::write_file(path, |w| w.write_all(&bytes).map_err(|e| Error::io(path, e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cube reads back as written; a missing file is `None`; a file with another key,
    /// side or channel count, a truncated one and one holding a NaN are refused by name.
    #[test]
    fn a_cube_reads_back_and_anything_else_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = cube_path(dir.path(), 7);
        assert!(read_cube(&path, 7, 2, 3).unwrap().is_none());
        let colours: Vec<f32> = (0..24).map(|i| i as f32 / 24.0).collect();
        write_cube(&path, 7, 2, 3, &colours).unwrap();
        assert_eq!(read_cube(&path, 7, 2, 3).unwrap().unwrap(), colours);
        for (key, side, channels) in [(8, 2, 3), (7, 3, 3), (7, 2, 1)] {
            let err = read_cube(&path, key, side, channels).unwrap_err().to_string();
            assert!(err.contains("guided-cube-") && err.contains("does not overwrite"), "{err}");
        }
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 4]).unwrap();
        assert!(read_cube(&path, 7, 2, 3).unwrap_err().to_string().contains("not the solid cube"));
        let mut nan = bytes.clone();
        let at = nan.len() - 4;
        nan[at..].copy_from_slice(&f32::NAN.to_le_bytes());
        std::fs::write(&path, &nan).unwrap();
        let err = read_cube(&path, 7, 2, 3).unwrap_err().to_string();
        assert!(err.contains("value 23") && err.contains("damaged"), "{err}");
    }
}
