//! A guided model (`.guided`, TOML): the recipe of a solid synthesized along a model's
//! frame field, as `solidtex guided` was given it (the mesh, the fill spec, the exemplars
//! and the settings), so that `view`, `cut`, `bake` and `render` synthesize what they show on demand
//! instead of reading stored voxels. Paths are relative to the model file's folder.

use super::atomic;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The extension of a guided model.
pub const EXTENSION: &str = "guided";

/// What a guided solid is made from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuidedModel {
    /// The closed mesh.
    pub mesh: PathBuf,
    /// The fill spec (strokes, depth, regions, scales).
    pub spec: PathBuf,
    /// The exemplar image (plane across frame x, or all three).
    pub exemplar: Option<PathBuf>,
    /// A solid exemplar volume instead.
    pub solid: Option<PathBuf>,
    /// The exemplar across frame y.
    pub ey: Option<PathBuf>,
    /// The exemplar across frame z.
    pub ez: Option<PathBuf>,
    /// Feature masks of the exemplars.
    pub mask: Option<PathBuf>,
    /// The feature mask of `ey`.
    pub ey_mask: Option<PathBuf>,
    /// The feature mask of `ez`.
    pub ez_mask: Option<PathBuf>,
    /// The longest side exemplars are shrunk to.
    pub max_exemplar: Option<usize>,
    /// Layered exemplars.
    #[serde(default)]
    pub layered: bool,
    /// The three planes matched directly, not through a solid cube.
    #[serde(default)]
    pub planes: bool,
    /// Voxels along the grid's longest side.
    pub res: usize,
    /// Neighbourhood side at the finer levels.
    pub n: usize,
    /// Neighbourhood side at the coarsest level.
    pub coarse_n: usize,
    /// Random seed.
    pub seed: u64,
    /// The field's tet count, overriding the spec's.
    pub tets: Option<usize>,
}

impl GuidedModel {
    /// Every path of the model, mutably.
    fn paths_mut(&mut self) -> impl Iterator<Item = &mut PathBuf> {
        [&mut self.mesh, &mut self.spec].into_iter().chain(
            [
                &mut self.exemplar,
                &mut self.solid,
                &mut self.ey,
                &mut self.ez,
                &mut self.mask,
                &mut self.ey_mask,
                &mut self.ez_mask,
            ]
            .into_iter()
            .flatten(),
        )
    }

    /// Every input file the model names.
    pub fn inputs(&self) -> Vec<&Path> {
        self.named_inputs().into_iter().map(|(_, p)| p).collect()
    }

    /// Every input file the model names, with its field's name.
    pub fn named_inputs(&self) -> Vec<(&'static str, &Path)> {
        let optional = [
            ("exemplar", &self.exemplar),
            ("solid", &self.solid),
            ("ey", &self.ey),
            ("ez", &self.ez),
            ("mask", &self.mask),
            ("ey_mask", &self.ey_mask),
            ("ez_mask", &self.ez_mask),
        ];
        let given = optional.into_iter().filter_map(|(name, p)| p.as_deref().map(|p| (name, p)));
        [("mesh", self.mesh.as_path()), ("spec", self.spec.as_path())].into_iter().chain(given).collect()
    }
}

/// Write `model` (its paths as the command line gave them) to `path`, the paths made
/// relative to `path`'s folder.
pub fn write(path: &Path, model: &GuidedModel) -> Result<()> {
    let folder = path.parent().filter(|f| !f.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut relative = model.clone();
    for p in relative.paths_mut() {
        *p = PathBuf::from(super::written_relative(p, folder));
    }
    let body = toml::to_string(&relative).map_err(|e| Error::invalid(format!("writing the guided model: {e}")))?;
    let text = format!(
        "# A guided model written by `solidtex guided`: `solidtex view`, `cut`, `bake` and `render`\n# synthesize what they show from \
         it along the spec's frame field. Paths are relative to this file.\n{body}"
    );
    atomic::write_document(path, text.as_bytes())
}

/// Read a guided model, its paths resolved against its folder.
pub fn read(path: &Path) -> Result<GuidedModel> {
    let text = atomic::read_text(path, "guided model")?;
    let mut model: GuidedModel = toml::from_str(&text).map_err(|e| {
        let at = e.span().map(|span| where_in(&text, span.start)).unwrap_or_default();
        let why = e
            .message()
            .replace("expected usize", "expected a whole number")
            .replace("expected u64", "expected a whole number");
        Error::file(path, format!("{at}is not a guided model as `solidtex guided` writes it: {why}"))
    })?;
    if model.exemplar.is_some() && model.solid.is_some() {
        return Err(Error::file(path, "gives both exemplar and solid; a guided model takes one of them"));
    }
    let folder = super::model_folder(path);
    for p in model.paths_mut() {
        *p = folder.join(&*p);
    }
    for (field, file) in model.named_inputs() {
        super::model_input(path, field, file, &folder)?;
    }
    Ok(model)
}

/// "line N (TEXT): " for the byte `at` of `text`: where a parse error is.
fn where_in(text: &str, at: usize) -> String {
    let line = super::manifest::line_at(text, at);
    let content = text.lines().nth(line - 1).unwrap_or("").trim();
    format!("line {line} ({content}): ")
}

/// Whether `path` names a guided model (by its extension).
pub fn is_guided(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case(EXTENSION))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model reads back as written, its paths relative to its folder on disk and
    /// resolved again on reading; a file that is not one, that gives both an exemplar and a
    /// solid, whose value does not parse (named by its line) or whose input is missing (named
    /// by its field) is refused by name.
    #[test]
    fn a_guided_model_reads_back_with_its_paths_resolved() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("models")).unwrap();
        let model = GuidedModel {
            mesh: d.join("fruit.obj"),
            spec: d.join("kiwi.toml"),
            exemplar: Some(d.join("photo.png")),
            solid: None,
            ey: None,
            ez: None,
            mask: None,
            ey_mask: None,
            ez_mask: None,
            max_exemplar: Some(96),
            layered: true,
            planes: false,
            res: 256,
            n: 5,
            coarse_n: 7,
            seed: 3,
            tets: None,
        };
        for file in ["fruit.obj", "kiwi.toml", "photo.png"] {
            std::fs::write(d.join(file), b"").unwrap();
        }
        let path = d.join("models/fruit.guided");
        write(&path, &model).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("mesh = \"../fruit.obj\""), "{text}");
        let back = read(&path).unwrap();
        assert_eq!(back.res, 256);
        assert!(same(&back.mesh, &model.mesh) && same(back.exemplar.as_ref().unwrap(), &d.join("photo.png")));
        std::fs::write(d.join("bad.guided"), "mesh = 3\n").unwrap();
        let e = read(&d.join("bad.guided")).unwrap_err().to_string();
        assert!(e.contains("bad.guided") && e.contains("not a guided model"), "{e}");
        std::fs::write(d.join("both.guided"), format!("{text}solid = \"cube.exr\"\n")).unwrap();
        let e = read(&d.join("both.guided")).unwrap_err().to_string();
        assert!(e.contains("both.guided") && e.contains("both exemplar and solid"), "{e}");
        let edited = |from: &str, to: &str| {
            std::fs::write(d.join("edited.guided"), text.replace(from, to)).unwrap();
            read(&d.join("edited.guided")).unwrap_err().to_string()
        };
        let e = edited("res = 256", "res = -5");
        assert!(e.contains("edited.guided: line ") && e.contains("(res = -5)") && e.contains("whole number"), "{e}");
        let e = edited("../fruit.obj", "../nope.obj");
        assert!(e.contains("edited.guided: mesh = ") && e.contains("nope.obj\": no such file"), "{e}");
    }

    /// Whether two paths name one place, `..` and `.` resolved by their text.
    fn same(a: &Path, b: &Path) -> bool {
        let plain = |p: &Path| {
            let mut out = PathBuf::new();
            for c in p.components() {
                match c {
                    std::path::Component::ParentDir => _ = out.pop(),
                    std::path::Component::CurDir => {}
                    other => out.push(other),
                }
            }
            out
        };
        plain(a) == plain(b)
    }
}
