//! Kopf's `.vol`: the interchange format of solid texture synthesis tools.
//!
//! ```text
//! offset  size  field
//!      0     4  magic "VOLU"
//!      4     4  version, i32 = 4
//!      8   256  texture name, NUL-padded
//!    264     1  wrap (tileable), bool; 3 bytes padding
//!    268     4  volSize, i32: the side of the cube
//!    272     4  numChannels, i32
//!    276     4  bytesPerChannel, i32: 1 (u8) or 4 (f32)
//!    280  3816  zero padding up to 4096
//!   4096     -  volSize^3 voxels, x fastest, channels interleaved
//! ```
//! All integers little-endian. The format holds cubes only and no channel names:
//! roles are assigned by position on reading (grey, grey+A, RGB, RGBA, extras).
//! solidtex writes f32 samples (bytesPerChannel = 4), so a round trip is exact.

use crate::error::{Error, Result};
use crate::volume::Volume;
use std::path::Path;

const HEADER: usize = 4096;

/// Write `volume` as `.vol` with f32 samples (atomically); `name` goes into the header.
pub fn write(path: &Path, volume: &Volume, name: &str) -> Result<()> {
    let [x, y, z] = volume.dims();
    if x != y || y != z {
        return Err(Error::file(
            path,
            format!("Kopf .vol holds cubes only; this volume is {x}x{y}x{z} (convert to .exr or .nrrd instead)"),
        ));
    }
    let mut bytes = vec![0u8; HEADER];
    bytes[0..4].copy_from_slice(b"VOLU");
    bytes[4..8].copy_from_slice(&4i32.to_le_bytes());
    let name = name.as_bytes();
    let len = name.len().min(255);
    bytes[8..8 + len].copy_from_slice(&name[..len]);
    bytes[264] = 1;
    bytes[268..272].copy_from_slice(&(x as i32).to_le_bytes());
    bytes[272..276].copy_from_slice(&(volume.channel_count() as i32).to_le_bytes());
    bytes[276..280].copy_from_slice(&4i32.to_le_bytes());
    bytes.reserve(volume.data().len() * 4);
    for v in volume.data() {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    super::atomic::write_bytes(path, &bytes)
}

/// Read a `.vol` file (u8 or f32 samples).
pub fn read(path: &Path, budget: u64) -> Result<Volume> {
    let bytes = super::atomic::read_bytes_within(path, super::atomic::file_cap(budget))?;
    parse(&bytes, budget).map_err(|e| e.in_file(path))
}

fn int(bytes: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

fn parse(bytes: &[u8], budget: u64) -> Result<Volume> {
    if bytes.len() < HEADER {
        return Err(Error::invalid(format!(
            "truncated .vol: {} bytes, shorter than the 4096-byte header",
            bytes.len()
        )));
    }
    if &bytes[0..4] != b"VOLU" {
        return Err(Error::invalid("not a Kopf .vol file: the magic is not \"VOLU\""));
    }
    let version = int(bytes, 4);
    if version != 4 {
        return Err(Error::invalid(format!(".vol version {version} is not supported; allowed: 4")));
    }
    let (side, n, width) = (int(bytes, 268), int(bytes, 272), int(bytes, 276));
    if side <= 0 || n <= 0 {
        return Err(Error::invalid(format!(
            ".vol header gives volSize {side} and numChannels {n}; both must be at least 1"
        )));
    }
    if width != 1 && width != 4 {
        return Err(Error::invalid(format!(".vol bytesPerChannel {width} is not supported; allowed: 1 or 4")));
    }
    let (side, n, width) = (side as usize, n as usize, width as usize);
    crate::volume::check_size([side; 3], n, budget)?;
    let need = side * side * side * n * width;
    let body = &bytes[HEADER..];
    if body.len() < need {
        return Err(Error::invalid(format!(
            "truncated .vol: the header promises {need} bytes of samples, the file holds {}",
            body.len()
        )));
    }
    let data: Vec<f32> = if width == 1 {
        body[..need].iter().map(|b| *b as f32 / 255.0).collect()
    } else {
        body[..need].chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
    };
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(format!(".vol sample {i} is {}; NaN and infinity are not allowed", data[i])));
    }
    let mut volume = Volume::from_data([side; 3], super::nrrd::default_channels(n), data)?;
    let name = name_of(bytes);
    if !name.is_empty() {
        volume.meta.set("name", name);
    }
    Ok(volume)
}

/// The texture name stored in a `.vol` header: a C string of single-byte characters,
/// read as Latin-1 (so every byte is a character that EXR and PNG text can hold),
/// control characters left out.
fn name_of(bytes: &[u8]) -> String {
    let raw = &bytes[8..264.min(bytes.len())];
    let end = raw.iter().position(|b| *b == 0).unwrap_or(raw.len());
    raw[..end].iter().map(|b| char::from(*b)).filter(|c| !c.is_control()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_byte_volumes_and_checks_the_header() {
        let mut bytes = vec![0u8; HEADER];
        bytes[0..4].copy_from_slice(b"VOLU");
        bytes[4..8].copy_from_slice(&4i32.to_le_bytes());
        bytes[8..12].copy_from_slice(b"kiwi");
        bytes[268..272].copy_from_slice(&2i32.to_le_bytes());
        bytes[272..276].copy_from_slice(&1i32.to_le_bytes());
        bytes[276..280].copy_from_slice(&1i32.to_le_bytes());
        bytes.extend_from_slice(&[0, 51, 102, 153, 204, 255, 0, 255]);
        let v = parse(&bytes, u64::MAX).unwrap();
        assert_eq!(v.dims(), [2, 2, 2]);
        assert_eq!(v.get(1, 0, 0, 0), 0.2);
        assert_eq!(name_of(&bytes), "kiwi");
        bytes[8..12].copy_from_slice(b"k\xe9w\xed");
        assert_eq!(name_of(&bytes), "k\u{e9}w\u{ed}", "a Latin-1 name reads as its characters");
        bytes[4] = 3;
        assert!(parse(&bytes, u64::MAX).unwrap_err().to_string().contains("version 3"));
    }
}
