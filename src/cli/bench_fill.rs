//! The filling workloads of `solidtex bench`: tet meshing, filling, cutting, viewing and
//! baking on shapes the project draws itself, and — with `--meshes DIR` — on closed meshes
//! from elsewhere (the bunny, sphere, stepped cylinder and pipe in ../shared/data/meshes).

use super::bench::BenchArgs;
use crate::error::Result;
use crate::fill::render::{self, Textures, View};
use crate::fill::spec::FillSpec;
use crate::fill::{self, Job, LstModel, MaskRef, Source, mesher, translucent};
use crate::mask::{self, Layer};
use crate::mesh::{Mesh, shapes};
use crate::procedural::{Recipe, generate};
use crate::progress::NoProgress;
use crate::volume::{Axis, Volume};
use crate::{TextureType, io};
use glam::Vec3;
use std::time::Instant;

/// The meshes of ../shared/data/meshes worth timing, by file name.
const OTHERS: [&str; 4] = ["libigl_bunny.obj", "cgal_sphere.obj", "cgal_dragknob.obj", "cgal_pipe.obj"];

/// The filling workloads of one mesh (`{}`: the mesh's name).
const NAMES: [&str; 7] =
    ["tetmesh/{}/5k", "paste/{}/5k", "cut/{}/512", "view/{}/512", "bake/{}/64", "render/{}/512", "export/{}/512"];

/// The one large fill: the drawn fruit at 50,000 tets, where the parallel parts show.
const LARGE: &str = "fill/large/fruit-2b/50k";

/// The names of all filling workloads (those of the optional meshes too).
pub fn names() -> Vec<String> {
    let cases = ["fruit-2b", "pipe-0"].into_iter().chain(OTHERS.map(|n| n.trim_end_matches(".obj")));
    let each = cases.flat_map(|case| NAMES.map(|n| format!("fill/{}", n.replace("{}", case))));
    each.chain(std::iter::once(LARGE.to_string())).collect()
}

/// Run the filling workloads.
pub fn run(args: &BenchArgs) -> Result<()> {
    if !names().iter().any(|n| wanted(args, n)) {
        return Ok(());
    }
    say!("{:<30} {:>5} {:>9} {:>9}  {}", "workload", "runs", "median s", "min s", "figures");
    let marble = generate(Recipe::Marble, [64; 3], 5)?;
    let fruit = shapes::named("fruit").expect("a drawn shape");
    let layered = layered_case(&fruit, &marble)?;
    let mut cases = vec![("fruit-2b", fruit, layered)];
    let pipe = shapes::named("pipe").expect("a drawn shape");
    cases.push(("pipe-0", pipe, isotropic_case(&marble)?));
    for name in OTHERS {
        let path = args.meshes.as_deref().map(|d| d.join(name));
        if let Some(path) = path.filter(|p| p.exists()) {
            let mesh = io::mesh_file::read_mesh(&path)?.canonical();
            let case = isotropic_case(&marble)?;
            cases.push((name.trim_end_matches(".obj"), mesh, case));
        }
    }
    for (name, mesh, case) in &cases {
        let large = *name == "fruit-2b" && wanted(args, LARGE);
        if !large && !NAMES.iter().any(|n| wanted(args, &format!("fill/{}", n.replace("{}", name)))) {
            continue;
        }
        timed(args, &format!("fill/tetmesh/{name}/5k"), || {
            // as a fill meshes: covering the solid
            let tets = mesher::tetrahedralize_covering(
                mesh,
                5000,
                crate::fill::cover_margin(&case.spec, fill::uses_depth(case.kind)),
            )?;
            Ok(format!("{} tets, min dihedral {:.1} deg", tets.tets.len(), tets.min_dihedral_degrees()))
        })?;
        let mut model = None;
        timed(args, &format!("fill/paste/{name}/5k"), || {
            let (m, report) = case.fill(mesh)?;
            let bytes = io::lst_file::to_bytes(&m).len();
            let p = &report.paste;
            let figures = format!(
                "{} tets, {} patches, {:.1} layers, angle {:.1}/{:.1} deg, uncovered {}, {:.0} KB",
                report.tets,
                p.patches,
                p.mean_layers,
                p.angle_mean,
                p.angle_p95,
                p.forced,
                bytes as f64 / 1024.0
            );
            model = Some(m);
            Ok(figures)
        })?;
        if large {
            timed(args, LARGE, || {
                let (_, report) = case.fill_with(mesh, 50_000)?;
                Ok(format!("{} tets, {} patches", report.tets, report.paste.patches))
            })?;
        }
        let renders = NAMES[2..].iter().any(|n| wanted(args, &format!("fill/{}", n.replace("{}", name))));
        if !renders {
            continue;
        }
        let model = match model {
            Some(m) => m,
            None => case.fill(mesh)?.0,
        };
        render_workloads(args, name, &model, &case.textures)?;
    }
    Ok(())
}

fn render_workloads(args: &BenchArgs, name: &str, model: &LstModel, textures: &Textures) -> Result<()> {
    let (lo, hi) = render::bounds(&[(model, textures)]);
    let view = View::framing((lo, hi), (lo + hi) / 2.0, Vec3::new(0.3, 0.2, 1.0), 512)?;
    timed(args, &format!("fill/cut/{name}/512"), || {
        let cut = render::cut(model, textures, &view);
        Ok(format!("{:.0} % of pixels inside", cut.inside_share() * 100.0))
    })?;
    timed(args, &format!("fill/view/{name}/512"), || {
        crate::fill::view::surface(model, textures, 35.0, 25.0, 512);
        Ok(String::new())
    })?;
    timed(args, &format!("fill/bake/{name}/64"), || {
        let v = render::bake(&[(model, textures)], &[], 64, u64::MAX)?;
        let [x, y, z] = v.dims();
        Ok(format!("{x}x{y}x{z}"))
    })?;
    timed(args, &format!("fill/render/{name}/512"), || {
        let settings = translucent::Settings {
            yaw: 35.0,
            pitch: 25.0,
            size: 512,
            slices: 200,
            opacity: 0.3,
            cutaway: None,
            levels: (0.0, 1.0),
            background: render::BACKGROUND,
        };
        let rendering = translucent::render(&[(model, textures)], translucent::Density::Uniform, &settings, None)?;
        Ok(format!("{} slices", rendering.slices))
    })?;
    // `export`'s default: edges of about two pixels of a 512 view, vertex colours, the file
    // made in memory
    timed(args, &format!("fill/export/{name}/512"), || {
        let edge = 2.0 * crate::fill::view::pixel_size(&[model], (35.0, 25.0), 512);
        let options = crate::fill::export::Options { edge, crease: crate::fill::view::DEFAULT_CREASE, atlas: None };
        let mesh = crate::fill::export::export(model, textures, None, options, &NoProgress)?;
        let part = io::gltf::Part { name: name.to_string(), mesh: &mesh };
        let bytes = io::gltf::glb(&[part], serde_json::Value::Null)?;
        Ok(format!("{} triangles, {:.1} MB", mesh.triangles.len(), bytes.len() as f64 / 1e6))
    })
}

/// Whether `--only` lets the workload `name` run.
pub(super) fn wanted(args: &BenchArgs, name: &str) -> bool {
    args.only.as_ref().is_none_or(|o| name.contains(o.as_str()))
}

pub(super) fn timed(args: &BenchArgs, name: &str, work: impl FnMut() -> Result<String>) -> Result<()> {
    timed_then(args, name, work, |figures| Ok(figures.clone()))
}

/// Like [`timed`], but the figures are computed from the last run's result after the
/// timing (a measurement of the result is not part of the work timed).
pub(super) fn timed_then<T>(
    args: &BenchArgs,
    name: &str,
    mut work: impl FnMut() -> Result<T>,
    figures: impl FnOnce(&T) -> Result<String>,
) -> Result<()> {
    if !wanted(args, name) {
        return Ok(());
    }
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..args.runs.max(1) {
        let started = Instant::now();
        last = Some(work()?);
        times.push(started.elapsed().as_secs_f64());
    }
    let figures = figures(last.as_ref().expect("one run at least"))?;
    times.sort_by(f64::total_cmp);
    say!("{:<30} {:>5} {:>9.3} {:>9.3}  {figures}", name, times.len(), times[times.len() / 2], times[0]);
    Ok(())
}

/// One fill workload: a spec, its type and axes, masks and the textures to render with.
struct Case {
    spec: FillSpec,
    kind: TextureType,
    axes: [usize; 3],
    sources: Vec<Source>,
    masks: Vec<Volume>,
    textures: Textures,
}

impl Case {
    /// Meshes `mesh` (5,000 tets) and fills it.
    fn fill(&self, mesh: &Mesh) -> Result<(LstModel, fill::FillReport)> {
        self.fill_with(mesh, self.spec.tets)
    }

    /// Meshes `mesh` into about `tets` tets and fills it.
    fn fill_with(&self, mesh: &Mesh, tets: usize) -> Result<(LstModel, fill::FillReport)> {
        let spec = FillSpec { tets, ..self.spec.clone() };
        let (tets, _) = fill::tetrahedralize(mesh, &spec, fill::uses_depth(self.kind))?;
        let job = Job {
            surface: mesh,
            spec: &self.spec,
            kind: self.kind,
            axes: self.axes,
            sources: self.sources.clone(),
            masks: self.masks.clone(),
        };
        fill::fill(&job, tets, &NoProgress)
    }
}

fn source(mask: MaskRef) -> Source {
    Source { exemplar: "marble".into(), volume: "marble.exr".into(), mask }
}

/// A kiwi-like 2-b fill: depth 1 along the long axis, the secondary direction along it.
fn layered_case(mesh: &Mesh, colour: &Volume) -> Result<Case> {
    let (lo, hi) = mesh.bounds();
    let axis = vec![Vec3::new(lo.x * 0.75, 0.0, 0.0), Vec3::new(hi.x * 0.75, 0.0, 0.0)];
    let mut spec = FillSpec::new("marble");
    spec.depth.axes = vec![axis.clone()];
    spec.directions = vec![axis];
    let refs: Vec<MaskRef> = Layer::ALL
        .iter()
        .map(|&layer| MaskRef::Layered { layer, depth: Axis::Z, size: 64, falloff: mask::DEFAULT_FALLOFF, seed: 0 })
        .collect();
    let masks = refs.iter().map(|r| r.generate().expect("a recipe")).collect::<Result<Vec<_>>>()?;
    let textures = Textures::new(&[colour.clone(), colour.clone(), colour.clone()], &masks);
    Ok(Case {
        spec,
        kind: TextureType::T2b,
        axes: [2, 0, 1],
        sources: refs.into_iter().map(source).collect(),
        masks,
        textures,
    })
}

/// A type-0 fill with a splotch, the texture a quarter of the model's diagonal.
fn isotropic_case(colour: &Volume) -> Result<Case> {
    let spec = FillSpec::new("marble");
    let r = MaskRef::Splotch { size: 64, falloff: mask::DEFAULT_FALLOFF, seed: 0 };
    let masks = vec![r.generate().expect("a recipe")?];
    let textures = Textures::new(std::slice::from_ref(colour), &masks);
    Ok(Case { spec, kind: TextureType::T0, axes: [0, 1, 2], sources: vec![source(r)], masks, textures })
}
