//! The exemplar library manifest (`exemplars/library.toml`): a raw serde form, then
//! a validated [`Plan`]. Every error names the file, the entry, the field, the value
//! and what is allowed.
//!
//! ```toml
//! [[exemplar]]
//! name = "marble"              # output file stem: letters, digits, '-', '_'
//! recipe = "procedural:marble" # procedural:marble | procedural:strata | procedural:wood
//! size = [64, 64, 64]          # or a single number for a cube
//! seed = 1
//! ```

use crate::error::{Error, Result};
use crate::procedural::Recipe;
use serde::Deserialize;
use std::path::Path;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    #[serde(default)]
    exemplar: Vec<RawExemplar>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExemplar {
    name: String,
    recipe: String,
    size: RawSize,
    #[serde(default)]
    seed: u64,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawSize {
    Cube(usize),
    Dims(Vec<usize>),
}

/// One validated library entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Output file stem.
    pub name: String,
    /// What makes the volume.
    pub recipe: Recipe,
    /// Size in voxels.
    pub dims: [usize; 3],
    /// Seed for everything random.
    pub seed: u64,
}

/// A validated manifest: what `solidtex build` will make.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Entries in manifest order.
    pub entries: Vec<Entry>,
}

/// Largest side accepted in a manifest.
pub const MAX_SIDE: usize = 512;

/// Read and validate a manifest file.
pub fn read_plan(path: &Path) -> Result<Plan> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_plan(&text).map_err(|e| e.in_file(path))
}

/// Validate manifest text.
pub fn parse_plan(text: &str) -> Result<Plan> {
    let raw: RawManifest = toml::from_str(text).map_err(|e| Error::invalid(format!("invalid manifest: {e}")))?;
    let mut entries: Vec<Entry> = Vec::new();
    for (i, e) in raw.exemplar.into_iter().enumerate() {
        let entry = validate(i, e)?;
        if entries.iter().any(|x| x.name == entry.name) {
            return Err(Error::invalid(format!(
                "exemplar[{i}].name = {:?} is used twice; names must be unique",
                entry.name
            )));
        }
        entries.push(entry);
    }
    if entries.is_empty() {
        return Err(Error::invalid("the manifest has no [[exemplar]] entries"));
    }
    Ok(Plan { entries })
}

fn validate(i: usize, raw: RawExemplar) -> Result<Entry> {
    let ok_name = !raw.name.is_empty() && raw.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if !ok_name {
        return Err(Error::invalid(format!(
            "exemplar[{i}].name = {:?} is not allowed: use ASCII letters, digits, '-' and '_'",
            raw.name
        )));
    }
    let recipe = raw
        .recipe
        .strip_prefix("procedural:")
        .ok_or_else(|| {
            Error::invalid(format!(
                "exemplar[{i}] ({}): recipe = {:?} is unknown; allowed: procedural:marble, procedural:strata, procedural:wood",
                raw.name, raw.recipe
            ))
        })?
        .parse::<Recipe>()
        .map_err(|e| Error::invalid(format!("exemplar[{i}] ({}): recipe: {e}", raw.name)))?;
    let dims = match raw.size {
        RawSize::Cube(n) => [n; 3],
        RawSize::Dims(v) if v.len() == 3 => [v[0], v[1], v[2]],
        RawSize::Dims(v) => {
            return Err(Error::invalid(format!(
                "exemplar[{i}] ({}): size = {v:?} must be one number or three, e.g. 64 or [64, 64, 32]",
                raw.name
            )));
        }
    };
    if dims.iter().any(|d| *d == 0 || *d > MAX_SIDE) {
        return Err(Error::invalid(format!(
            "exemplar[{i}] ({}): size = {dims:?} is out of range; each side must be 1..={MAX_SIDE}",
            raw.name
        )));
    }
    Ok(Entry { name: raw.name, recipe, dims, seed: raw.seed })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_good_manifest_becomes_a_plan() {
        let plan = parse_plan(
            "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = 3\n\
             [[exemplar]]\nname = \"s\"\nrecipe = \"procedural:strata\"\nsize = [8, 8, 16]\n",
        )
        .unwrap();
        assert_eq!(plan.entries[0].dims, [8, 8, 8]);
        assert_eq!(plan.entries[1].recipe, Recipe::Strata);
        assert_eq!(plan.entries[1].seed, 0);
    }

    #[test]
    fn each_mistake_names_its_field() {
        let cases = [
            ("name = \"a b\"\nrecipe = \"procedural:marble\"\nsize = 8", "name = \"a b\""),
            ("name = \"a\"\nrecipe = \"sweep:x\"\nsize = 8", "recipe = \"sweep:x\""),
            ("name = \"a\"\nrecipe = \"procedural:granite\"\nsize = 8", "granite"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = [8, 8]", "size = [8, 8]"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 0", "out of range"),
            ("name = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\ncolour = 1", "colour"),
        ];
        for (body, expected) in cases {
            let err = parse_plan(&format!("[[exemplar]]\n{body}\n")).unwrap_err().to_string();
            assert!(err.contains(expected), "{body}: {err}");
        }
    }
}
