//! 8-bit PNG: the volume atlas, slice stacks, and plain RGB pictures.
//!
//! Atlas and slice PNGs carry a `tEXt` chunk with keyword `solidtex` holding
//! `key: value` lines (`dims`, `channels`, `type`, `provenance.*`, and for a slice
//! `slice`), so they read back as volumes. PNG holds 1 to 4 channels
//! (grey, grey+alpha, RGB, RGBA); samples are rounded to the nearest 1/255.

use super::{atlas, fields};
use crate::error::{Error, Result};
use crate::render::{Rgb8, to_u8};
use crate::volume::{Channel, Image2d, Volume};
use std::fs;
use std::path::{Path, PathBuf};

const KEYWORD: &str = "solidtex";

fn colour_type(n: usize, path: &Path, names: &str) -> Result<png::ColorType> {
    Ok(match n {
        1 => png::ColorType::Grayscale,
        2 => png::ColorType::GrayscaleAlpha,
        3 => png::ColorType::Rgb,
        4 => png::ColorType::Rgba,
        _ => {
            return Err(Error::file(
                path,
                format!("PNG holds 1 to 4 channels; this volume has {n} ({names}); use .exr or .nrrd"),
            ));
        }
    })
}

/// Encode 8-bit samples with an optional solidtex text chunk, atomically.
fn write_png(
    path: &Path,
    size: (usize, usize),
    colour: png::ColorType,
    bytes: &[u8],
    text: Option<String>,
) -> Result<()> {
    super::atomic::write_file(path, |w| {
        let fail = |e: png::EncodingError| Error::file(path, format!("cannot write PNG: {e}"));
        let mut encoder = png::Encoder::new(w, size.0 as u32, size.1 as u32);
        encoder.set_color(colour);
        encoder.set_depth(png::BitDepth::Eight);
        if let Some(text) = text {
            encoder.add_text_chunk(KEYWORD.to_string(), latin1(&text)).map_err(fail)?;
        }
        let mut writer = encoder.write_header().map_err(fail)?;
        writer.write_image_data(bytes).map_err(fail)?;
        writer.finish().map_err(fail)
    })
}

/// `text` with every character outside Latin-1 (which a tEXt chunk cannot hold) as `?`.
fn latin1(text: &str) -> String {
    text.chars().map(|c| if (c as u32) < 256 { c } else { '?' }).collect()
}

/// Write the volume's flipbook atlas as an 8-bit PNG.
pub fn write_atlas(path: &Path, volume: &Volume) -> Result<()> {
    let colour = colour_type(volume.channel_count(), path, &crate::volume::channel_names(volume.channels()))?;
    let (w, h, data) = atlas::to_atlas(volume);
    let bytes: Vec<u8> = data.iter().map(|v| to_u8(*v)).collect();
    write_png(path, (w, h), colour, &bytes, Some(fields::to_lines(&fields::fields(volume))))
}

/// Write a picture.
pub fn write_rgb8(path: &Path, picture: &Rgb8) -> Result<()> {
    write_png(path, (picture.width, picture.height), png::ColorType::Rgb, &picture.data, None)
}

/// An 8-bit RGB picture encoded as PNG, in memory (to embed in another file).
pub fn rgb8_bytes(picture: &Rgb8) -> Result<Vec<u8>> {
    let fail = |e: png::EncodingError| Error::invalid(format!("cannot encode PNG: {e}"));
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, picture.width as u32, picture.height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(fail)?;
    writer.write_image_data(&picture.data).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(bytes)
}

/// Write a 2D image with 1 to 4 channels as an 8-bit PNG.
pub fn write_image(path: &Path, image: &Image2d) -> Result<()> {
    let colour = colour_type(image.channel_count(), path, &crate::volume::channel_names(image.channels()))?;
    let bytes: Vec<u8> = image.data().iter().map(|v| to_u8(*v)).collect();
    write_png(path, (image.width(), image.height()), colour, &bytes, None)
}

/// Write each z-slice as `z0000.png`, `z0001.png` ... into the folder `path` (atomically).
pub fn write_stack(path: &Path, volume: &Volume) -> Result<()> {
    let n = volume.channel_count();
    let colour = colour_type(n, path, &crate::volume::channel_names(volume.channels()))?;
    let [dx, dy, dz] = volume.dims();
    let mut text = fields::fields(volume);
    super::atomic::write_folder(path, |folder| {
        for z in 0..dz {
            let start = volume.index(0, 0, z) * n;
            let bytes: Vec<u8> = volume.data()[start..start + dx * dy * n].iter().map(|v| to_u8(*v)).collect();
            text.retain(|(k, _)| k != "slice");
            text.push(("slice".to_string(), z.to_string()));
            write_png(&folder.join(format!("z{z:04}.png")), (dx, dy), colour, &bytes, Some(fields::to_lines(&text)))?;
        }
        Ok(())
    })
}

/// A decoded PNG: size, channel count, samples in [0, 1], and its solidtex text.
struct Decoded {
    width: usize,
    height: usize,
    channels: usize,
    samples: Vec<f32>,
    text: Option<String>,
}

/// Decode a PNG whose samples, as f32, fit in `budget` bytes; the size in its header is
/// checked before any pixel memory is taken.
fn decode(path: &Path, budget: u64) -> Result<Decoded> {
    let fail = |e: png::DecodingError| Error::file(path, format!("cannot read PNG (corrupt or truncated?): {e}"));
    let file = super::atomic::open_regular(path, super::atomic::file_cap(budget))?;
    let limits = png::Limits { bytes: usize::try_from(budget).unwrap_or(usize::MAX) };
    let mut decoder = png::Decoder::new_with_limits(std::io::BufReader::new(file), limits);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(fail)?;
    let text = reader.info().uncompressed_latin1_text.iter().find(|t| t.keyword == KEYWORD).map(|t| t.text.clone());
    let (width, height) = reader.info().size();
    let (colour, _) = reader.output_color_type();
    let needed = width as u128 * height as u128 * colour.samples() as u128 * 4;
    if needed > budget as u128 {
        return Err(Error::file(
            path,
            format!(
                "a {width}x{height} PNG with {} channel(s) needs {needed} bytes as samples, over the voxel budget of \
                 {budget} bytes (raise it with SOLIDTEX_MAX_BYTES)",
                colour.samples()
            ),
        ));
    }
    let size = reader.output_buffer_size().ok_or_else(|| Error::file(path, "PNG is too large to decode"))?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(fail)?;
    let channels = info.color_type.samples();
    let samples = match info.bit_depth {
        png::BitDepth::Sixteen => buf[..info.buffer_size()]
            .chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]) as f32 / 65535.0)
            .collect(),
        _ => buf[..info.buffer_size()].iter().map(|b| *b as f32 / 255.0).collect(),
    };
    Ok(Decoded { width: info.width as usize, height: info.height as usize, channels, samples, text })
}

/// The size a solidtex volume atlas' description names, read from a PNG's header alone;
/// `None` for a slice (its description names the slice), any other PNG, or bytes that are
/// no PNG.
pub fn volume_dims(bytes: &[u8]) -> Option<[usize; 3]> {
    let reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().ok()?;
    let text = reader.info().uncompressed_latin1_text.iter().find(|t| t.keyword == KEYWORD)?;
    let lines = fields::from_lines(&text.text);
    if lines.iter().any(|(key, _)| key == "slice") {
        return None;
    }
    fields::parse(&lines).ok()?.dims
}

/// Read a PNG atlas written by [`write_atlas`].
pub fn read_atlas(path: &Path, budget: u64) -> Result<Volume> {
    let png = decode(path, budget)?;
    let text = png.text.as_deref().ok_or_else(|| {
        Error::file(path, "this PNG has no solidtex atlas description (tEXt 'solidtex'); it is a plain 2D image")
    })?;
    let described = fields::parse(&fields::from_lines(text)).map_err(|e| e.in_file(path))?;
    let dims = described.dims.ok_or_else(|| Error::file(path, "the solidtex description has no dims"))?;
    let channels = channels_for(described.channels, png.channels, path)?;
    crate::volume::check_size(dims, channels.len(), budget).map_err(|e| e.in_file(path))?;
    let v = atlas::from_atlas(dims, channels, png.width, png.height, &png.samples).map_err(|e| e.in_file(path))?;
    Ok(v.with_meta(described.meta).with_model_grid(described.model_grid))
}

fn channels_for(named: Option<Vec<Channel>>, stored: usize, path: &Path) -> Result<Vec<Channel>> {
    match named {
        Some(list) if list.len() == stored => Ok(list),
        Some(list) => {
            Err(Error::file(path, format!("the description names {} channels but the PNG stores {stored}", list.len())))
        }
        None => Ok(super::nrrd::default_channels(stored)),
    }
}

/// Read a folder of PNG slices (sorted by name) as a volume, z = file order.
pub fn read_stack(path: &Path, budget: u64) -> Result<Volume> {
    let files = png_files(path)?;
    let first = decode(&files[0], budget)?;
    let described = match &first.text {
        Some(t) => fields::parse(&fields::from_lines(t)).map_err(|e| e.in_file(&files[0]))?,
        None => fields::parse(&[])?,
    };
    let channels = channels_for(described.channels, first.channels, &files[0])?;
    let dims = [first.width, first.height, files.len()];
    if let Some(named) = described.dims.filter(|d| *d != dims) {
        return Err(Error::file(
            path,
            format!(
                "its slices say the volume is {}x{}x{}, but the folder holds {} slice(s) of {}x{}: a slice is missing or \
                 a file was added",
                named[0], named[1], named[2], dims[2], dims[0], dims[1]
            ),
        ));
    }
    crate::volume::check_size(dims, channels.len(), budget).map_err(|e| e.in_file(path))?;
    let mut data = Vec::with_capacity(dims.iter().product::<usize>() * channels.len());
    for (z, file) in files.iter().enumerate() {
        let slice = if z == 0 { first_samples(&first) } else { decode(file, budget)? };
        check_slice_index(file, if z == 0 { &first.text } else { &slice.text }, z)?;
        if (slice.width, slice.height, slice.channels) != (first.width, first.height, first.channels) {
            return Err(Error::file(
                file,
                format!(
                    "slice is {}x{} with {} channels; the first slice is {}x{} with {}",
                    slice.width, slice.height, slice.channels, first.width, first.height, first.channels
                ),
            ));
        }
        data.extend_from_slice(&slice.samples);
    }
    Ok(Volume::from_data(dims, channels, data)?.with_meta(described.meta).with_model_grid(described.model_grid))
}

/// A slice solidtex wrote names its own index: it must be the file's place in name order.
fn check_slice_index(file: &Path, text: &Option<String>, z: usize) -> Result<()> {
    let lines = text.as_deref().map(fields::from_lines).unwrap_or_default();
    match lines.iter().find(|(key, _)| key == "slice") {
        Some((_, index)) if index.trim() != z.to_string() => Err(Error::file(
            file,
            format!(
                "this slice says it is slice {}, but it is slice {z} in name order: a slice before it is missing or a \
                 file was added",
                index.trim()
            ),
        )),
        _ => Ok(()),
    }
}

fn first_samples(first: &Decoded) -> Decoded {
    Decoded { samples: first.samples.clone(), text: None, ..*first }
}

fn png_files(folder: &Path) -> Result<Vec<PathBuf>> {
    let entries = fs::read_dir(folder).map_err(|e| Error::io(folder, e))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("png")))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(Error::file(folder, "this folder holds no .png slices"));
    }
    Ok(files)
}
