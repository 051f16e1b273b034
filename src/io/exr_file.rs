//! The native volume file: OpenEXR holding the flipbook atlas (see [`super::atlas`]),
//! f32 samples, ZIP-compressed (lossless), channels named by role, and the volume's
//! description in one custom layer attribute `solidtex` (a `stringvector` of
//! `key: value` lines, the same description PNG atlases carry):
//!
//! ```text
//! dims: 64 64 64          x, y, z size in voxels (required)
//! tiles: 8 8              atlas columns and rows (must match the layout rule)
//! channels: R,G,B,Depth   channel names in storage order
//! type: 1-b               LST type (optional)
//! provenance.seed: 3      provenance entries (optional)
//! ```
//! One attribute, in a fixed order, so the same volume always gives the same bytes.

use super::{atlas, fields};
use crate::error::{Error, Result};
use crate::volume::{Channel, Volume};
use exr::prelude::*;
use std::collections::HashMap;
use std::path::Path;

const ATTRIBUTE: &str = "solidtex";

/// Write `volume` as an EXR atlas (atomically).
pub fn write(path: &Path, volume: &Volume) -> Result<()> {
    let (width, height, data) = atlas::to_atlas(volume);
    let n = volume.channel_count();
    let channels: Vec<AnyChannel<FlatSamples>> = volume
        .channels()
        .iter()
        .enumerate()
        .map(|(c, role)| {
            let samples = data.iter().skip(c).step_by(n).copied().collect();
            AnyChannel::new(role.name(), FlatSamples::F32(samples))
        })
        .collect();
    let mut attributes = LayerAttributes::named("solidtex volume");
    attributes.other = attributes_of(volume)?;
    let layer = Layer::new(
        (width, height),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    let image = Image::from_layer(layer);
    super::atomic::write_file(path, |w| {
        image.write().to_buffered(w).map_err(|e| Error::file(path, format!("cannot write EXR: {e}")))
    })
}

/// An EXR text: one byte a character, so characters outside Latin-1 become `?`.
fn text(value: &str) -> Result<Text> {
    let latin1: String = value.chars().map(|c| if (c as u32) < 256 { c } else { '?' }).collect();
    Text::new_or_none(&latin1).ok_or_else(|| Error::invalid(format!("{value:?} cannot be stored in an EXR attribute")))
}

fn attributes_of(volume: &Volume) -> Result<HashMap<Text, AttributeValue>> {
    let [columns, rows] = atlas::layout(volume.dims()[2]);
    let mut lines = fields::fields(volume);
    lines.insert(1, ("tiles".to_string(), format!("{columns} {rows}")));
    let list = lines.iter().map(|(k, v)| text(&format!("{k}: {v}"))).collect::<Result<_>>()?;
    Ok(HashMap::from([(text(ATTRIBUTE)?, AttributeValue::TextVector(list))]))
}

/// Read an EXR atlas written by [`write`] (or by another tool that sets the same attribute).
pub fn read(path: &Path, budget: u64) -> Result<Volume> {
    let fail = |m: String| Error::file(path, m);
    let image = read_all(path, budget)?;
    let layer = &image.layer_data;
    let lines = description(&layer.attributes.other).ok_or_else(|| {
        fail(format!("no {ATTRIBUTE:?} attribute: this EXR is a 2D image, not a solidtex volume atlas"))
    })?;
    let described = fields::parse(&lines).map_err(|e| e.in_file(path))?;
    let dims = described.dims.ok_or_else(|| fail("the solidtex description has no dims".to_string()))?;
    let stored = stored_channels(layer).map_err(|e| e.in_file(path))?;
    let channels = match described.channels {
        Some(list) if list.len() == stored.len() => list,
        Some(list) => {
            return Err(fail(format!(
                "the description lists {} channel(s) ({}) but the file stores {} ({}); they must be the same",
                list.len(),
                crate::volume::channel_names(&list),
                stored.len(),
                crate::volume::channel_names(&stored)
            )));
        }
        None => stored,
    };
    crate::volume::check_size(dims, channels.len(), budget).map_err(|e| e.in_file(path))?;
    check_tiles(&lines, dims).map_err(|e| e.in_file(path))?;
    let (w, h) = (layer.size.0, layer.size.1);
    let data = interleave(layer, &channels, w * h).map_err(|e| e.in_file(path))?;
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        let n = channels.len();
        return Err(fail(format!(
            "sample {} of channel {} at atlas pixel ({}, {}) is not finite; NaN and infinity are not allowed",
            data[i],
            channels[i % n],
            (i / n) % w,
            (i / n) / w
        )));
    }
    let volume = atlas::from_atlas(dims, channels, w, h, &data).map_err(|e| e.in_file(path))?;
    Ok(volume.with_meta(described.meta).with_model_grid(described.model_grid))
}

/// The size a solidtex volume's description names, read from an EXR's header alone;
/// `None` for any other EXR (a 2D image) or bytes that are no EXR.
pub fn volume_dims(bytes: &[u8]) -> Option<[usize; 3]> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false).ok()?;
    let lines = meta.headers.iter().find_map(|h| description(&h.own_attributes.other))?;
    fields::parse(&lines).ok()?.dims
}

/// The `tiles` field, if present, must match the layout of `dims`.
fn check_tiles(lines: &[(String, String)], dims: [usize; 3]) -> Result<()> {
    let Some((_, value)) = lines.iter().find(|(k, _)| k == "tiles") else { return Ok(()) };
    let want = atlas::layout(dims[2]);
    let got: Vec<usize> = value.split_whitespace().filter_map(|t| t.parse().ok()).collect();
    if got != want {
        return Err(Error::invalid(format!(
            "tiles says {value:?} but {} slices are stored in {}x{} tiles",
            dims[2], want[0], want[1]
        )));
    }
    Ok(())
}

type ExrImage = Image<Layer<AnyChannels<FlatSamples>>>;

/// Read the first layer, after checking the header's size against the budget.
fn read_all(path: &Path, budget: u64) -> Result<ExrImage> {
    let bytes = super::atomic::read_bytes_within(path, super::atomic::file_cap(budget))?;
    check_header(&bytes, budget).map_err(|e| e.in_file(path))?;
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| Error::file(path, format!("cannot read EXR (corrupt or truncated?): {e}")))
}

/// Every layer the header declares must fit in the budget as f32 samples.
fn check_header(bytes: &[u8], budget: u64) -> Result<()> {
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| Error::invalid(format!("cannot read EXR header (corrupt or truncated?): {e}")))?;
    for header in meta.headers.iter() {
        let size = header.layer_size;
        let channels = header.channels.list.len();
        let needed = size.0 as u128 * size.1 as u128 * channels.max(1) as u128 * 4;
        if needed > budget as u128 {
            return Err(Error::invalid(format!(
                "the EXR header declares a {}x{} layer with {channels} channel(s): {needed} bytes of samples, over \
                 the voxel budget of {budget} bytes (raise it with SOLIDTEX_MAX_BYTES)",
                size.0, size.1
            )));
        }
    }
    Ok(())
}

/// The `key: value` lines of the `solidtex` attribute.
fn description(attrs: &HashMap<Text, AttributeValue>) -> Option<Vec<(String, String)>> {
    let value = attrs.iter().find(|(k, _)| *k == ATTRIBUTE).map(|(_, v)| v)?;
    match value {
        AttributeValue::TextVector(list) => {
            let text: Vec<String> = list.iter().map(|t| t.to_string()).collect();
            Some(fields::from_lines(&text.join("\n")))
        }
        _ => None,
    }
}

/// Channel roles from the file's own channel names (sorted by name, as EXR stores them).
fn stored_channels(layer: &Layer<AnyChannels<FlatSamples>>) -> Result<Vec<Channel>> {
    let list =
        layer.channel_data.list.iter().map(|c| Channel::parse(&c.name.to_string())).collect::<Result<Vec<_>>>()?;
    Channel::check_list(&list)?;
    Ok(list)
}

/// The samples of `channels`, interleaved per pixel.
fn interleave(layer: &Layer<AnyChannels<FlatSamples>>, channels: &[Channel], pixels: usize) -> Result<Vec<f32>> {
    let n = channels.len();
    let mut data = vec![0.0f32; pixels * n];
    for (c, role) in channels.iter().enumerate() {
        let stored = layer
            .channel_data
            .list
            .iter()
            .find(|ch| ch.name.to_string() == role.name())
            .ok_or_else(|| Error::invalid(format!("channel {role} is listed in the description but not stored")))?;
        for (i, v) in stored.sample_data.values_as_f32().enumerate().take(pixels) {
            data[i * n + c] = v;
        }
    }
    Ok(data)
}
