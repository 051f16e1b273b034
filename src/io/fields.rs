//! The volume description shared by the text-based headers (PNG tEXt, NRRD keys):
//! `dims`, `channels`, `type`, `origin` and `voxel` (where a baked volume sits in model
//! space) and `provenance.<key>` as text fields.

use crate::error::{Error, Result};
use crate::texture_type::TextureType;
use crate::volume::{Channel, Meta, ModelGrid, Volume};

/// What a header says about a volume.
#[derive(Debug, Clone, PartialEq)]
pub struct Described {
    /// Dims, if given.
    pub dims: Option<[usize; 3]>,
    /// Channel roles, if given.
    pub channels: Option<Vec<Channel>>,
    /// Type and provenance.
    pub meta: Meta,
    /// Where the volume sits in model space, if given.
    pub model_grid: Option<ModelGrid>,
}

/// The fields describing `volume`, in a fixed order.
pub fn fields(volume: &Volume) -> Vec<(String, String)> {
    let d = volume.dims();
    let mut out = vec![
        ("dims".to_string(), format!("{} {} {}", d[0], d[1], d[2])),
        ("channels".to_string(), crate::volume::channel_names(volume.channels())),
    ];
    if let Some(t) = volume.meta.texture_type {
        out.push(("type".to_string(), t.to_string()));
    }
    if let Some(g) = volume.model_grid {
        out.push(("origin".to_string(), format!("{} {} {}", g.origin[0], g.origin[1], g.origin[2])));
        out.push(("voxel".to_string(), g.voxel.to_string()));
    }
    for (k, v) in &volume.meta.provenance {
        out.push((format!("provenance.{k}"), v.clone()));
    }
    out
}

/// Read fields back; unknown keys are ignored, bad values are errors naming the field.
pub fn parse(fields: &[(String, String)]) -> Result<Described> {
    let mut out = Described { dims: None, channels: None, meta: Meta::default(), model_grid: None };
    let (mut origin, mut voxel) = (None, None);
    for (key, value) in fields {
        match key.as_str() {
            "dims" => out.dims = Some(parse_dims(value)?),
            "channels" => out.channels = Some(Channel::parse_list(value)?),
            "type" => out.meta.texture_type = Some(value.parse::<TextureType>()?),
            "origin" => origin = Some(parse_point("origin", value)?),
            "voxel" => voxel = Some(parse_voxel("voxel", value)?),
            other => {
                if let Some(k) = other.strip_prefix("provenance.") {
                    out.meta.set(k, value.clone());
                }
            }
        }
    }
    out.model_grid = match (origin, voxel) {
        (Some(origin), Some(voxel)) => Some(ModelGrid { origin, voxel }),
        (None, None) => None,
        _ => {
            return Err(Error::invalid(
                "the description gives only one of origin and voxel; a place in model space needs both",
            ));
        }
    };
    Ok(out)
}

/// Three finite numbers, `-0.5 0 1.25`, as a model point (`field` names it in errors).
pub fn parse_point(field: &str, text: &str) -> Result<[f32; 3]> {
    let numbers: Option<Vec<f32>> =
        text.split_whitespace().map(|t| t.parse::<f32>().ok().filter(|v| v.is_finite())).collect();
    match numbers.as_deref() {
        Some(&[x, y, z]) => Ok([x, y, z]),
        _ => Err(Error::invalid(format!("{field} {text:?} is not three finite numbers such as \"-0.5 0 1.25\""))),
    }
}

/// A voxel's side: a finite number above 0 (`field` names it in errors).
pub fn parse_voxel(field: &str, text: &str) -> Result<f32> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(Error::invalid(format!("{field} {text:?} is not a voxel side: a finite number above 0"))),
    }
}

/// `64 64 32` or `64x64x32` as dims.
pub fn parse_dims(text: &str) -> Result<[usize; 3]> {
    let parts: Vec<&str> = text.split(|c: char| c == 'x' || c.is_whitespace()).filter(|s| !s.is_empty()).collect();
    let bad = || Error::invalid(format!("dims {text:?} are not three whole numbers such as \"64 64 64\""));
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut dims = [0; 3];
    for (d, p) in dims.iter_mut().zip(&parts) {
        *d = p.parse().map_err(|_| bad())?;
    }
    Ok(dims)
}

/// Fields as `key: value` lines (values must not contain newlines; they are replaced).
pub fn to_lines(fields: &[(String, String)]) -> String {
    fields.iter().map(|(k, v)| format!("{k}: {}\n", v.replace('\n', " "))).collect()
}

/// `key: value` lines back to fields.
pub fn from_lines(text: &str) -> Vec<(String, String)> {
    text.lines().filter_map(|line| line.split_once(": ")).map(|(k, v)| (k.to_string(), v.to_string())).collect()
}
