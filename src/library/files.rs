//! The one place that names the files a library build writes into its output folder.

use crate::io::manifest::{Entry, MaskKind};
use crate::mask::Layer;
use std::path::{Path, PathBuf};

/// The cache folder inside an output folder (records and the build lock).
pub const CACHE: &str = ".cache";

/// The built volume of exemplar `name`.
pub fn volume(output: &Path, name: &str) -> PathBuf {
    output.join(format!("{name}.exr"))
}

/// The contact sheet of exemplar `name`.
pub fn sheet(name: &str) -> String {
    format!("{name}.sheet.png")
}

/// The 3D view (a `solidtex web` page) of exemplar `name`.
pub fn view(name: &str) -> String {
    format!("{name}.view.html")
}

/// The cache record of exemplar `name`, relative to the output folder.
pub fn record(name: &str) -> String {
    format!("{CACHE}/{name}.json")
}

/// The splotch mask of exemplar `name`.
pub fn splotch_mask(output: &Path, name: &str) -> PathBuf {
    output.join(format!("{name}.mask.exr"))
}

/// The folder of exemplar `name`'s outer, middle and inner masks.
pub fn layer_folder(output: &Path, name: &str) -> PathBuf {
    output.join(format!("{name}.masks"))
}

/// One of exemplar `name`'s layer masks.
pub fn layer_mask(output: &Path, name: &str, layer: Layer) -> PathBuf {
    layer_folder(output, name).join(layer_file(layer))
}

/// The file of a layer mask inside its folder.
pub fn layer_file(layer: Layer) -> String {
    format!("{}.exr", layer.name())
}

/// An extra export of exemplar `name` (`nrrd`, `vol`, `png` or the `slices` folder).
pub fn export(output: &Path, name: &str, format: &str) -> PathBuf {
    match format {
        "slices" => output.join(format!("{name}_slices")),
        ext => output.join(format!("{name}.{ext}")),
    }
}

/// Every file and folder an entry's build writes, relative to the output folder, in a
/// fixed order (the volume, the sheet, the 3D view, the exports, the masks; not the cache
/// record).
pub fn outputs(entry: &Entry) -> Vec<String> {
    let name = &entry.name;
    let here = Path::new("");
    let relative = |p: PathBuf| p.to_string_lossy().into_owned();
    let mut files = vec![relative(volume(here, name)), sheet(name), view(name)];
    files.extend(entry.exports.iter().map(|e| relative(export(here, name, e))));
    for kind in &entry.masks {
        files.push(match kind {
            MaskKind::Splotch => relative(splotch_mask(here, name)),
            MaskKind::Layered => relative(layer_folder(here, name)),
        });
    }
    files
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::manifest::parse_plan;

    #[test]
    fn an_entry_names_its_volume_sheet_exports_and_masks() {
        let text = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\n\
                    exports = [\"nrrd\", \"slices\"]\nmasks = [\"splotch\", \"layered\"]\n";
        let plan = parse_plan(text, Path::new(".")).unwrap();
        assert_eq!(
            outputs(&plan.entries[0]),
            ["m.exr", "m.sheet.png", "m.view.html", "m.nrrd", "m_slices", "m.mask.exr", "m.masks"]
        );
        assert_eq!(layer_mask(Path::new("out"), "m", Layer::Inner), Path::new("out/m.masks/inner.exr"));
        assert_eq!(record("m"), ".cache/m.json");
    }
}
