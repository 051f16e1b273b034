//! DDS volume textures (`.dds`) for DirectX engines: one uncompressed RGBA texture with
//! a depth, the DX10 header (through the `ddsfile` crate), no mipmaps.
//!
//! RGBA comes from R, G, B and A (a grey volume's channel three times; alpha 1 where the
//! volume has none); other channels are not stored. Pixel formats: RGBA8 (unsigned
//! normalized), RGBA16F (half floats, the default) and RGBA32F. Reading gives an RGBA
//! volume; the size in the header is checked against the data and the budget first.

use crate::error::{Error, Result};
use crate::volume::{Channel, Volume};
use ddsfile::{AlphaMode, Caps2, D3D10ResourceDimension, Dds, DxgiFormat, NewDxgiParams};
use std::path::Path;

/// The pixel formats written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DdsFormat {
    /// 8 bits per channel, [0, 1] (`DXGI_FORMAT_R8G8B8A8_UNORM`).
    Rgba8,
    /// Half floats (`DXGI_FORMAT_R16G16B16A16_FLOAT`).
    Rgba16F,
    /// Floats (`DXGI_FORMAT_R32G32B32A32_FLOAT`).
    Rgba32F,
}

impl DdsFormat {
    /// The names the command line takes.
    pub const NAMES: [&str; 3] = ["rgba8", "rgba16f", "rgba32f"];

    /// The format named `text` (one of [`DdsFormat::NAMES`]).
    pub fn parse(text: &str) -> Result<DdsFormat> {
        match text {
            "rgba8" => Ok(DdsFormat::Rgba8),
            "rgba16f" => Ok(DdsFormat::Rgba16F),
            "rgba32f" => Ok(DdsFormat::Rgba32F),
            other => Err(Error::invalid(format!(
                "DDS format {other:?} is unknown; allowed: {}",
                DdsFormat::NAMES.join(", ")
            ))),
        }
    }

    fn dxgi(self) -> DxgiFormat {
        match self {
            DdsFormat::Rgba8 => DxgiFormat::R8G8B8A8_UNorm,
            DdsFormat::Rgba16F => DxgiFormat::R16G16B16A16_Float,
            DdsFormat::Rgba32F => DxgiFormat::R32G32B32A32_Float,
        }
    }
}

/// Write `volume` as a DDS volume texture (atomically).
pub fn write(path: &Path, volume: &Volume, format: DdsFormat) -> Result<()> {
    super::atomic::write_bytes(path, &to_bytes(volume, format)?)
}

/// Read a DDS volume texture within `budget` bytes of voxels.
pub fn read(path: &Path, budget: u64) -> Result<Volume> {
    let bytes = super::atomic::read_bytes_within(path, super::atomic::file_cap(budget))?;
    parse(&bytes, budget).map_err(|e| e.in_file(path))
}

/// The RGBA of every voxel, x fastest.
fn rgba(volume: &Volume) -> Vec<[f32; 4]> {
    let channels = volume.channels();
    let find = |role: Channel| channels.iter().position(|c| *c == role);
    let r = find(Channel::R).unwrap_or(0);
    let (g, b) = (find(Channel::G).unwrap_or(r), find(Channel::B).unwrap_or(r));
    let a = find(Channel::A);
    volume.data().chunks_exact(volume.channel_count()).map(|v| [v[r], v[g], v[b], a.map_or(1.0, |a| v[a])]).collect()
}

fn to_bytes(volume: &Volume, format: DdsFormat) -> Result<Vec<u8>> {
    let [x, y, z] = volume.dims().map(|d| d as u32);
    let mut dds = Dds::new_dxgi(NewDxgiParams {
        height: y,
        width: x,
        depth: Some(z),
        format: format.dxgi(),
        mipmap_levels: None,
        array_layers: None,
        caps2: Some(Caps2::VOLUME),
        is_cubemap: false,
        resource_dimension: D3D10ResourceDimension::Texture3D,
        alpha_mode: AlphaMode::Straight,
    })
    .map_err(|e| Error::invalid(format!("cannot make a DDS volume texture: {e}")))?;
    dds.data =
        rgba(volume).iter().flat_map(|p| p.iter().flat_map(|v| encode(*v, format)).collect::<Vec<u8>>()).collect();
    let mut out = Vec::new();
    dds.write(&mut out).map_err(|e| Error::invalid(format!("cannot write the DDS: {e}")))?;
    Ok(out)
}

fn encode(v: f32, format: DdsFormat) -> Vec<u8> {
    match format {
        DdsFormat::Rgba8 => vec![(v.clamp(0.0, 1.0) * 255.0).round() as u8],
        DdsFormat::Rgba16F => half::f16::from_f32(v).to_le_bytes().to_vec(),
        DdsFormat::Rgba32F => v.to_le_bytes().to_vec(),
    }
}

/// The name of a DDS file's pixel format, as its header gives it (e.g. `BC1_UNorm`).
fn format_name(dds: &Dds) -> String {
    match (dds.get_dxgi_format(), dds.get_d3d_format()) {
        (Some(dxgi), _) => format!("{dxgi:?}"),
        (None, Some(d3d)) => format!("{d3d:?} (a DX9 header)"),
        (None, None) => "unknown to solidtex".to_string(),
    }
}

fn parse(bytes: &[u8], budget: u64) -> Result<Volume> {
    let dds = Dds::read(bytes).map_err(|e| Error::invalid(format!("not a DDS file: {e}")))?;
    let format = match dds.get_dxgi_format() {
        Some(DxgiFormat::R8G8B8A8_UNorm) => DdsFormat::Rgba8,
        Some(DxgiFormat::R16G16B16A16_Float) => DdsFormat::Rgba16F,
        Some(DxgiFormat::R32G32B32A32_Float) => DdsFormat::Rgba32F,
        _ => {
            return Err(Error::invalid(format!(
                "pixel format {} is not supported; allowed: uncompressed RGBA8, RGBA16F and RGBA32F with a DX10 header",
                format_name(&dds)
            )));
        }
    };
    if dds.header.depth == Some(0) {
        return Err(Error::invalid(
            "the header marks a volume (its depth flag is set) of depth 0; a volume has at least 1 slice",
        ));
    }
    let dims = [dds.get_width(), dds.get_height(), dds.get_depth()].map(|d| d as usize);
    let sample = match format {
        DdsFormat::Rgba8 => 1,
        DdsFormat::Rgba16F => 2,
        DdsFormat::Rgba32F => 4,
    };
    if dims.contains(&0) {
        return Err(Error::invalid(format!(
            "the header says {}x{}x{} voxels; every side must be at least 1",
            dims[0], dims[1], dims[2]
        )));
    }
    let need = dims.iter().try_fold(4 * sample, |acc: usize, d| acc.checked_mul(*d));
    if need.is_none_or(|n| n > dds.data.len()) {
        return Err(Error::invalid(format!(
            "the header says {}x{}x{} voxels, which the {} bytes of data cannot hold",
            dims[0],
            dims[1],
            dims[2],
            dds.data.len()
        )));
    }
    crate::volume::check_size(dims, 4, budget)?;
    let voxels = dims.iter().product::<usize>() * 4;
    let samples: Vec<f32> = dds.data[..voxels * sample]
        .chunks_exact(sample)
        .map(|b| match format {
            DdsFormat::Rgba8 => b[0] as f32 / 255.0,
            DdsFormat::Rgba16F => half::f16::from_le_bytes([b[0], b[1]]).to_f32(),
            DdsFormat::Rgba32F => f32::from_le_bytes(b.try_into().expect("4 bytes")),
        })
        .collect();
    if samples.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid("a sample is not a finite number"));
    }
    Volume::from_data(dims, Channel::rgba(), samples)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Volume {
        Volume::from_fn([5, 3, 7], Channel::rgba(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 4.0, y as f32 / 2.0, z as f32 / 6.0, 0.25 + x as f32 / 8.0]);
        })
        .unwrap()
    }

    /// Each pixel format round-trips within its precision; the header names a 3D texture.
    #[test]
    fn each_format_round_trips_within_its_precision() {
        let v = sample();
        for (format, tolerance) in
            [(DdsFormat::Rgba32F, 0.0), (DdsFormat::Rgba16F, 1e-3), (DdsFormat::Rgba8, 0.5 / 255.0 + 1e-6)]
        {
            let bytes = to_bytes(&v, format).unwrap();
            let dds = Dds::read(&bytes[..]).unwrap();
            assert_eq!((dds.get_width(), dds.get_height(), dds.get_depth()), (5, 3, 7));
            let back = parse(&bytes, u64::MAX).unwrap();
            assert_eq!(back.dims(), v.dims());
            let worst = back.data().iter().zip(v.data()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
            assert!(worst <= tolerance, "{format:?}: off by {worst}");
        }
    }

    #[test]
    fn a_grey_volume_is_grey_and_opaque() {
        let v = Volume::from_fn([2, 2, 2], Channel::grey(), |x, _, _, o| o[0] = x as f32).unwrap();
        let back = parse(&to_bytes(&v, DdsFormat::Rgba32F).unwrap(), u64::MAX).unwrap();
        assert_eq!(&back.data()[4..8], &[1.0, 1.0, 1.0, 1.0]);
    }

    /// A compressed format is refused by its plain name.
    #[test]
    fn another_pixel_format_is_named_plainly() {
        let mut bytes = to_bytes(&sample(), DdsFormat::Rgba8).unwrap();
        // the DX10 header's DXGI format, after the magic and the 124-byte header
        bytes[128..132].copy_from_slice(&(DxgiFormat::BC1_UNorm as u32).to_le_bytes());
        let err = parse(&bytes, u64::MAX).unwrap_err().to_string();
        assert!(err.starts_with("pixel format BC1_UNorm is not supported; allowed:"), "{err}");
    }

    #[test]
    fn a_header_bigger_than_its_data_is_refused() {
        let mut bytes = to_bytes(&sample(), DdsFormat::Rgba8).unwrap();
        bytes.truncate(bytes.len() - 10);
        let err = parse(&bytes, u64::MAX).unwrap_err().to_string();
        assert!(err.contains("5x3x7") && err.contains("cannot hold"), "{err}");
        for cut in 0..148 {
            assert!(parse(&bytes[..cut], u64::MAX).is_err());
        }
    }

    /// A depth of 0 with the depth flag set is refused, not read as one slice of the data.
    #[test]
    fn a_volume_header_of_depth_zero_is_refused() {
        let mut bytes = to_bytes(&sample(), DdsFormat::Rgba8).unwrap();
        // the depth field: after the magic, the header's size, flags, height and width
        bytes[24..28].copy_from_slice(&0u32.to_le_bytes());
        let err = parse(&bytes, u64::MAX).unwrap_err().to_string();
        assert!(err.contains("depth 0"), "{err}");
        // a height of 0 is named as a side of 0, not as data too short
        let mut bytes = to_bytes(&sample(), DdsFormat::Rgba8).unwrap();
        bytes[12..16].copy_from_slice(&0u32.to_le_bytes());
        let err = parse(&bytes, u64::MAX).unwrap_err().to_string();
        assert!(err.contains("x0x") && err.contains("every side must be at least 1"), "{err}");
    }
}
