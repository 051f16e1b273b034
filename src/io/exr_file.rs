//! The native volume file: OpenEXR holding the flipbook atlas (see [`super::atlas`]),
//! f32 samples, ZIP-compressed (lossless), channels named by role, and the volume's
//! description in custom layer attributes:
//!
//! | attribute          | type       | value                                   |
//! |--------------------|------------|-----------------------------------------|
//! | `solidtexDims`     | v3i        | x, y, z size in voxels                  |
//! | `solidtexTiles`    | v2i        | atlas columns, rows                     |
//! | `solidtexChannels` | stringvector | channel names in storage order        |
//! | `solidtexType`     | string     | LST type (`0`, `1-a` ... `2-d`), optional |
//! | `solidtexProvenance` | stringvector | `key=value` entries                 |

use super::atlas;
use crate::error::{Error, Result};
use crate::texture_type::TextureType;
use crate::volume::{Channel, Meta, Volume};
use exr::prelude::*;
use std::collections::HashMap;
use std::path::Path;

const DIMS: &str = "solidtexDims";
const TILES: &str = "solidtexTiles";
const CHANNELS: &str = "solidtexChannels";
const TYPE: &str = "solidtexType";
const PROVENANCE: &str = "solidtexProvenance";

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

fn text(path_free: &str) -> Result<Text> {
    Text::new_or_none(path_free)
        .ok_or_else(|| Error::invalid(format!("{path_free:?} cannot be stored in an EXR attribute (use plain ASCII)")))
}

fn attributes_of(volume: &Volume) -> Result<HashMap<Text, AttributeValue>> {
    let d = volume.dims();
    let [columns, rows] = atlas::layout(d[2]);
    let mut map = HashMap::new();
    map.insert(text(DIMS)?, AttributeValue::IntVec3((d[0] as i32, d[1] as i32, d[2] as i32)));
    map.insert(text(TILES)?, AttributeValue::IntVec2(Vec2(columns as i32, rows as i32)));
    let names = volume.channels().iter().map(|c| text(c.name())).collect::<Result<_>>()?;
    map.insert(text(CHANNELS)?, AttributeValue::TextVector(names));
    if let Some(t) = volume.meta.texture_type {
        map.insert(text(TYPE)?, AttributeValue::Text(text(t.name())?));
    }
    let entries: Vec<Text> =
        volume.meta.provenance.iter().map(|(k, v)| text(&format!("{k}={v}"))).collect::<Result<_>>()?;
    if !entries.is_empty() {
        map.insert(text(PROVENANCE)?, AttributeValue::TextVector(entries));
    }
    Ok(map)
}

/// Read an EXR atlas written by [`write`] (or by another tool that sets the same attributes).
pub fn read(path: &Path, budget: u64) -> Result<Volume> {
    let fail = |m: String| Error::file(path, m);
    let image = read_all(path)?;
    let layer = &image.layer_data;
    let attrs = &layer.attributes.other;
    let dims = dims_of(attrs)
        .ok_or_else(|| fail(format!("no {DIMS} attribute: this EXR is a 2D image, not a solidtex volume atlas")))?;
    let channels = channels_of(attrs, layer).map_err(|e| e.in_file(path))?;
    crate::volume::check_size(dims, channels.len(), budget).map_err(|e| e.in_file(path))?;
    if let Some(AttributeValue::IntVec2(t)) = get(attrs, TILES) {
        let want = atlas::layout(dims[2]);
        if [t.0 as usize, t.1 as usize] != want {
            return Err(fail(format!(
                "{TILES} says {}x{} tiles but {} slices are stored in {}x{}",
                t.0, t.1, dims[2], want[0], want[1]
            )));
        }
    }
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
    Ok(volume.with_meta(meta_of(attrs).map_err(|e| e.in_file(path))?))
}

type ExrImage = Image<Layer<AnyChannels<FlatSamples>>>;

fn read_all(path: &Path) -> Result<ExrImage> {
    let bytes = super::atomic::read_bytes(path)?;
    exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| Error::file(path, format!("cannot read EXR (corrupt or truncated?): {e}")))
}

fn get<'a>(attrs: &'a HashMap<Text, AttributeValue>, key: &str) -> Option<&'a AttributeValue> {
    attrs.iter().find(|(k, _)| *k == key).map(|(_, v)| v)
}

fn dims_of(attrs: &HashMap<Text, AttributeValue>) -> Option<[usize; 3]> {
    match get(attrs, DIMS)? {
        AttributeValue::IntVec3((x, y, z)) => Some([*x, *y, *z].map(|v| v.max(0) as usize)),
        _ => None,
    }
}

/// Channel roles in storage order: from `solidtexChannels`, else the file's own names.
fn channels_of(attrs: &HashMap<Text, AttributeValue>, layer: &Layer<AnyChannels<FlatSamples>>) -> Result<Vec<Channel>> {
    let names: Vec<String> = match get(attrs, CHANNELS) {
        Some(AttributeValue::TextVector(list)) => list.iter().map(|t| t.to_string()).collect(),
        _ => layer.channel_data.list.iter().map(|c| c.name.to_string()).collect(),
    };
    let list = names.iter().map(|n| Channel::parse(n)).collect::<Result<Vec<_>>>()?;
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
            .ok_or_else(|| Error::invalid(format!("channel {role} is listed in {CHANNELS} but not stored")))?;
        for (i, v) in stored.sample_data.values_as_f32().enumerate().take(pixels) {
            data[i * n + c] = v;
        }
    }
    Ok(data)
}

fn meta_of(attrs: &HashMap<Text, AttributeValue>) -> Result<Meta> {
    let mut meta = Meta::default();
    if let Some(AttributeValue::Text(t)) = get(attrs, TYPE) {
        meta.texture_type = Some(t.to_string().parse::<TextureType>()?);
    }
    if let Some(AttributeValue::TextVector(list)) = get(attrs, PROVENANCE) {
        for entry in list {
            let entry = entry.to_string();
            if let Some((k, v)) = entry.split_once('=') {
                meta.set(k, v);
            }
        }
    }
    Ok(meta)
}
