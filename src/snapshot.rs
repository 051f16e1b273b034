//! Small text snapshots of volumes for regression tests: dims, channels, type, a content
//! hash, per-channel statistics and an 8x8 thumbnail of the central z-slice per channel.
//!
//! ```text
//! solidtex-snapshot 1
//! dims 16 16 16
//! channels R,G,B
//! type 0
//! hash 5c1e...            blake3 of the samples rounded to 16 bits
//! stat R 0.512300 0.101000 0.000000 1.000000     mean std min max
//! thumb R 0.5100 0.5200 ...                      8 rows of 8 block means, row by row
//! ```
//! Compared exactly (hash) or within a tolerance (stats and thumbnails).

use crate::error::{Error, Result};
use crate::volume::Volume;

/// Thumbnail side.
pub const THUMB: usize = 8;
/// Decimals a snapshot file keeps of each statistic.
const STAT_DIGITS: usize = 6;
/// Decimals a snapshot file keeps of each thumbnail value.
const THUMB_DIGITS: usize = 4;

/// A volume's snapshot.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Size in voxels.
    pub dims: [usize; 3],
    /// Channel names.
    pub channels: Vec<String>,
    /// Texture type, if set.
    pub texture_type: Option<String>,
    /// Content hash of the 16-bit-rounded samples.
    pub hash: String,
    /// Per channel: mean, std, min, max.
    pub stats: Vec<[f64; 4]>,
    /// Per channel: THUMB x THUMB block means of the central z-slice, row by row.
    pub thumbs: Vec<Vec<f64>>,
}

impl Snapshot {
    /// Take the snapshot of `volume`.
    pub fn of(volume: &Volume) -> Snapshot {
        let mut hasher = blake3::Hasher::new();
        for v in volume.data() {
            hasher.update(&((v.clamp(0.0, 1.0) * 65535.0).round() as u16).to_le_bytes());
        }
        let stats = volume.channel_stats(1).iter().map(|s| [s.mean, s.std, s.min as f64, s.max as f64]).collect();
        Snapshot {
            dims: volume.dims(),
            channels: volume.channels().iter().map(|c| c.name().to_string()).collect(),
            texture_type: volume.meta.texture_type.map(|t| t.to_string()),
            hash: hasher.finalize().to_hex()[..32].to_string(),
            stats,
            thumbs: (0..volume.channel_count()).map(|c| thumbnail(volume, c)).collect(),
        }
    }

    /// The text form.
    pub fn to_text(&self) -> String {
        let [x, y, z] = self.dims;
        let mut out = format!("solidtex-snapshot 1\ndims {x} {y} {z}\nchannels {}\n", self.channels.join(","));
        out += &format!("type {}\nhash {}\n", self.texture_type.as_deref().unwrap_or("-"), self.hash);
        for (name, s) in self.channels.iter().zip(&self.stats) {
            let values: Vec<String> = s.iter().map(|v| format!("{v:.STAT_DIGITS$}")).collect();
            out += &format!("stat {name} {}\n", values.join(" "));
        }
        for (name, t) in self.channels.iter().zip(&self.thumbs) {
            let values: Vec<String> = t.iter().map(|v| format!("{v:.THUMB_DIGITS$}")).collect();
            out += &format!("thumb {name} {}\n", values.join(" "));
        }
        out
    }

    /// Read the text form.
    pub fn parse(text: &str) -> Result<Snapshot> {
        let mut lines = text.lines();
        if lines.next() != Some("solidtex-snapshot 1") {
            return Err(Error::invalid("not a solidtex snapshot: the first line must be \"solidtex-snapshot 1\""));
        }
        let mut snap = Snapshot {
            dims: [0; 3],
            channels: Vec::new(),
            texture_type: None,
            hash: String::new(),
            stats: Vec::new(),
            thumbs: Vec::new(),
        };
        for (n, line) in lines.enumerate() {
            let bad = || Error::invalid(format!("snapshot line {}: {line:?} cannot be read", n + 2));
            let (key, rest) = line.split_once(' ').ok_or_else(bad)?;
            // a NaN would compare as no difference at all: every value must be a number
            let number = |t: &str| match t.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(_) => Err(Error::invalid(format!(
                    "snapshot line {}: {t:?} is not a finite number (a snapshot holds numbers only)",
                    n + 2
                ))),
                Err(_) => Err(bad()),
            };
            let numbers = |skip: usize| rest.split_whitespace().skip(skip).map(number).collect::<Result<Vec<f64>>>();
            match key {
                "dims" => {
                    let dims = numbers(0)?;
                    if dims.len() != 3 || dims.iter().any(|d| *d < 1.0 || d.fract() != 0.0) {
                        return Err(Error::invalid(format!(
                            "snapshot dims line '{rest}' must be three whole numbers of at least 1 (voxels along x, y, z)"
                        )));
                    }
                    snap.dims = [0, 1, 2].map(|a| dims[a] as usize);
                }
                "channels" => snap.channels = rest.split(',').map(str::to_string).collect(),
                "type" => snap.texture_type = (rest != "-").then(|| rest.to_string()),
                "hash" => snap.hash = rest.to_string(),
                "stat" => snap.stats.push(numbers(1)?.try_into().map_err(|_| bad())?),
                "thumb" => snap.thumbs.push(numbers(1)?),
                _ => return Err(bad()),
            }
        }
        snap.check_complete()?;
        Ok(snap)
    }

    /// A comparison reads every field: dims, the hash, and per channel one statistics
    /// line and one full thumbnail. A file cut short misses some of them.
    fn check_complete(&self) -> Result<()> {
        let missing = |what: &str| Error::invalid(format!("snapshot has no {what} line (truncated?)"));
        if self.dims.contains(&0) {
            return Err(missing("dims"));
        }
        if self.channels.is_empty() {
            return Err(missing("channels"));
        }
        if self.hash.is_empty() {
            return Err(missing("hash"));
        }
        let n = self.channels.len();
        if self.stats.len() != n || self.thumbs.len() != n {
            return Err(Error::invalid(format!(
                "snapshot names {n} channel(s) but has {} stat and {} thumb line(s); one of each per channel \
                 is needed (truncated?)",
                self.stats.len(),
                self.thumbs.len()
            )));
        }
        if let Some(c) = self.thumbs.iter().position(|t| t.len() != THUMB * THUMB) {
            return Err(Error::invalid(format!(
                "snapshot thumb line {} has {} values; {} are needed",
                c + 1,
                self.thumbs[c].len(),
                THUMB * THUMB
            )));
        }
        Ok(())
    }

    /// Differences from `expected`: none means equal (tolerance 0: the hash must match;
    /// otherwise stats and thumbnail values may differ by up to `tolerance`). Both sides are
    /// compared as a file stores them (stats to 6 decimals, thumbnails to 4), so a volume
    /// always matches the snapshot file written of it, at any tolerance.
    pub fn differences(&self, expected: &Snapshot, tolerance: f64) -> Vec<String> {
        let mut out = Vec::new();
        if self.dims != expected.dims {
            out.push(format!("dims {}, expected {}", dims_text(self.dims), dims_text(expected.dims)));
        }
        if self.channels != expected.channels || self.texture_type != expected.texture_type {
            out.push(format!(
                "channels {} type {}, expected {} type {}",
                self.channels.join(","),
                self.texture_type.as_deref().unwrap_or("none"),
                expected.channels.join(","),
                expected.texture_type.as_deref().unwrap_or("none")
            ));
        }
        if !out.is_empty() {
            return out;
        }
        if tolerance == 0.0 {
            if self.hash != expected.hash {
                out.push(format!("content hash {}, expected {}", self.hash, expected.hash));
            }
            return out;
        }
        for (c, name) in self.channels.iter().enumerate() {
            let (Some(a), Some(b), Some(e), Some(f)) =
                (self.stats.get(c), self.thumbs.get(c), expected.stats.get(c), expected.thumbs.get(c))
            else {
                out.push(format!("channel {name}: statistics or thumbnail missing"));
                continue;
            };
            let (s, t) = (worst(a, e, STAT_DIGITS), worst(b, f, THUMB_DIGITS));
            if s > tolerance || t > tolerance {
                out.push(format!(
                    "channel {name}: stats differ by {s:.STAT_DIGITS$}, thumbnail by {t:.THUMB_DIGITS$} \
                     (tolerance {tolerance})"
                ));
            }
        }
        out
    }
}

/// Dims as `XxYxZ`.
fn dims_text([x, y, z]: [usize; 3]) -> String {
    format!("{x}x{y}x{z}")
}

/// `value` as a snapshot file keeps it: rounded to `digits` decimals.
fn stored(value: f64, digits: usize) -> f64 {
    format!("{value:.digits$}").parse().unwrap_or(value)
}

/// The largest difference of two lists of values, each rounded as a file keeps it.
fn worst(a: &[f64], b: &[f64], digits: usize) -> f64 {
    a.iter().zip(b).map(|(x, y)| (stored(*x, digits) - stored(*y, digits)).abs()).fold(0.0, f64::max)
}

/// Block means of the central z-slice of channel `c`.
fn thumbnail(volume: &Volume, c: usize) -> Vec<f64> {
    let [dx, dy, dz] = volume.dims();
    let z = dz / 2;
    let mut out = Vec::with_capacity(THUMB * THUMB);
    for by in 0..THUMB {
        for bx in 0..THUMB {
            let (x0, x1) = (bx * dx / THUMB, ((bx + 1) * dx / THUMB).max(bx * dx / THUMB + 1).min(dx));
            let (y0, y1) = (by * dy / THUMB, ((by + 1) * dy / THUMB).max(by * dy / THUMB + 1).min(dy));
            let (mut sum, mut n) = (0.0, 0.0);
            for y in y0..y1 {
                for x in x0..x1 {
                    sum += volume.get(x.min(dx - 1), y.min(dy - 1), z, c) as f64;
                    n += 1.0;
                }
            }
            out.push(sum / f64::max(n, 1.0));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    #[test]
    fn text_round_trips_and_differences_are_named() {
        let v = Volume::from_fn([10, 6, 4], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 9.0, y as f32 / 5.0, z as f32 / 3.0])
        })
        .unwrap();
        let snap = Snapshot::of(&v);
        let back = Snapshot::parse(&snap.to_text()).unwrap();
        assert!(back.differences(&snap, 0.0).is_empty());
        let mut w = v.clone();
        w.set(3, 3, 2, 0, 0.9);
        let other = Snapshot::of(&w);
        assert!(other.differences(&snap, 0.0)[0].contains("content hash"));
        assert!(other.differences(&snap, 0.5).is_empty(), "within a loose tolerance");
        assert!(!other.differences(&snap, 0.001).is_empty());
        assert!(Snapshot::parse("hello").unwrap_err().to_string().contains("first line"));
    }

    #[test]
    fn a_volume_matches_the_snapshot_file_written_of_it_at_any_tolerance() {
        let v = Volume::from_fn([9, 7, 5], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 7.0, (y * z) as f32 / 13.0, 1.0 / (1.0 + x as f32)])
        })
        .unwrap();
        let snap = Snapshot::of(&v);
        let file = Snapshot::parse(&snap.to_text()).unwrap();
        for tolerance in [0.0, 1e-12, 1e-7, 1e-5, 4.9e-5, 1e-3] {
            assert_eq!(snap.differences(&file, tolerance), Vec::<String>::new(), "tolerance {tolerance}");
        }
    }

    #[test]
    fn a_snapshot_cut_short_is_an_error_naming_what_is_missing() {
        let v = Volume::from_fn([6, 5, 4], Channel::rgb(), |x, y, _, o| o.copy_from_slice(&[x as f32, y as f32, 0.5]))
            .unwrap();
        let text = Snapshot::of(&v).to_text();
        let cases = [("stat G", "1 stat and 0 thumb"), ("thumb B", "3 stat and 2 thumb"), ("hash", "no hash")];
        for (cut_before, want) in cases {
            let short = &text[..text.find(cut_before).unwrap()];
            let err = Snapshot::parse(short).unwrap_err().to_string();
            assert!(err.contains(want), "cut before {cut_before:?}: {err}");
        }
        for (field, value) in [("stat R", "NaN"), ("thumb G", "nan"), ("stat B", "inf")] {
            let start = text.find(field).unwrap() + field.len() + 1;
            let end = start + text[start..].find(' ').unwrap();
            let damaged = format!("{}{value}{}", &text[..start], &text[end..]);
            let err = Snapshot::parse(&damaged).unwrap_err().to_string();
            assert!(err.contains(&format!("\"{value}\" is not a finite number")), "{err}");
        }
        let thumb_cut = &text[..text.len() - 8];
        assert!(Snapshot::parse(thumb_cut).unwrap_err().to_string().contains("thumb line 3 has 63 values"));
        // a dims line that is there but wrong is named as wrong, not as missing
        for dims in ["0 0 0", "6 5", "6 5 4.5"] {
            let damaged = text.replacen("dims 6 5 4", &format!("dims {dims}"), 1);
            let err = Snapshot::parse(&damaged).unwrap_err().to_string();
            assert!(err.contains(&format!("dims line '{dims}'")) && err.contains("at least 1"), "{err}");
        }
    }

    #[test]
    fn differences_report_missing_channel_data_instead_of_panicking() {
        let v = Volume::from_fn([4, 4, 4], Channel::rgb(), |x, _, _, o| o.copy_from_slice(&[x as f32; 3])).unwrap();
        let snap = Snapshot::of(&v);
        let mut short = snap.clone();
        short.stats.truncate(1);
        short.thumbs.truncate(1);
        let found = snap.differences(&short, 0.01);
        assert_eq!(found, ["channel G: statistics or thumbnail missing", "channel B: statistics or thumbnail missing"]);
    }
}
