//! The fill spec (TOML): a raw serde form, then a validated [`FillSpec`]. Every error names
//! the file, the field, the value and what is allowed. Paths in the spec are relative to
//! its folder. The format, with examples: `docs/fill.md`.

use super::{manifest, values};
use crate::error::{Error, Result};
use crate::fill::spec::{DEFAULT_REGION_BAND, DepthSpec, FaceGroup, FillSpec, PasteSpec, RegionSpec};
use crate::texture_type::TextureType;
use crate::volume::Axis;
use glam::{Quat, Vec3};
use serde::Deserialize;
use std::path::Path;

/// Allowed target tet counts.
pub const TETS: std::ops::RangeInclusive<usize> = 100..=200_000;

/// A face group's `angle` when a spec gives none: no limit (the thesis' multi-face fill).
pub const NO_LIMIT: f32 = 180.0;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpec {
    exemplar: String,
    library: Option<String>,
    built: Option<String>,
    #[serde(rename = "type")]
    texture_type: Option<String>,
    #[serde(default)]
    seed: u64,
    scale: Option<f32>,
    tets: Option<usize>,
    axes: Option<String>,
    mask_falloff: Option<f32>,
    #[serde(default)]
    direction: Vec<RawStroke>,
    #[serde(default)]
    depth: Option<RawDepth>,
    #[serde(default)]
    scale_at: Vec<RawScale>,
    #[serde(default)]
    paste: Vec<RawPaste>,
    #[serde(default)]
    region: Vec<RawRegion>,
    region_band: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion {
    exemplar: String,
    depth: [f32; 2],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStroke {
    points: Vec<[f32; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDepth {
    surface: Option<bool>,
    #[serde(default)]
    axis: Vec<Vec<[f32; 3]>>,
    taper: Option<f32>,
    #[serde(default)]
    points: Vec<[f32; 4]>,
    #[serde(default)]
    faces: Vec<RawFaces>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFaces {
    at: [f32; 3],
    crease: Option<f32>,
    angle: Option<f32>,
    value: f32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScale {
    point: [f32; 3],
    scale: f32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPaste {
    exemplar: String,
    at: [f32; 3],
    rotate: Option<String>,
    scale: f32,
}

/// Reads and validates a fill spec. A file that is not TOML is named as such, and its
/// content is not quoted.
pub fn read_fill_spec(path: &Path) -> Result<FillSpec> {
    let text = super::read_text(path, "fill spec")?;
    let folder = path.parent().unwrap_or(Path::new("."));
    spec_of(&text, folder, manifest::has_toml_name(path)).map_err(|e| e.in_file(path))
}

/// Validates fill spec text; `folder` resolves relative paths.
pub fn parse_fill_spec(text: &str, folder: &Path) -> Result<FillSpec> {
    spec_of(text, folder, true)
}

/// [`parse_fill_spec`]; `quote` allows a syntax error to show the line it is on. Errors
/// of a field start with the line it is on.
fn spec_of(text: &str, folder: &Path, quote: bool) -> Result<FillSpec> {
    let raw: RawSpec = toml::from_str(text).map_err(|e| {
        let error = manifest::syntax_error(text, &e, "fill spec", quote);
        // a tet count of the wrong kind: say its range, as for one out of it
        let start = e.span().map_or(0, |s| s.start.min(text.len()));
        let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
        if e.span().is_some() && text[line_start..].trim_start().starts_with("tets") {
            let range = format!("a whole number, {} to {}", TETS.start(), TETS.end());
            return Error::invalid(error.to_string().replace("a whole number, 0 or more", &range));
        }
        error
    })?;
    validate(raw, folder).map_err(|e| {
        let message = e.to_string();
        match manifest::line_of(text, manifest::leading_path(&message)) {
            Some(line) => Error::invalid(format!("line {line}: {message}")),
            None => e,
        }
    })
}

fn validate(raw: RawSpec, folder: &Path) -> Result<FillSpec> {
    let texture_type = raw
        .texture_type
        .as_deref()
        .map(|t| t.parse::<TextureType>().map_err(|e| Error::invalid(format!("type = {t:?}: {e}"))))
        .transpose()?;
    let tets = values::within("tets =", raw.tets.unwrap_or(5000), *TETS.start(), *TETS.end())?;
    positive("scale", raw.scale)?;
    let falloff = raw.mask_falloff.map(|f| values::falloff("mask_falloff =", f)).transpose()?;
    let here = |p: Option<&String>, default: &str| p.map_or_else(|| default.into(), |p| folder.join(p));
    let band = raw.region_band.unwrap_or(DEFAULT_REGION_BAND);
    let regions = regions(raw.region)?;
    Ok(FillSpec {
        exemplar: raw.exemplar,
        library: here(raw.library.as_ref(), "exemplars/library.toml"),
        built: here(raw.built.as_ref(), "out"),
        texture_type,
        seed: raw.seed,
        scale: raw.scale,
        tets,
        axes: raw.axes.as_deref().map(axes).transpose()?,
        mask_falloff: falloff,
        directions: strokes(&raw.direction)?,
        depth: depth(raw.depth)?,
        scales: scales(&raw.scale_at)?,
        pastes: raw.paste.into_iter().enumerate().map(|(i, p)| paste(i, p)).collect::<Result<_>>()?,
        region_band: region_band(band, &regions)?,
        regions,
    })
}

/// The regions, in order from depth 0 to 1, each range inside 0..1 and meeting the next.
fn regions(raw: Vec<RawRegion>) -> Result<Vec<RegionSpec>> {
    let mut reached = 0.0;
    for (i, r) in raw.iter().enumerate() {
        let [from, to] = r.depth;
        if !(0.0..=1.0).contains(&from) || !(0.0..=1.0).contains(&to) || from >= to {
            return Err(Error::invalid(format!(
                "region[{i}].depth = [{from}, {to}] must be two depths from 0 (surface) to 1 (innermost), the first \
                 smaller"
            )));
        }
        if from != reached {
            return Err(Error::invalid(format!(
                "region[{i}].depth starts at {from}, not at {reached} where {}; the regions run from depth 0 to 1 \
                 in order, each starting where the one before ends",
                if i == 0 { "depth starts".to_string() } else { format!("region[{}] ends", i - 1) }
            )));
        }
        if r.exemplar.trim().is_empty() {
            return Err(Error::invalid(format!("region[{i}].exemplar is empty; name a library exemplar")));
        }
        reached = to;
    }
    if !raw.is_empty() && reached != 1.0 {
        return Err(Error::invalid(format!(
            "region[{}].depth ends at {reached}; the last region reaches depth 1 (the innermost)",
            raw.len() - 1
        )));
    }
    Ok(raw.into_iter().map(|r| RegionSpec { exemplar: r.exemplar, depth: r.depth }).collect())
}

/// The band regions blend across: 0 (a sharp border) to 0.5, and no wider than the
/// narrowest region (the regions checked first).
fn region_band(band: f32, raw: &[RegionSpec]) -> Result<f32> {
    if !(0.0..=0.5).contains(&band) {
        return Err(Error::invalid(format!(
            "region_band = {band} must be a depth width from 0 (a sharp border) to 0.5"
        )));
    }
    if let Some((i, r)) = raw
        .iter()
        .enumerate()
        .filter(|(_, r)| r.depth[1] - r.depth[0] < band)
        .min_by(|a, b| (a.1.depth[1] - a.1.depth[0]).total_cmp(&(b.1.depth[1] - b.1.depth[0])))
    {
        return Err(Error::invalid(format!(
            "region_band = {band} is wider than region[{i}] (depth {} to {}); give a band no wider than the \
             narrowest region",
            r.depth[0], r.depth[1]
        )));
    }
    Ok(band)
}

fn positive(field: &str, value: Option<f32>) -> Result<()> {
    match value {
        Some(v) if !(v.is_finite() && v > 0.0) => {
            Err(Error::invalid(format!("{field} = {v} must be a positive number of model units")))
        }
        _ => Ok(()),
    }
}

fn axes(text: &str) -> Result<[Axis; 2]> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let bad = || {
        Error::invalid(format!("axes = {text:?} must be two different texture axes like \"z,x\" (primary, secondary)"))
    };
    if parts.len() != 2 {
        return Err(bad());
    }
    let a: Axis = parts[0].parse().map_err(|_| bad())?;
    let b: Axis = parts[1].parse().map_err(|_| bad())?;
    if a == b { Err(bad()) } else { Ok([a, b]) }
}

fn point(field: &str, p: [f32; 3]) -> Result<Vec3> {
    let v = Vec3::from(p);
    if v.is_finite() { Ok(v) } else { Err(Error::invalid(format!("{field} = {p:?} must be finite"))) }
}

fn strokes(raw: &[RawStroke]) -> Result<Vec<Vec<Vec3>>> {
    let mut out = Vec::new();
    for (i, s) in raw.iter().enumerate() {
        let line: Vec<Vec3> =
            s.points.iter().map(|p| point(&format!("direction[{i}].points"), *p)).collect::<Result<_>>()?;
        let length: f32 = line.windows(2).map(|w| w[0].distance(w[1])).sum();
        if line.len() < 2 || length <= 0.0 {
            return Err(Error::invalid(format!(
                "direction[{i}].points needs at least two different points (a stroke)"
            )));
        }
        out.push(line);
    }
    Ok(out)
}

fn depth(raw: Option<RawDepth>) -> Result<DepthSpec> {
    let Some(raw) = raw else { return Ok(DepthSpec { surface: true, ..Default::default() }) };
    let mut axes = Vec::new();
    for (i, line) in raw.axis.iter().enumerate() {
        let field = format!("depth.axis[{i}]");
        if line.is_empty() {
            return Err(Error::invalid(format!("{field} is empty; give one point or a polyline")));
        }
        let mut line = line.iter().map(|p| point(&field, *p)).collect::<Result<Vec<_>>>()?;
        // a point repeated in a row adds no segment (and a segment without length has no
        // direction to carry on along past the axis' end)
        line.dedup();
        axes.push(line);
    }
    let mut points = Vec::new();
    for (i, p) in raw.points.iter().enumerate() {
        let field = format!("depth.points[{i}]");
        if !(0.0..=1.0).contains(&p[3]) {
            return Err(Error::invalid(format!("{field}: depth {} must be 0 (surface) to 1 (innermost)", p[3])));
        }
        points.push((point(&field, [p[0], p[1], p[2]])?, p[3]));
    }
    let mut faces = Vec::new();
    for (i, f) in raw.faces.iter().enumerate() {
        let field = format!("depth.faces[{i}]");
        if !(0.0..=1.0).contains(&f.value) {
            return Err(Error::invalid(format!("{field}.value = {} must be 0 to 1", f.value)));
        }
        let crease = f.crease.unwrap_or(30.0);
        if !(0.0..=180.0).contains(&crease) {
            return Err(Error::invalid(format!("{field}.crease = {crease} must be 0 to 180 degrees")));
        }
        let angle = f.angle.unwrap_or(NO_LIMIT);
        if !(0.0..=180.0).contains(&angle) {
            return Err(Error::invalid(format!("{field}.angle = {angle} must be 0 to 180 degrees")));
        }
        faces.push(FaceGroup { at: point(&field, f.at)?, crease, angle, value: f.value });
    }
    let taper = raw.taper.unwrap_or(0.0);
    if !(0.0..=0.5).contains(&taper) {
        return Err(Error::invalid(format!(
            "depth.taper is {taper}; allowed are 0 (the core ends squarely) to 0.5 (the whole axis tapers)"
        )));
    }
    Ok(DepthSpec { surface: raw.surface.unwrap_or(true), axes, taper, points, faces })
}

fn scales(raw: &[RawScale]) -> Result<Vec<(Vec3, f32)>> {
    raw.iter()
        .enumerate()
        .map(|(i, s)| {
            positive(&format!("scale_at[{i}].scale"), Some(s.scale))?;
            Ok((point(&format!("scale_at[{i}].point"), s.point)?, s.scale))
        })
        .collect()
}

fn paste(i: usize, raw: RawPaste) -> Result<PasteSpec> {
    positive(&format!("paste[{i}].scale"), Some(raw.scale))?;
    let rotation = match raw.rotate.as_deref() {
        Some(r) => values::rotation(&format!("paste[{i}].rotate"), r)?,
        None => Quat::IDENTITY,
    };
    Ok(PasteSpec { exemplar: raw.exemplar, at: point(&format!("paste[{i}].at"), raw.at)?, rotation, scale: raw.scale })
}

/// `spec` as the TOML [`parse_fill_spec`] reads back (the library and build folder as
/// given, relative to where the text is written); a header comment says what wrote it.
pub fn spec_text(spec: &FillSpec, library: &str, built: &str, header: &str) -> String {
    let v = |p: Vec3| format!("[{}, {}, {}]", p.x, p.y, p.z);
    let line = |ps: &[Vec3]| format!("[{}]", ps.iter().map(|p| v(*p)).collect::<Vec<_>>().join(", "));
    let mut t = header.lines().map(|l| format!("# {l}\n")).collect::<String>();
    t += &format!("exemplar = {:?}\nlibrary = {library:?}\nbuilt = {built:?}\n", spec.exemplar);
    if let Some(kind) = spec.texture_type {
        t += &format!("type = \"{kind}\"\n");
    }
    t += &format!("seed = {}\ntets = {}\n", spec.seed, spec.tets);
    if let Some(scale) = spec.scale {
        t += &format!("scale = {scale}\n");
    }
    if let Some([a, b]) = spec.axes {
        t += &format!("axes = \"{a},{b}\"\n");
    }
    if let Some(falloff) = spec.mask_falloff {
        t += &format!("mask_falloff = {falloff}\n");
    }
    if spec.region_band != DEFAULT_REGION_BAND {
        t += &format!("region_band = {}\n", spec.region_band);
    }
    for stroke in &spec.directions {
        t += &format!("\n[[direction]]\npoints = {}\n", line(stroke));
    }
    let d = &spec.depth;
    t += &format!("\n[depth]\nsurface = {}\n", d.surface);
    if !d.axes.is_empty() {
        t += &format!("axis = [{}]\n", d.axes.iter().map(|a| line(a)).collect::<Vec<_>>().join(", "));
    }
    if d.taper > 0.0 {
        t += &format!("taper = {}\n", d.taper);
    }
    if !d.points.is_empty() {
        let points: Vec<String> = d.points.iter().map(|(p, x)| format!("[{}, {}, {}, {x}]", p.x, p.y, p.z)).collect();
        t += &format!("points = [{}]\n", points.join(", "));
    }
    for f in &d.faces {
        t += &format!("\n[[depth.faces]]\nat = {}\ncrease = {}\n", v(f.at), f.crease);
        if f.angle < NO_LIMIT {
            t += &format!("angle = {}\n", f.angle);
        }
        t += &format!("value = {}\n", f.value);
    }
    for (p, scale) in &spec.scales {
        t += &format!("\n[[scale_at]]\npoint = {}\nscale = {scale}\n", v(*p));
    }
    for r in &spec.regions {
        t += &format!("\n[[region]]\nexemplar = {:?}\ndepth = [{}, {}]\n", r.exemplar, r.depth[0], r.depth[1]);
    }
    for p in &spec.pastes {
        let (axis, angle) = p.rotation.to_axis_angle();
        let axis = if axis.is_finite() && axis.length() > 0.5 { axis } else { Vec3::Z };
        t += &format!(
            "\n[[paste]]\nexemplar = {:?}\nat = {}\nrotate = \"{},{},{},{}\"\nscale = {}\n",
            p.exemplar,
            v(p.at),
            axis.x,
            axis.y,
            axis.z,
            angle.to_degrees(),
            p.scale
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every part of a spec survives writing and reading back.
    #[test]
    fn a_written_spec_reads_back_the_same() {
        let mut spec = FillSpec::new("kiwi");
        spec.texture_type = Some(TextureType::T2b);
        (spec.seed, spec.tets, spec.scale, spec.mask_falloff) = (7, 3000, Some(0.4), Some(0.1));
        spec.axes = Some([Axis::Z, Axis::X]);
        spec.directions = vec![vec![Vec3::new(-0.8, 0.0, 0.1), Vec3::new(0.8, 0.25, 0.0)]];
        spec.depth.axes = vec![vec![Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)]];
        spec.depth.taper = 0.5;
        spec.depth.points = vec![(Vec3::new(0.1, 0.2, 0.3), 0.75)];
        spec.depth.faces = vec![
            FaceGroup { at: Vec3::new(0.0, 0.5, 0.0), crease: 25.0, angle: NO_LIMIT, value: 1.0 },
            FaceGroup { at: Vec3::new(0.0, -0.5, 0.0), crease: 30.0, angle: 20.0, value: 0.5 },
        ];
        spec.scales = vec![(Vec3::new(0.5, 0.0, 0.0), 0.2)];
        let rotation = Quat::from_axis_angle(Vec3::Y, 30f32.to_radians());
        spec.pastes = vec![PasteSpec { exemplar: "marble".into(), at: Vec3::new(0.1, 0.0, 0.0), rotation, scale: 0.3 }];
        spec.regions = vec![
            RegionSpec { exemplar: "bark".into(), depth: [0.0, 0.2] },
            RegionSpec { exemplar: "wood".into(), depth: [0.2, 1.0] },
        ];
        spec.region_band = 0.1;
        let folder = Path::new("/specs");
        (spec.library, spec.built) = (folder.join("lib.toml"), folder.join("../out"));
        let text = spec_text(&spec, "lib.toml", "../out", "written by a test\nsecond line");
        assert!(text.starts_with("# written by a test\n# second line\n"), "{text}");
        let back = parse_fill_spec(&text, folder).unwrap();
        let paste = (back.pastes[0].rotation.dot(rotation).abs() - 1.0).abs();
        assert!(paste < 1e-5, "{text}");
        assert_eq!(FillSpec { pastes: spec.pastes.clone(), ..back }, spec, "{text}");
    }

    #[test]
    fn a_full_spec_parses() {
        let text = r#"
            exemplar = "kiwi"
            type = "2-b"
            seed = 4
            tets = 3000
            axes = "z,x"
            [[direction]]
            points = [[0, 0, -1], [0, 0, 1]]
            [depth]
            axis = [[[0, 0, -0.8], [0, 0, 0.8]]]
            points = [[0.1, 0, 0, 0.5]]
            [[depth.faces]]
            at = [0, 1, 0]
            value = 1
            [[scale_at]]
            point = [0, 0, 0]
            scale = 0.3
            [[paste]]
            exemplar = "marble"
            at = [0, 0, 0]
            rotate = "0,1,0,45"
            scale = 0.5
        "#;
        let s = parse_fill_spec(text, Path::new("specs")).unwrap();
        assert_eq!(s.texture_type, Some(TextureType::T2b));
        assert_eq!(s.axes, Some([Axis::Z, Axis::X]));
        assert_eq!(s.library, Path::new("exemplars/library.toml"));
        assert!(s.depth.surface && s.depth.axes[0].len() == 2 && s.depth.faces[0].crease == 30.0);
        assert_eq!(s.pastes[0].exemplar, "marble");
    }

    /// An axis point repeated in a row is read once: the same polyline, the same ends.
    #[test]
    fn a_repeated_axis_point_is_read_once() {
        let read = |axis: &str| {
            parse_fill_spec(&format!("exemplar = \"a\"\n[depth]\naxis = [{axis}]\n"), Path::new("."))
                .unwrap()
                .depth
                .axes
        };
        let plain = read("[[-0.5, 0, 0], [0.5, 0, 0]]");
        assert_eq!(read("[[-0.5, 0, 0], [-0.5, 0, 0], [0.5, 0, 0], [0.5, 0, 0]]"), plain);
        assert_eq!(read("[[0, 0, 0], [0, 0, 0]]"), vec![vec![Vec3::ZERO]]);
    }

    #[test]
    fn mistakes_name_the_field_and_the_allowed_values() {
        let cases = [
            ("exemplar = \"a\"\ntets = 5", "tets = 5"),
            ("exemplar = \"a\"\ntets = \"many\"", "100 to 200000"),
            ("exemplar = \"a\"\nscale = -1", "scale = -1"),
            ("exemplar = \"a\"\naxes = \"z,z\"", "axes"),
            ("exemplar = \"a\"\ntype = \"3-a\"", "type"),
            ("exemplar = \"a\"\n[[direction]]\npoints = [[0, 0, 0]]", "direction[0]"),
            ("exemplar = \"a\"\n[depth]\npoints = [[0, 0, 0, 2]]", "depth.points[0]"),
            ("exemplar = \"a\"\ncolour = 1", "unknown field"),
            ("exemplar = \"a\"\n[[region]]\nexemplar = \"b\"\ndepth = [0, 1.5]", "region[0].depth = [0, 1.5]"),
            ("exemplar = \"a\"\n[[region]]\nexemplar = \"b\"\ndepth = [0.1, 1]", "not at 0 where depth starts"),
            (
                "exemplar = \"a\"\n[[region]]\nexemplar = \"b\"\ndepth = [0, 0.3]\n[[region]]\nexemplar = \"c\"\ndepth = [0.4, 1]",
                "region[1].depth starts at 0.4, not at 0.3 where region[0] ends",
            ),
            ("exemplar = \"a\"\n[[region]]\nexemplar = \"b\"\ndepth = [0, 0.5]", "reaches depth 1"),
            (
                "exemplar = \"a\"\nregion_band = 0.2\n[[region]]\nexemplar = \"b\"\ndepth = [0, 0.1]\n[[region]]\nexemplar = \"c\"\ndepth = [0.1, 1]",
                "wider than region[0]",
            ),
            ("exemplar = \"a\"\nregion_band = 0.7", "region_band = 0.7"),
            (
                "exemplar = \"a\"\nregion_band = 0\n[[region]]\nexemplar = \"b\"\ndepth = [1, 0]",
                "line 5: region[0].depth = [1, 0] must be two depths",
            ),
        ];
        for (text, want) in cases {
            let e = parse_fill_spec(text, Path::new(".")).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?} gave {e}");
        }
    }
}
