//! NRRD (teem's "nearly raw raster data", read by 3D Slicer, ParaView and ITK).
//!
//! Written as one attached file: a text header, a blank line, then raw little-endian
//! f32 samples. A 1-channel volume is 3D (`sizes: X Y Z`); with more channels the
//! first axis holds the channels (`sizes: C X Y Z`, kind `RGB-color`, `RGBA-color`
//! or `vector`). Roles, type and provenance ride in `solidtex_*:=` key/value lines. A
//! volume placed in model space (a bake) has it in NRRD's own fields: `space dimension: 3`,
//! `space directions` (one vector a voxel step along x, y, z; `none` for the channel
//! axis) and `space origin` (the centre of the first voxel), which 3D Slicer, ParaView
//! and ITK read; reading takes them back when they describe an axis-aligned grid of
//! cubic voxels.
//! Reading accepts raw encoding of float, double, uchar, ushort (normalised to
//! [0, 1] for the integer types), in either endianness.

use super::fields;
use crate::error::{Error, Result};
use crate::volume::{Channel, ModelGrid, Volume};
use std::path::Path;

/// Write `volume` as NRRD (atomically).
pub fn write(path: &Path, volume: &Volume) -> Result<()> {
    let mut bytes = header(volume).into_bytes();
    bytes.reserve(volume.data().len() * 4);
    for v in volume.data() {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    super::atomic::write_bytes(path, &bytes)
}

fn header(volume: &Volume) -> String {
    let [x, y, z] = volume.dims();
    let n = volume.channel_count();
    let (dimension, sizes, kinds) = match n {
        1 => (3, format!("{x} {y} {z}"), "domain domain domain".to_string()),
        _ => {
            let kind = match n {
                3 => "RGB-color",
                4 => "RGBA-color",
                _ => "vector",
            };
            (4, format!("{n} {x} {y} {z}"), format!("{kind} domain domain domain"))
        }
    };
    let mut text = format!(
        "NRRD0004\n# written by solidtex {}\ntype: float\ndimension: {dimension}\nsizes: {sizes}\nkinds: {kinds}\n",
        env!("CARGO_PKG_VERSION")
    );
    if let Some(grid) = volume.model_grid {
        text.push_str(&space_fields(grid, n > 1));
    }
    text.push_str("endian: little\nencoding: raw\n");
    // the place in model space is in the space fields above
    let described = fields::fields(volume).into_iter().filter(|(k, _)| k != "origin" && k != "voxel");
    for (k, v) in described {
        text.push_str(&format!("solidtex_{k}:={}\n", v.replace('\n', " ")));
    }
    text.push('\n');
    text
}

/// `space dimension`, `space directions` (after `none` for a channel axis) and `space
/// origin` of `grid`.
fn space_fields(grid: ModelGrid, channel_axis: bool) -> String {
    let s = grid.voxel;
    let [x, y, z] = grid.origin;
    let none = if channel_axis { "none " } else { "" };
    format!("space dimension: 3\nspace directions: {none}({s},0,0) (0,{s},0) (0,0,{s})\nspace origin: ({x},{y},{z})\n")
}

/// The place in space of a header's `space directions` and `space origin`, when they
/// describe a grid solidtex keeps: axes along the space's, the same positive step on each.
/// Any other (rotated, uneven, another dimension) reads as no place; the samples are kept.
fn model_grid(header: &Header) -> Option<ModelGrid> {
    let origin = vector(header.space_origin.as_deref()?)?;
    let directions = header.space_directions.as_deref()?;
    let steps: Vec<[f32; 3]> =
        directions.split_whitespace().filter(|d| *d != "none").map(vector).collect::<Option<_>>()?;
    let voxel = steps.first()?[0];
    let aligned = steps.len() == 3
        && steps.iter().enumerate().all(|(a, v)| (0..3).all(|b| v[b] == if a == b { voxel } else { 0.0 }));
    (aligned && voxel > 0.0).then_some(ModelGrid { origin, voxel })
}

/// A NRRD vector of three finite numbers, `(1,0,-2.5)`.
fn vector(text: &str) -> Option<[f32; 3]> {
    let inner = text.trim().strip_prefix('(')?.strip_suffix(')')?;
    let numbers: Vec<f32> =
        inner.split(',').map(|t| t.trim().parse::<f32>().ok().filter(|v| v.is_finite())).collect::<Option<_>>()?;
    numbers.try_into().ok()
}

/// Read a NRRD file with attached raw data.
pub fn read(path: &Path, budget: u64) -> Result<Volume> {
    let bytes = super::atomic::read_bytes_within(path, super::atomic::file_cap(budget))?;
    parse(&bytes, budget).map_err(|e| e.in_file(path))
}

struct Header {
    sizes: Vec<usize>,
    sample: Sample,
    big_endian: bool,
    extra: Vec<(String, String)>,
    space_directions: Option<String>,
    space_origin: Option<String>,
}

#[derive(Clone, Copy)]
enum Sample {
    F32,
    F64,
    U8,
    U16,
}

impl Sample {
    fn bytes(self) -> usize {
        match self {
            Sample::U8 => 1,
            Sample::U16 => 2,
            Sample::F32 => 4,
            Sample::F64 => 8,
        }
    }
}

fn parse(bytes: &[u8], budget: u64) -> Result<Volume> {
    if !bytes.starts_with(b"NRRD000") {
        return Err(Error::invalid("not a NRRD file: it does not start with \"NRRD000\""));
    }
    let end = find_blank_line(bytes).ok_or_else(|| {
        Error::invalid("NRRD header has no blank line before the data (truncated, or detached data is not supported)")
    })?;
    let text = String::from_utf8_lossy(&bytes[..end.0]);
    let header = parse_header(&text)?;
    let (dims, channels) = shape(&header, budget)?;
    let body = &bytes[end.1..];
    let count = dims.iter().product::<usize>() * channels.len();
    let need = count * header.sample.bytes();
    if body.len() < need {
        return Err(Error::invalid(format!(
            "NRRD data is truncated: the header promises {need} bytes of samples, the file holds {}",
            body.len()
        )));
    }
    if body.len() > need {
        return Err(Error::invalid(format!(
            "NRRD data holds {} bytes, more than the {need} its sizes and type promise: the header does not \
             describe the data",
            body.len()
        )));
    }
    let data = decode(&body[..need], header.sample, header.big_endian);
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(format!("NRRD sample {i} is {}; NaN and infinity are not allowed", data[i])));
    }
    let described = fields::parse(&strip_prefix(&header.extra))?;
    let channels = match described.channels {
        Some(named) if named.len() != channels.len() => {
            return Err(Error::invalid(format!(
                "NRRD field solidtex_channels names {} channel(s) ({}) but the sizes give {}; they must be the same",
                named.len(),
                crate::volume::channel_names(&named),
                channels.len()
            )));
        }
        named => named.unwrap_or(channels),
    };
    let grid = model_grid(&header);
    Ok(Volume::from_data(dims, channels, data)?.with_meta(described.meta).with_model_grid(grid))
}

/// (end of header text, start of data) at the first empty line.
fn find_blank_line(bytes: &[u8]) -> Option<(usize, usize)> {
    let lf = bytes.windows(2).position(|w| w == b"\n\n").map(|i| (i, i + 2));
    let crlf = bytes.windows(4).position(|w| w == b"\r\n\r\n").map(|i| (i, i + 4));
    match (lf, crlf) {
        (Some(a), Some(b)) => Some(if a.0 < b.0 { a } else { b }),
        (a, b) => a.or(b),
    }
}

fn parse_header(text: &str) -> Result<Header> {
    let mut header = Header {
        sizes: Vec::new(),
        sample: Sample::F32,
        big_endian: false,
        extra: Vec::new(),
        space_directions: None,
        space_origin: None,
    };
    let mut dimension = None;
    let mut seen: Vec<String> = Vec::new();
    for line in text.lines().skip(1).map(str::trim).filter(|l| !l.starts_with('#') && !l.is_empty()) {
        if let Some((k, v)) = line.split_once(":=") {
            once(&mut seen, k.trim())?;
            header.extra.push((k.trim().to_string(), v.to_string()));
            continue;
        }
        let Some((key, value)) = line.split_once(':') else {
            return Err(Error::invalid(format!("NRRD header line {line:?} has no ':'")));
        };
        let value = value.trim();
        once(&mut seen, key.trim())?;
        match key.trim() {
            "type" => header.sample = sample_type(value)?,
            "dimension" => dimension = value.parse::<usize>().ok(),
            "sizes" => header.sizes = parse_sizes(value)?,
            "endian" => header.big_endian = value == "big",
            "space directions" => header.space_directions = Some(value.to_string()),
            "space origin" => header.space_origin = Some(value.to_string()),
            "encoding" if value != "raw" => {
                return Err(Error::invalid(format!("NRRD encoding {value:?} is not supported; allowed: raw")));
            }
            "data file" | "datafile" => {
                return Err(Error::invalid("detached NRRD data files are not supported; save with attached raw data"));
            }
            _ => {}
        }
    }
    match dimension {
        None => Err(Error::invalid("NRRD header has no dimension field (a whole number: 3 or 4)")),
        Some(d) if d != header.sizes.len() => {
            Err(Error::invalid(format!("NRRD dimension {d} does not match the {} sizes given", header.sizes.len())))
        }
        Some(_) => Ok(header),
    }
}

/// Refuse a header field given twice (which of the two would count is not said).
fn once(seen: &mut Vec<String>, key: &str) -> Result<()> {
    if seen.iter().any(|k| k == key) {
        return Err(Error::invalid(format!("NRRD header gives the field {key:?} twice")));
    }
    seen.push(key.to_string());
    Ok(())
}

fn sample_type(value: &str) -> Result<Sample> {
    Ok(match value {
        "float" => Sample::F32,
        "double" => Sample::F64,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Sample::U8,
        "ushort" | "unsigned short" | "uint16" | "uint16_t" | "unsigned short int" => Sample::U16,
        other => {
            return Err(Error::invalid(format!(
                "NRRD type {other:?} is not supported; allowed: float, double, uchar, ushort"
            )));
        }
    })
}

fn parse_sizes(value: &str) -> Result<Vec<usize>> {
    value
        .split_whitespace()
        .map(|s| s.parse::<usize>().map_err(|_| Error::invalid(format!("NRRD sizes {value:?} are not whole numbers"))))
        .collect()
}

/// Dims and default channel roles from the sizes, checked against the budget first.
fn shape(header: &Header, budget: u64) -> Result<([usize; 3], Vec<Channel>)> {
    let s = &header.sizes;
    let (dims, n) = match s.len() {
        3 => ([s[0], s[1], s[2]], 1),
        4 => ([s[1], s[2], s[3]], s[0]),
        k => return Err(Error::invalid(format!("NRRD dimension {k} is not supported; allowed: 3 or 4"))),
    };
    if dims.contains(&0) || n == 0 {
        return Err(Error::invalid(format!("NRRD sizes {s:?} contain a zero; every size must be at least 1")));
    }
    crate::volume::check_size(dims, n, budget)?;
    Ok((dims, default_channels(n)))
}

/// Roles by position when a file names none: grey, grey+alpha, RGB, RGBA, then extras.
pub fn default_channels(n: usize) -> Vec<Channel> {
    match n {
        1 => Channel::grey(),
        2 => vec![Channel::R, Channel::A],
        3 => Channel::rgb(),
        _ => {
            let mut list = Channel::rgba();
            list.extend((4..n).map(|i| Channel::Named(format!("extra{i}"))));
            list
        }
    }
}

fn decode(body: &[u8], sample: Sample, big: bool) -> Vec<f32> {
    let chunk = sample.bytes();
    body.chunks_exact(chunk)
        .map(|b| {
            let mut a = [0u8; 8];
            a[..chunk].copy_from_slice(b);
            if big {
                a[..chunk].reverse();
            }
            match sample {
                Sample::U8 => a[0] as f32 / 255.0,
                Sample::U16 => u16::from_le_bytes([a[0], a[1]]) as f32 / 65535.0,
                Sample::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]),
                Sample::F64 => f64::from_le_bytes(a) as f32,
            }
        })
        .collect()
}

fn strip_prefix(extra: &[(String, String)]) -> Vec<(String, String)> {
    extra.iter().filter_map(|(k, v)| k.strip_prefix("solidtex_").map(|k| (k.to_string(), v.clone()))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_foreign_uchar_big_endian_file() {
        let mut bytes =
            b"NRRD0004\ntype: unsigned char\ndimension: 3\nsizes: 2 1 1\nendian: big\nencoding: raw\n\n".to_vec();
        bytes.extend_from_slice(&[0, 255]);
        let v = parse(&bytes, u64::MAX).unwrap();
        assert_eq!(v.data(), &[0.0, 1.0]);
        assert_eq!(v.channels(), Channel::grey().as_slice());
    }

    #[test]
    fn huge_sizes_are_refused_before_allocation() {
        for sizes in [
            "2147483647 1 1 1",
            "9223372036854775807 1 1 1",
            "100000000 1 1",
            "1 4294967295 4294967295 2",
            "18446744073709551615 9223372036854775807 3 2",
        ] {
            let text = format!(
                "NRRD0004\ntype: float\ndimension: {}\nsizes: {sizes}\nencoding: raw\n\n",
                sizes.split(' ').count()
            );
            let err = parse(text.as_bytes(), 1 << 20).unwrap_err().to_string();
            assert!(err.contains("over the voxel budget"), "{sizes}: {err}");
        }
    }

    #[test]
    fn refuses_gzip_and_bad_dimension() {
        let gz = b"NRRD0004\ntype: float\ndimension: 3\nsizes: 2 1 1\nencoding: gzip\n\n";
        assert!(parse(gz, u64::MAX).unwrap_err().to_string().contains("allowed: raw"));
        let dim = b"NRRD0004\ntype: float\ndimension: 2\nsizes: 2 1 1\nencoding: raw\n\n";
        assert!(parse(dim, u64::MAX).unwrap_err().to_string().contains("dimension 2 does not match the 3 sizes"));
        let none = b"NRRD0004\ntype: float\nencoding: raw\n\n";
        assert!(parse(none, u64::MAX).unwrap_err().to_string().contains("no dimension field"));
    }

    /// A placed volume's space fields read back as its place; a grid another tool rotated,
    /// stretched or wrote oddly reads without one, its samples kept.
    #[test]
    fn space_fields_give_the_place_of_an_axis_aligned_grid_only() {
        let grid = ModelGrid { origin: [-1.0, 0.5, 2.0], voxel: 0.25 };
        let placed = Volume::from_data([2, 1, 1], Channel::grey(), vec![0.0, 1.0]).unwrap().with_model_grid(Some(grid));
        let mut bytes = header(&placed).into_bytes();
        bytes.extend([0f32, 1f32].iter().flat_map(|v| v.to_le_bytes()));
        assert_eq!(parse(&bytes, u64::MAX).unwrap(), placed);
        let odd = ["(0,0.25,0) (0.25,0,0) (0,0,0.25)", "(0.25,0,0) (0,0.5,0) (0,0,0.25)", "(1,0) (0,1) (0,0,1)"];
        for directions in odd {
            let text = format!(
                "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 1 1\nencoding: raw\nspace dimension: 3\n\
                 space directions: {directions}\nspace origin: (0,0,0)\n\n"
            );
            let mut bytes = text.into_bytes();
            bytes.extend([0u8, 255]);
            let read = parse(&bytes, u64::MAX).unwrap();
            assert_eq!((read.model_grid, read.data()), (None, &[0.0, 1.0][..]), "{directions}");
        }
    }

    /// A header that contradicts itself or its data is refused: a field given twice, a
    /// channel list of another length than the sizes, more data than the sizes promise.
    #[test]
    fn refuses_a_header_at_odds_with_itself_or_its_data() {
        let file = |header: &str, samples: usize| {
            let mut bytes = format!("NRRD0004\ntype: uchar\nencoding: raw\n{header}\n").into_bytes();
            bytes.extend(std::iter::repeat_n(7u8, samples));
            parse(&bytes, u64::MAX).map(|v| v.channel_count())
        };
        assert_eq!(file("dimension: 4\nsizes: 3 2 2 2\nsolidtex_channels:=R,G,B\n", 24).unwrap(), 3);
        let twice = file("dimension: 4\nsizes: 3 2 2 2\nsizes: 2 2 2 2\n", 24).unwrap_err().to_string();
        assert!(twice.contains("\"sizes\" twice"), "{twice}");
        let named = file("dimension: 4\nsizes: 3 2 2 2\nsolidtex_channels:=R,G\n", 24).unwrap_err().to_string();
        assert!(named.contains("names 2 channel(s) (R,G) but the sizes give 3"), "{named}");
        let more = file("dimension: 4\nsizes: 2 2 2 2\n", 24).unwrap_err().to_string();
        assert!(more.contains("holds 24 bytes, more than the 16"), "{more}");
    }
}
