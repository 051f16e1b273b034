//! The filling backend end to end: fill, cut, bake and view through the binary, on shapes
//! the project draws itself and the default exemplar library.

use crate::support::{assert_fails, assert_usage, at, listing, solidtex, solidtex_env, stderr};
use std::path::Path;

fn library() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars/library.toml").to_string_lossy().into_owned()
}

/// Writes a spec into `dir` (library = the default one, built into `dir/built`).
pub fn spec(dir: &Path, name: &str, body: &str) -> String {
    let text = format!("library = {:?}\nbuilt = \"built\"\n{body}", library());
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

pub fn draw(dir: &Path, what: &str) -> String {
    let path = at(dir, &format!("{what}.obj"));
    assert!(solidtex(&["draw", what, "-o", &path]).status.success());
    path
}

const KIWI: &str = r#"
exemplar = "kiwi"
seed = 3
tets = 3000
[depth]
axis = [[[-0.75, 0, 0], [0.75, 0, 0]]]
[[direction]]
points = [[-0.75, 0, 0], [0.75, 0, 0]]
"#;

/// The drawn fruit and the kiwi spec, written into `dir`: (mesh, spec).
pub fn kiwi_fruit(dir: &Path) -> (String, String) {
    (draw(dir, "fruit"), spec(dir, "kiwi.toml", KIWI))
}

pub fn fill(dir: &Path, mesh: &str, spec: &str, out: &str) -> serde_json::Value {
    let json = at(dir, &format!("{out}.json"));
    let run = solidtex(&["fill", mesh, "--spec", spec, "-o", &at(dir, out), "--json", &json]);
    assert!(run.status.success(), "{}", stderr(&run));
    serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap()
}

/// Draws `shape` into `dir` and fills it by a spec of `body` (named after `name`) into
/// `NAME.lst`; the model's path.
pub fn filled(dir: &Path, shape: &str, name: &str, body: &str) -> String {
    let (mesh, spec) = (draw(dir, shape), spec(dir, &format!("{name}.toml"), body));
    fill(dir, &mesh, &spec, &format!("{name}.lst"));
    at(dir, &format!("{name}.lst"))
}

fn pixel(png: &str, x: u32, y: u32) -> [f32; 3] {
    let img = image::open(png).unwrap().to_rgb8();
    img.get_pixel(x, y).0.map(|c| c as f32 / 255.0)
}

#[test]
fn a_kiwi_fill_covers_every_tet_and_puts_the_skin_on_the_surface() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, spec) = kiwi_fruit(d);
    let stats = fill(d, &mesh, &spec, "kiwi.lst");
    assert_eq!(stats["fill"]["paste"]["forced"], 0, "{stats}");
    assert!(stats["fill"]["tets"].as_u64().unwrap() > 2000);
    assert!(stats["fill"]["paste"]["angle_mean"].as_f64().unwrap() < 20.0, "{stats}");
    let seams = stats["seam_strength"].as_f64().unwrap();
    assert!((0.5..=1.3).contains(&seams), "seam strength {seams} (docs/fill.md: at most 1.3)");
    // a cut across the fruit's axis: a 0.65-radius disc; 512 px span 1.3 x 1.04
    let png = at(d, "cut.png");
    assert!(
        solidtex(&["cut", &at(d, "kiwi.lst"), "--plane", "0,0,0,1,0,0", "--size", "512", "-o", &png]).status.success()
    );
    let centre = pixel(&png, 256, 256);
    assert!(centre.iter().all(|c| *c > 0.75), "the core is pale: {centre:?}");
    let px_per_unit = 512.0 / (1.3 * 1.04);
    let rim = (256.0 + 0.64 * px_per_unit) as u32;
    let skin = pixel(&png, 256, rim);
    assert!(skin[0] > skin[1] && skin[1] > skin[2] && skin[0] < 0.6, "brown skin at the rim: {skin:?}");
    let flesh = pixel(&png, 256, (256.0 + 0.3 * px_per_unit) as u32);
    assert!(flesh[1] > flesh[0] && flesh[1] > flesh[2], "green flesh between: {flesh:?}");
}

/// Connected groups (4-neighbour) of at least `least` pixels darker than `share` of the
/// median brightness inside `radius` pixels of the picture's centre, with each group's
/// mean distance from the centre.
fn dark_spots(png: &str, radius: f32, share: f32, least: usize) -> Vec<f32> {
    let img = image::open(png).unwrap().to_rgb8();
    let (w, h) = img.dimensions();
    let from_centre =
        |x: u32, y: u32| ((x as f32 - w as f32 / 2.0).powi(2) + (y as f32 - h as f32 / 2.0).powi(2)).sqrt();
    let light = |x: u32, y: u32| img.get_pixel(x, y).0.iter().map(|c| *c as f32).sum::<f32>() / 3.0;
    let mut inside: Vec<f32> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| from_centre(x, y) < radius)
        .map(|(x, y)| light(x, y))
        .collect();
    inside.sort_by(f32::total_cmp);
    let limit = share * inside[inside.len() / 2];
    let dark = |x: u32, y: u32| from_centre(x, y) < radius && light(x, y) < limit;
    let mut seen = vec![false; (w * h) as usize];
    let mut spots = Vec::new();
    for start in 0..w * h {
        let (x, y) = (start % w, start / w);
        if seen[start as usize] || !dark(x, y) {
            continue;
        }
        seen[start as usize] = true;
        let (mut stack, mut distances) = (vec![(x, y)], Vec::new());
        while let Some((x, y)) = stack.pop() {
            distances.push(from_centre(x, y));
            let next = [(x.wrapping_sub(1), y), (x + 1, y), (x, y.wrapping_sub(1)), (x, y + 1)];
            for (nx, ny) in next {
                if nx < w && ny < h && !seen[(ny * w + nx) as usize] && dark(nx, ny) {
                    seen[(ny * w + nx) as usize] = true;
                    stack.push((nx, ny));
                }
            }
        }
        if distances.len() >= least {
            spots.push(distances.iter().sum::<f32>() / distances.len() as f32);
        }
    }
    spots
}

/// How round the pale region around the centre of a cut is: the radius of the largest
/// circle about its centroid holding only core pixels over the smallest holding them all.
/// Core pixels: red above `level`, connected to the pale pixel nearest the centre.
fn roundness(png: &str, level: u8) -> f32 {
    let img = image::open(png).unwrap().to_rgb8();
    let (w, h) = img.dimensions();
    let pale = |x: u32, y: u32| img.get_pixel(x, y).0[0] > level;
    let centre = |x: u32, y: u32| (x as f32 - w as f32 / 2.0).powi(2) + (y as f32 - h as f32 / 2.0).powi(2);
    let all = (0..h).flat_map(|y| (0..w).map(move |x| (x, y)));
    let start = all.clone().filter(|&(x, y)| pale(x, y)).min_by(|a, b| centre(a.0, a.1).total_cmp(&centre(b.0, b.1)));
    let (mut core, mut stack) = (vec![false; (w * h) as usize], vec![start.expect("a pale pixel")]);
    while let Some((x, y)) = stack.pop() {
        if x >= w || y >= h || core[(y * w + x) as usize] || !pale(x, y) {
            continue;
        }
        core[(y * w + x) as usize] = true;
        stack.extend([(x.wrapping_sub(1), y), (x + 1, y), (x, y.wrapping_sub(1)), (x, y + 1)]);
    }
    let inside: Vec<(u32, u32)> = all.clone().filter(|&(x, y)| core[(y * w + x) as usize]).collect();
    let n = inside.len() as f32;
    let (cx, cy) = inside.iter().fold((0.0, 0.0), |(a, b), &(x, y)| (a + x as f32 / n, b + y as f32 / n));
    let from = |&(x, y): &(u32, u32)| ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
    let outer = inside.iter().map(from).fold(0.0, f32::max);
    let inner = all.filter(|&(x, y)| !core[(y * w + x) as usize]).map(|p| from(&p)).fold(f32::INFINITY, f32::min);
    inner / outer
}

/// The repository's kiwi fill (exemplars/kiwi_fill.toml on the drawn fruit): a cut across
/// the axis shows at least 25 seeds (thesis Fig. 7.1), in a ring around the pale core. The
/// seeds' bounding spheres let 60 fit in the exemplar, which left 4 to 8 in a cut. The core
/// is round at the default tet count (refined near the axis): its inscribed over its
/// circumscribed radius is at least 0.8 at every paleness level, as the median over the
/// spec's fill seed and the next two (one seed's cut swings by about 0.05 where a pale ray
/// touches the core; without the refinement, a square-ish octagon, the median at the
/// lowest level is 0.76).
#[test]
fn a_cut_across_the_kiwi_shows_a_ring_of_seeds_around_a_round_core() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let repo_spec =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars/kiwi_fill.toml")).unwrap();
    let body: String = repo_spec
        .lines()
        .filter(|l| !l.starts_with("library") && !l.starts_with("built"))
        .map(|l| format!("{l}\n"))
        .collect();
    let (mesh, spec) = (draw(d, "fruit"), spec(d, "kiwi.toml", &body));
    fill(d, &mesh, &spec, "kiwi.lst");
    let png = at(d, "cut.png");
    assert!(
        solidtex(&["cut", &at(d, "kiwi.lst"), "--plane", "0,0,0,1,0,0", "--size", "512", "-o", &png]).status.success()
    );
    // the fruit's radius, 0.65, is 246 px; the seeds are searched inside 80 % of it
    let fruit = 0.65 * 512.0 / (1.3 * 1.04);
    let seeds = dark_spots(&png, 0.8 * fruit, 0.8, 4);
    assert!(seeds.len() >= 25, "{} seeds", seeds.len());
    let in_ring = seeds.iter().filter(|r| (0.3 * fruit..0.6 * fruit).contains(*r)).count();
    assert!(in_ring as f32 >= 0.9 * seeds.len() as f32, "{in_ring} of {} seeds in the ring", seeds.len());
    let mut cuts = vec![png];
    for seed in ["2", "3"] {
        let lst = at(d, &format!("kiwi{seed}.lst"));
        assert!(solidtex(&["fill", &mesh, "--spec", &spec, "--seed", seed, "-o", &lst]).status.success());
        let png = at(d, &format!("cut{seed}.png"));
        assert!(solidtex(&["cut", &lst, "--plane", "0,0,0,1,0,0", "--size", "512", "-o", &png]).status.success());
        cuts.push(png);
    }
    for level in [170, 190, 210] {
        let mut round: Vec<f32> = cuts.iter().map(|png| roundness(png, level)).collect();
        round.sort_by(f32::total_cmp);
        assert!(round[1] >= 0.8, "core roundness {round:.3?} at level {level}");
    }
}

/// Over the middle 60 % of a cut along the log (its axis running across the picture), the
/// spread in pixels of the row where the depth picture's upper half falls below `level`:
/// the heartwood's edge, straight along a round log.
fn edge_spread(png: &str, level: f32) -> f32 {
    let img = image::open(png).unwrap().to_rgb8();
    let (w, h) = img.dimensions();
    let value = |x: u32, y: u32| img.get_pixel(x, y).0[0] as f32;
    let rows: Vec<f32> = (w / 5..w * 4 / 5)
        .map(|x| {
            let mut y = h / 2;
            while y > 0 && value(x, y) > level {
                y -= 1;
            }
            let (above, below) = (value(x, y), value(x, y + 1));
            y as f32 + if below != above { (level - above) / (below - above) } else { 0.0 }
        })
        .collect();
    rows.iter().copied().fold(f32::MIN, f32::max) - rows.iter().copied().fold(f32::MAX, f32::min)
}

/// The trunk on the drawn log (2-b, an axis): the texture's depth is smooth inside each
/// tet, so a cut across the axis shows round depth contours (pith and rings) and a cut
/// along it a straight heartwood edge. With depth linear over each tet the pith was a
/// square (roundness 0.84 at level 230) and the edge zigzagged with the lattice's period
/// (2 px at 256²).
#[test]
fn the_logs_pith_is_round_and_its_heartwood_straight() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = filled(d, "log", "trunk", TRUNK);
    let (across, along) = (at(d, "across.png"), at(d, "along.png"));
    for (png, plane) in [(&across, "0,0,1,0,0,1"), (&along, "0,0,1,1,0,0")] {
        let run = solidtex(&["cut", &model, "--channel", "Depth", "--plane", plane, "--size", "256", "-o", png]);
        assert!(run.status.success(), "{}", stderr(&run));
    }
    for level in [128, 180, 230, 250] {
        let round = roundness(&across, level);
        assert!(round >= 0.95, "depth contour {level}: roundness {round:.3}");
    }
    for level in [180.0, 230.0] {
        let spread = edge_spread(&along, level);
        assert!(spread <= 1.0, "depth contour {level} along the log: {spread:.2} px");
    }
}

/// The repository's strata spec on the drawn block: patches end where their masks fade,
/// not at tet faces (a patch cut off where its mask is still high draws a straight seam
/// along the lattice; such fills measure 1.4-1.6).
#[test]
fn the_strata_block_shows_no_hard_seams() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let repository = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars/strata_fill.toml"));
    let body: String = repository
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("library") && !l.starts_with("built"))
        .map(|l| format!("{l}\n"))
        .collect();
    let (mesh, spec) = (draw(d, "block"), spec(d, "strata.toml", &body));
    let stats = fill(d, &mesh, &spec, "strata.lst");
    let seams = stats["seam_strength"].as_f64().unwrap();
    assert!((0.5..=1.3).contains(&seams), "seam strength {seams} (docs/fill.md: at most 1.3)");
}

#[test]
fn fills_replay_for_a_seed_and_ignore_the_mesh_orientation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, spec) = kiwi_fruit(d);
    fill(d, &mesh, &spec, "a.lst");
    fill(d, &mesh, &spec, "b.lst");
    let same = std::fs::read(d.join("a.lst")).unwrap() == std::fs::read(d.join("b.lst")).unwrap();
    assert!(same, "two fills with the same seed differ");
    // one thread and four: the same model and the same cut
    for (threads, name) in [("1", "t1"), ("4", "t4")] {
        let env = [("RAYON_NUM_THREADS", threads)];
        let lst = at(d, &format!("{name}.lst"));
        assert!(solidtex_env(&["fill", &mesh, "--spec", &spec, "-o", &lst], &env).status.success());
        let png = at(d, &format!("{name}.png"));
        assert!(solidtex_env(&["cut", &lst, "--size", "96", "-o", &png], &env).status.success());
    }
    for ext in ["lst", "png"] {
        let read = |n: &str| std::fs::read(d.join(format!("{n}.{ext}"))).unwrap();
        assert!(read("t1") == read("t4"), "the {ext} depends on the thread count");
    }
    assert!(std::fs::read(d.join("t1.lst")).unwrap() == std::fs::read(d.join("a.lst")).unwrap());
    // the same fruit with every triangle flipped (facing inwards)
    let text = std::fs::read_to_string(&mesh).unwrap();
    let flipped: String = text
        .lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(rest) => format!("f {}\n", rest.split_whitespace().rev().collect::<Vec<_>>().join(" ")),
            None => format!("{l}\n"),
        })
        .collect();
    let inward = at(d, "inward.obj");
    std::fs::write(&inward, flipped).unwrap();
    fill(d, &inward, &spec, "c.lst");
    let same = std::fs::read(d.join("a.lst")).unwrap() == std::fs::read(d.join("c.lst")).unwrap();
    assert!(same, "the inward-facing copy fills differently");
}

#[test]
fn a_pipe_of_genus_one_fills_and_its_hole_stays_empty() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "pipe");
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\nscale = 0.6\ntets = 3000\nseed = 1\n");
    let stats = fill(d, &mesh, &spec, "pipe.lst");
    assert_eq!(stats["fill"]["paste"]["forced"], 0, "{stats}");
    assert_eq!(stats["type"], "0");
    let png = at(d, "cut.png");
    assert!(solidtex(&["cut", &at(d, "pipe.lst"), "--size", "128", "-o", &png]).status.success());
    assert_eq!(pixel(&png, 64, 64), [24, 24, 28].map(|c| c as f32 / 255.0), "the hole is background");
    let tube = pixel(&png, 64, 64 - (0.75 * 128.0 / (2.1 * 1.04)) as u32);
    assert!(tube.iter().all(|c| *c > 0.4), "marble in the tube: {tube:?}");
    // bake: RGBA, alpha 0 in the hole and 1 in the tube
    let exr = at(d, "pipe.exr");
    let run = solidtex(&["bake", &at(d, "pipe.lst"), "--res", "32", "-o", &exr]);
    assert!(run.status.success(), "{}", stderr(&run));
    let v = solidtex::io::read_volume(Path::new(&exr), u64::MAX).unwrap();
    let [x, y, z] = v.dims();
    assert_eq!((x, y), (32, 32));
    assert!((8..=12).contains(&z), "{z}");
    assert_eq!(v.get(16, 16, z / 2, 3), 0.0);
    assert_eq!(v.get(16, 16 - 11, z / 2, 3), 1.0);
}

/// A bake records where it sits over its model: voxel (0, 0, 0)'s centre and the voxel
/// side, in the EXR's description (as `info` shows it, text and JSON), in NRRD's own space
/// fields (origin: the first voxel's centre; one direction vector per axis); every voxel
/// inside the model is centred inside the mesh's box, and the voxels' cells start at its
/// corner. A format with no room for it says so.
#[test]
fn a_bake_records_where_it_sits_over_its_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = filled(d, "block", "marble", "exemplar = \"marble\"\nscale = 1.0\ntets = 2000\nseed = 1\n");
    let (lo, hi) = solidtex::io::mesh_file::read_mesh(&d.join("block.obj")).unwrap().bounds();
    let (lo, hi) = (lo.to_array(), hi.to_array());
    let exr = at(d, "baked.exr");
    let run = solidtex(&["bake", &model, "--res", "16", "-o", &exr]);
    assert!(run.status.success(), "{}", stderr(&run));
    let placed = |file: &str| {
        let run = solidtex(&["info", file, "--json"]);
        let json: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        json["model_grid"].clone()
    };
    let grid = placed(&exr);
    let number = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("no number in {grid}")) as f32;
    let (voxel, origin, from, to) = (
        number(&grid["voxel"]),
        [0, 1, 2].map(|a| number(&grid["origin"][a])),
        [0, 1, 2].map(|a| number(&grid["box_min"][a])),
        [0, 1, 2].map(|a| number(&grid["box_max"][a])),
    );
    let longest = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f32::max);
    assert!((voxel - longest / 16.0).abs() < 1e-6, "voxel {voxel} for a longest side {longest}");
    for a in 0..3 {
        assert!((origin[a] - (lo[a] + voxel / 2.0)).abs() < 1e-5, "origin {origin:?}, box from {lo:?}");
        assert!((from[a] - lo[a]).abs() < 1e-5 && to[a] >= hi[a] - 1e-5 && to[a] < hi[a] + voxel, "{grid}");
    }
    let v = solidtex::io::read_volume(Path::new(&exr), u64::MAX).unwrap();
    let [x, y, z] = v.dims();
    for k in 0..z {
        for j in 0..y {
            for i in 0..x {
                let centre: [f32; 3] = std::array::from_fn(|a| origin[a] + [i, j, k][a] as f32 * voxel);
                let within = (0..3).all(|a| centre[a] > lo[a] && centre[a] < hi[a]);
                assert!(v.get(i, j, k, 3) == 0.0 || within, "voxel ({i}, {j}, {k}) is inside at {centre:?}");
            }
        }
    }
    let info = solidtex(&["info", &exr]);
    let text = String::from_utf8_lossy(&info.stdout);
    let [ox, oy, oz] = origin;
    assert!(text.contains(&format!("origin    {ox} {oy} {oz} (model-space centre of voxel 0 0 0)")), "{text}");
    assert!(text.contains(&format!("voxel     {voxel} (side, model units)")), "{text}");

    let nrrd = at(d, "baked.nrrd");
    let run = solidtex(&["bake", &model, "--res", "16", "-o", &nrrd]);
    assert!(run.status.success(), "{}", stderr(&run));
    let bytes = std::fs::read(&nrrd).unwrap();
    let end = bytes.windows(2).position(|w| w == b"\n\n").unwrap();
    let header = String::from_utf8_lossy(&bytes[..end]).into_owned();
    for line in [
        "space dimension: 3".to_string(),
        format!("space directions: none ({voxel},0,0) (0,{voxel},0) (0,0,{voxel})"),
        format!("space origin: ({ox},{oy},{oz})"),
    ] {
        assert!(header.lines().any(|l| l == line), "{line:?} not in {header}");
    }
    assert_eq!(placed(&nrrd), grid, "the NRRD reads back in the same place");

    let dds = at(d, "baked.dds");
    let run = solidtex(&["bake", &model, "--res", "16", "-o", &dds]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("keeps no place in model space"), "{}", stderr(&run));
}

#[test]
fn two_models_cut_together_and_the_surface_view_draws_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let block = draw(d, "block");
    let spec = spec(d, "strata.toml", "exemplar = \"strata\"\ntype = \"0\"\nscale = 1.0\ntets = 2000\n");
    fill(d, &block, &spec, "block.lst");
    let (fruit, kiwi) = kiwi_fruit(d);
    fill(d, &fruit, &kiwi, "kiwi.lst");
    let png = at(d, "both.png");
    let run = solidtex(&[
        "cut",
        &at(d, "kiwi.lst"),
        &at(d, "block.lst"),
        "--plane",
        "0,0,0,0,0,1",
        "--size",
        "64",
        "-o",
        &png,
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    // (0, 0): inside both, the kiwi (listed first) shows its pale core; (0.95, 0.45): only
    // the block holds it, so strata show there. 64 px span 2 x 1.04 model units.
    let px = |x: f32, y: f32| pixel(&png, (32.0 + x * 32.0 / 1.04) as u32, (32.0 - y * 32.0 / 1.04) as u32);
    assert!(px(0.0, 0.0).iter().all(|c| *c > 0.7), "kiwi core {:?}", px(0.0, 0.0));
    let strata = px(0.95, 0.45);
    assert!(strata[0] > strata[2] && strata[0] > 0.3 && strata[1] < strata[0], "strata {strata:?}");
    let view = at(d, "view.png");
    assert!(solidtex(&["view", &at(d, "kiwi.lst"), "--size", "96", "-o", &view]).status.success());
    let img = image::open(&view).unwrap().to_rgb8();
    assert_ne!(img.get_pixel(48, 48).0, [24, 24, 28], "the fruit is in the middle");
    assert_eq!(img.get_pixel(1, 1).0, [24, 24, 28], "the corner is background");
    let flat = at(d, "flat.png");
    assert!(solidtex(&["view", &at(d, "kiwi.lst"), "--size", "96", "--flat", "-o", &flat]).status.success());
    assert_ne!(std::fs::read(&flat).unwrap(), std::fs::read(&view).unwrap(), "--flat changes the shading");
    let bad = solidtex(&["view", &at(d, "kiwi.lst"), "--crease", "200", "-o", &at(d, "bad.png")]);
    assert_usage(&bad, &["--crease"]);
    assert!(!d.join("bad.png").exists());
}

/// The pixels of a PNG whose every channel is at most `level` (0 to 255).
fn darker_than(png: &str, level: u8) -> usize {
    image::open(png).unwrap().to_rgb8().pixels().filter(|p| p.0.iter().all(|c| *c <= level)).count()
}

#[test]
fn a_translucent_render_shows_the_seeds_inside_the_kiwi() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = filled(d, "fruit", "kiwi", KIWI);
    let render = |name: &str, extra: &[&str]| {
        let png = at(d, name);
        let mut args = vec!["render", &model, "--size", "128", "-o", &png];
        args.extend_from_slice(extra);
        let run = solidtex(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        (png, stderr(&run))
    };
    // the exemplars have no density channel: uniform, and the message says why
    let (plain, said) = render("plain.png", &[]);
    assert!(said.contains("density uniform") && said.contains("Density or A"), "{said}");
    assert!(!said.contains("background alone"), "{said}");
    let img = image::open(&plain).unwrap().to_rgb8();
    let centre = img.get_pixel(64, 64).0;
    assert!(centre[1] > centre[0] && centre[1] > centre[2], "green flesh seen through: {centre:?}");
    assert_eq!(img.get_pixel(1, 1).0, [24, 24, 28], "the corner is background");
    // on a light background, only the darkest material dense: the seeds show as dark specks
    let light = ["--density", "dark", "--opacity", "0.99", "--background", "240,240,235"];
    let (seeds, _) = render("seeds.png", &[&light[..], &["--levels", "0.7,0.85"]].concat());
    let specks = darker_than(&seeds, 200);
    assert!(specks > 100, "seeds seen through the fruit: {specks} dark pixels");
    let (none, said) = render("none.png", &[&light[..], &["--levels", "0.97,1"]].concat());
    assert_eq!(darker_than(&none, 200), 0, "nothing is that dense");
    assert!(said.contains("background alone: --levels leave none"), "{said}");
    let (clear, said) = render("clear.png", &["--opacity", "0"]);
    assert!(said.contains("background alone: --opacity 0"), "{said}");
    assert_eq!(pixel(&clear, 64, 64), pixel(&clear, 1, 1), "a clear fruit shows the background");

    // cut away the half toward the camera (looking down -z): the pale core shows on the face
    let (cut, _) = render("cut.png", &["--yaw", "0", "--pitch", "0", "--opacity", "0.95", "--cutaway", "0,0,0,0,0,1"]);
    let core = pixel(&cut, 64, 64);
    assert!(core.iter().all(|c| *c > 0.6), "the core on the cut face: {core:?}");
    assert!(pixel(&plain, 64, 64)[2] < 0.5, "without the cutaway the core is hidden");
    // bad values are refused, naming them, with nothing written
    let bad = at(d, "bad.png");
    let refused = |extra: &[&str], needles: &[&str], code: i32| {
        let mut args = vec!["render", &model, "-o", &bad];
        args.extend_from_slice(extra);
        let run = solidtex(&args);
        if code == 2 {
            assert_usage(&run, needles)
        } else {
            assert_fails(&run, needles)
        }
        assert!(!Path::new(&bad).exists());
    };
    refused(&["--opacity", "1"], &["--opacity"], 2);
    refused(&["--levels", "0.8,0.2"], &["--levels"], 2);
    refused(&["--cutaway", "0,0,0,0,0,0"], &["--cutaway", "zero"], 2);
    refused(&["--background", "0,0,300"], &["--background"], 2);
    refused(&["--density", "alpha"], &["kiwi.exr", "Density or A"], 1);
}

const STRATA: &str = r#"
exemplar = "strata"
seed = 1
tets = 2000
[depth]
surface = false
[[depth.faces]]
at = [0, 0.5, 0]
value = 0
[[depth.faces]]
at = [0, -0.5, 0]
value = 1
"#;

#[test]
fn the_exemplars_other_channels_survive_the_fill_into_cuts_and_bakes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = filled(d, "block", "strata", STRATA);
    // the block's top (y = 0.5) is depth 0, its bottom depth 1: the Depth channel says so
    let png = at(d, "depth.png");
    let run = solidtex(&["cut", &model, "--channel", "Depth", "--plane", "0,0,0,1,0,0", "--size", "64", "-o", &png]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("channel Depth: 0.0"), "{}", stderr(&run));
    // the block's 1 x 1 end seen along x: 64 px span 1.04 units, its rows 1 to 62
    let column: Vec<f32> = (3..61).map(|y| pixel(&png, 32, y)[0]).collect();
    assert!(column[0] < 0.1 && column[57] > 0.9, "depth from top to bottom: {column:?}");
    assert!(column.windows(2).all(|w| w[1] >= w[0] - 0.02), "depth grows downward: {column:?}");
    // the bake carries it between the colour and the inside mask
    let exr = at(d, "baked.exr");
    let run = solidtex(&["bake", &model, "--res", "16", "-o", &exr]);
    assert!(run.status.success(), "{}", stderr(&run));
    let v = solidtex::io::read_volume(Path::new(&exr), u64::MAX).unwrap();
    let names: Vec<&str> = v.channels().iter().map(|c| c.name()).collect();
    assert_eq!(names, ["R", "G", "B", "Depth", "A"]);
    let [x, y, z] = v.dims();
    // voxel y grows with model y: the low rows are the block's bottom (depth 1)
    let (bottom, top) = (v.get(x / 2, 1, z / 2, 3), v.get(x / 2, y - 2, z / 2, 3));
    assert!(top < 0.2 && bottom > 0.8, "depth at the bottom {bottom}, at the top {top}");
    // `--carry none` bakes the colour and the inside alone, the same values; a channel the
    // exemplars lack is refused by name, with what may be carried, and nothing written
    let plain = at(d, "plain.exr");
    let run = solidtex(&["bake", &model, "--res", "16", "--carry", "none", "-o", &plain]);
    assert!(run.status.success(), "{}", stderr(&run));
    let p = solidtex::io::read_volume(Path::new(&plain), u64::MAX).unwrap();
    assert_eq!(p.channels().iter().map(|c| c.name()).collect::<Vec<_>>(), ["R", "G", "B", "A"]);
    let (mid, k) = ([x / 2, y / 2, z / 2], [0, 1, 2, 4]);
    assert_eq!(k.map(|c| v.get(mid[0], mid[1], mid[2], c)), [0, 1, 2, 3].map(|c| p.get(mid[0], mid[1], mid[2], c)));
    let unused = at(d, "unused.exr");
    let run = solidtex(&["bake", &model, "--carry", "Displacement", "-o", &unused]);
    assert_usage(&run, &["--carry Displacement", "allowed: Depth or none"]);
    assert!(!Path::new(&unused).exists());
    // a channel no exemplar has is refused, naming the exemplar file and what it has
    let bad = at(d, "bad.png");
    assert_fails(
        &solidtex(&["cut", &model, "--channel", "Displacement", "-o", &bad]),
        &["strata.exr", "R, G, B, Depth"],
    );
    assert_usage(&solidtex(&["cut", &model, "--channel", "a b", "-o", &bad]), &["channel name"]);
    assert!(!Path::new(&bad).exists());
}

pub const TRUNK: &str = r#"
exemplar = "trunk"
seed = 1
tets = 6000
[depth]
surface = false
axis = [[[0, 0, 0.1], [0, 0, 1.9]]]
[[depth.faces]]
at = [0.5, 0, 1]
crease = 30
value = 0
[[direction]]
points = [[0, 0, 0.1], [0, 0, 1.9]]
"#;

/// The 95th percentile of the brightness steps between horizontal neighbours off the
/// background, in the picture's right third (the log's side, away from its end).
fn rough(png: &str) -> u8 {
    let img = image::open(png).unwrap().to_rgb8();
    let mut steps = Vec::new();
    for y in 0..img.height() {
        for x in img.width() * 2 / 3..img.width() - 1 {
            let (a, b) = (img.get_pixel(x, y).0, img.get_pixel(x + 1, y).0);
            if a != [24, 24, 28] && b != [24, 24, 28] {
                steps.push(a[0].abs_diff(b[0]));
            }
        }
    }
    steps.sort_unstable();
    steps[steps.len() * 95 / 100]
}

#[test]
fn displacement_mapping_raises_the_bark_into_furrows() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = filled(d, "log", "trunk", TRUNK);
    let (plain, raised) = (at(d, "plain.png"), at(d, "raised.png"));
    assert!(solidtex(&["view", &model, "--size", "160", "-o", &plain]).status.success());
    let run = solidtex(&["view", &model, "--size", "160", "--displacement", "0.1", "-o", &raised]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("0.1 x (Displacement - 0.5)"), "{}", stderr(&run));
    let (smooth, furrowed) = (rough(&plain), rough(&raised));
    assert!(smooth <= 6 && furrowed >= 12, "brightness steps: plain {smooth}, displaced {furrowed}");
    // the kiwi's exemplar has no relief: refused, naming its file and the channel
    let (fruit, kiwi) = kiwi_fruit(d);
    fill(d, &fruit, &kiwi, "kiwi.lst");
    let bad = at(d, "bad.png");
    let run = solidtex(&["view", &at(d, "kiwi.lst"), "--displacement", "0.1", "-o", &bad]);
    assert_fails(&run, &["kiwi.exr", "Displacement"]);
    assert_usage(
        &solidtex(&["view", &model, "--displacement", "50", "-o", &bad]),
        &["--displacement 50 is larger than the models' size", "allowed"],
    );
    // a stroke cut across the log: its face shows the relief at the rim, only when displaced
    let across = ["cut", &model, "--stroke", "0,-1,1.5;0,1,1.5", "--extrude", "1,0,0", "--keep", "0,0,0.5"];
    let view = ["--yaw", "40", "--pitch", "30", "--size", "160"];
    let (flat_cut, relief_cut) = (at(d, "flat_cut.png"), at(d, "relief_cut.png"));
    assert!(solidtex(&[&across[..], &view, &["-o", &flat_cut]].concat()).status.success());
    let run = solidtex(&[&across[..], &view, &["--displacement", "0.1", "-o", &relief_cut]].concat());
    assert!(run.status.success() && stderr(&run).contains("displaced by 0.1"), "{}", stderr(&run));
    let changed = |a: &str, b: &str| {
        let (a, b) = (image::open(a).unwrap().to_rgb8(), image::open(b).unwrap().to_rgb8());
        a.pixels().zip(b.pixels()).filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 24)).count()
    };
    assert!(changed(&flat_cut, &relief_cut) > 200, "{} pixels changed", changed(&flat_cut, &relief_cut));
    let kiwi_cut = ["cut", &at(d, "kiwi.lst"), "--stroke", "0,-1,0;0,1,0", "--extrude", "0,0,1"];
    assert_fails(
        &solidtex(&[&kiwi_cut[..], &["--displacement", "0.1", "-o", &bad]].concat()),
        &["kiwi.exr", "Displacement"],
    );
    assert_usage(&solidtex(&[&across[..], &["--displacement", "5000", "-o", &bad]].concat()), &["--displacement"]);
    assert!(!Path::new(&bad).exists());
}

#[test]
fn stroke_cuts_show_the_inside_of_what_they_keep() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let model = filled(d, "fruit", "kiwi", KIWI);
    // cut the fruit across its axis (x) at 0, keep x < 0; seen from +x the face shows
    let png = at(d, "half.png");
    let args = ["cut", &model, "--stroke", "0,-1,0;0,1,0", "--extrude", "0,0,1", "--keep", "-0.5,0,0"];
    let run = solidtex(&[&args[..], &["--yaw", "90", "--pitch", "0", "--size", "128", "-o", &png]].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("cut faces on"), "{}", stderr(&run));
    let core = pixel(&png, 64, 64);
    assert!(core.iter().all(|c| *c > 0.6), "the pale core in the middle of the face: {core:?}");
    let flesh = pixel(&png, 64, 64 + 25);
    assert!(flesh[1] > flesh[0] && flesh[1] > flesh[2], "green flesh around it: {flesh:?}");
    // keeping the other half, the camera sees the skin
    let skin_png = at(d, "skin.png");
    let other = ["cut", &model, "--stroke", "0,-1,0;0,1,0", "--extrude", "0,0,1", "--keep", "0.5,0,0"];
    assert!(
        solidtex(&[&other[..], &["--yaw", "90", "--pitch", "0", "--size", "128", "-o", &skin_png]].concat())
            .status
            .success()
    );
    let skin = pixel(&skin_png, 64, 64);
    assert!(skin[0] > skin[1] && skin[0] < 0.6, "brown skin: {skin:?}");
    // bad strokes are refused, naming the option, nothing written
    let bad = at(d, "bad.png");
    assert_usage(&solidtex(&["cut", &model, "--stroke", "0,0,0", "-o", &bad]), &["--stroke", "two or more"]);
    assert_usage(
        &solidtex(&["cut", &model, "--stroke", "0,0,0;1,0,0", "--extrude", "0,0,0", "-o", &bad]),
        &["--extrude"],
    );
    let along = solidtex(&["cut", &model, "--stroke", "0,0,0;0,0,1", "--extrude", "0,0,1", "-o", &bad]);
    assert_fails(&along, &["kiwi.lst", "two points apart"]);
    assert_usage(
        &solidtex(&["cut", &model, "--stroke", "0,0,0;1,0,0", "--plane", "0,0,0,0,0,1", "-o", &bad]),
        &["--plane"],
    );
    assert!(!Path::new(&bad).exists());
}

#[test]
fn a_cake_of_four_fills_shows_every_layer_without_gaps() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cake = at(d, "cake");
    let run = solidtex(&["draw", "cake", "-o", &cake, "--library", &library(), "--built", &at(d, "built")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let layers = ["sponge-low", "cream", "sponge-high", "glaze"];
    let mut models = Vec::new();
    for layer in layers {
        let (mesh, spec) = (format!("{cake}/{layer}.obj"), format!("{cake}/{layer}.toml"));
        let out = format!("{cake}/{layer}.lst");
        let run = solidtex(&["fill", &mesh, "--spec", &spec, "-o", &out]);
        assert!(run.status.success(), "{layer}: {}", stderr(&run));
        assert!(!stderr(&run).contains("holds"), "{layer} keeps its volume: {}", stderr(&run));
        models.push(out);
    }
    // a vertical cut through the axis: 128 px span 2 x 1.04 units; y from 0 to 1.08
    let png = at(d, "cut.png");
    let mut args: Vec<&str> = vec!["cut"];
    args.extend(models.iter().map(String::as_str));
    args.extend(["--plane", "0,0.5,0,0,0,1", "--size", "128", "-o", &png]);
    let run = solidtex(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    let img = image::open(&png).unwrap().to_rgb8();
    let (step, top) = (2.08 / 128.0, 64.0 - 0.54 / (2.08 / 128.0));
    let at_height = |y: f32| img.get_pixel(64, (top + (1.08 - y) / step) as u32).0.map(|c| c as f32 / 255.0);
    let column: Vec<[f32; 3]> = (1..54).map(|k| at_height(k as f32 * 0.02)).collect();
    assert!(column.iter().all(|c| *c != [24.0 / 255.0, 24.0 / 255.0, 28.0 / 255.0]), "a gap in the column");
    let (sponge, cream, glaze) = (at_height(0.2), at_height(0.49), at_height(1.03));
    assert!(sponge[0] > 0.5 && sponge[2] < 0.6 * sponge[0], "sponge is yellow: {sponge:?}");
    assert!(cream.iter().all(|c| *c > 0.85), "cream is near white: {cream:?}");
    assert!(glaze[0] < 0.55 && glaze[0] > glaze[2], "the glaze is dark brown: {glaze:?}");
    assert!(at_height(0.8)[2] < 0.6 * at_height(0.8)[0], "sponge again above the cream");
    // the surface view and the volume rendering take all four too
    let view = at(d, "view.png");
    let mut args: Vec<&str> = vec!["view"];
    args.extend(models.iter().map(String::as_str));
    args.extend(["--size", "96", "-o", &view]);
    assert!(solidtex(&args).status.success());
    // drawing again is refused while the folder holds files it did not write (the fills);
    // a fresh folder is drawn again in place, until the user adds a file
    assert!(!solidtex(&["draw", "cake", "-o", &cake, "--library", &library()]).status.success());
    let fresh = at(d, "fresh");
    assert!(solidtex(&["draw", "cake", "-o", &fresh, "--library", &library()]).status.success());
    assert!(solidtex(&["draw", "cake", "-o", &fresh, "--library", &library()]).status.success());
    std::fs::write(d.join("fresh/notes.txt"), "mine").unwrap();
    assert!(!solidtex(&["draw", "cake", "-o", &fresh, "--library", &library()]).status.success());
    assert_eq!(std::fs::read_to_string(d.join("fresh/notes.txt")).unwrap(), "mine");
}

#[test]
fn a_manual_paste_shows_on_top_of_the_automatic_fill() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let block = draw(d, "block");
    let plain = "exemplar = \"marble\"\nscale = 1.0\ntets = 2000\n";
    let pasted = format!("{plain}[[paste]]\nexemplar = \"carrot\"\nat = [0.4, 0, 0]\nscale = 0.8\n");
    let (a, b) = (spec(d, "plain.toml", plain), spec(d, "pasted.toml", &pasted));
    fill(d, &block, &a, "plain.lst");
    let stats = fill(d, &block, &b, "pasted.lst");
    assert_eq!(stats["fill"]["paste"]["forced"], 0);
    let cut = |model: &str| {
        let png = at(d, &format!("{model}.png"));
        assert!(
            solidtex(&["cut", &at(d, model), "--plane", "0,0,0,0,0,1", "--size", "64", "-o", &png]).status.success()
        );
        pixel(&png, (32.0 + 0.4 * 32.0 / 1.04) as u32, 32)
    };
    let (marble, carrot) = (cut("plain.lst"), cut("pasted.lst"));
    assert!((marble[0] - marble[2]).abs() < 0.15, "marble is grey-white: {marble:?}");
    assert!(
        carrot[0] > carrot[1] && carrot[1] > carrot[2] && carrot[0] - carrot[2] > 0.3,
        "carrot is orange: {carrot:?}"
    );
}

#[test]
fn bad_fills_are_refused_with_the_reason_and_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fruit = draw(d, "fruit");
    let out = at(d, "out.lst");
    let cases: Vec<(String, String, Vec<&str>)> = vec![
        (
            fruit.clone(),
            spec(d, "unknown.toml", "exemplar = \"plum\"\n"),
            vec!["unknown.toml", "plum", "not in the library", "kiwi"],
        ),
        (fruit.clone(), spec(d, "nostroke.toml", "exemplar = \"wood\"\ntype = \"1-a\"\n"), vec!["1-a", "direction"]),
        (
            fruit.clone(),
            spec(
                d,
                "nodepth.toml",
                "exemplar = \"kiwi\"\n[depth]\nsurface = true\n[[direction]]\npoints = [[0,0,0],[0.5,0,0]]\n",
            ),
            vec!["2-b", "depth"],
        ),
        (
            fruit.clone(),
            spec(d, "outside.toml", &KIWI.replace("0.75, 0, 0]]]", "3, 0, 0]]]")),
            vec!["depth.axis[0]", "outside the model"],
        ),
        (fruit.clone(), spec(d, "tiny.toml", "exemplar = \"marble\"\nscale = 0.001\n"), vec!["scale", "tet edges"]),
        (
            fruit.clone(),
            spec(
                d,
                "far.toml",
                "exemplar = \"marble\"\n[[paste]]\nexemplar = \"marble\"\nat = [50, 0, 0]\nscale = 0.4\n",
            ),
            vec!["paste[0].at", "outside the model"],
        ),
        (
            fruit.clone(),
            spec(
                d,
                "speck.toml",
                "exemplar = \"marble\"\n[[paste]]\nexemplar = \"marble\"\nat = [0, 0, 0]\nscale = 1e-9\n",
            ),
            vec!["paste[0].scale", "tet edges"],
        ),
    ];
    for (mesh, spec, needles) in cases {
        assert_fails(&solidtex(&["fill", &mesh, "--spec", &spec, "-o", &out]), &needles);
    }
    // an open mesh: the fruit without its last face
    let text = std::fs::read_to_string(&fruit).unwrap();
    let last = text.rfind("\nf ").unwrap();
    let open = at(d, "open.obj");
    std::fs::write(&open, &text[..last + 1]).unwrap();
    let marble = spec(d, "marble.toml", "exemplar = \"marble\"\n");
    assert_fails(
        &solidtex(&["fill", &open, "--spec", &marble, "-o", &out]),
        &["open.obj", "not closed", "3 boundary edge"],
    );
    // a flat mesh: two triangles back to back
    let flat = at(d, "flat.obj");
    std::fs::write(&flat, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n").unwrap();
    assert_fails(&solidtex(&["fill", &flat, "--spec", &marble, "-o", &out]), &["flat.obj", "volume"]);
    assert!(!listing(d).iter().any(|n| n.ends_with(".lst")), "{:?}", listing(d));
}

#[test]
fn a_damaged_model_file_is_named_and_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, spec) = (draw(d, "block"), spec(d, "m.toml", "exemplar = \"marble\"\nscale = 1.0\ntets = 2000\n"));
    fill(d, &mesh, &spec, "m.lst");
    let bytes = std::fs::read(d.join("m.lst")).unwrap();
    std::fs::write(d.join("cut.lst"), &bytes[..bytes.len() / 2]).unwrap();
    let png = at(d, "x.png");
    assert_fails(&solidtex(&["cut", &at(d, "cut.lst"), "-o", &png]), &["cut.lst", "truncated"]);
    std::fs::write(d.join("junk.lst"), b"hello").unwrap();
    assert_fails(&solidtex(&["cut", &at(d, "junk.lst"), "-o", &png]), &["junk.lst", "SOLIDLST"]);
    assert!(!d.join("x.png").exists());
}

/// A model reads its files from beside itself: linked from another folder it still finds
/// them; copied away from them, the error names the model, the file it misses and where
/// it looked.
#[test]
fn a_model_reads_its_files_from_its_own_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, spec) = (draw(d, "block"), spec(d, "m.toml", "exemplar = \"marble\"\nscale = 1.0\ntets = 2000\n"));
    fill(d, &mesh, &spec, "m.lst");
    let elsewhere = d.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::os::unix::fs::symlink(d.join("m.lst"), elsewhere.join("linked.lst")).unwrap();
    let (direct, linked) = (at(d, "direct.png"), at(d, "linked.png"));
    assert!(solidtex(&["cut", &at(d, "m.lst"), "-o", &direct]).status.success());
    let run = solidtex(&["cut", &elsewhere.join("linked.lst").to_string_lossy(), "-o", &linked]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(std::fs::read(&direct).unwrap(), std::fs::read(&linked).unwrap());
    std::fs::copy(d.join("m.lst"), elsewhere.join("copied.lst")).unwrap();
    let run = solidtex(&["cut", &elsewhere.join("copied.lst").to_string_lossy(), "-o", &at(d, "copied.png")]);
    assert_fails(&run, &["copied.lst", "no such file in", "relative to the model's folder"]);
    assert!(!d.join("copied.png").exists());
}

/// A hollow tube of `segments` sides, axis along y (outer radius 0.3, inner 0.1, length 1),
/// with one ring of long triangles per wall: a coarse triangulation.
fn coarse_tube(path: &Path, segments: usize) {
    let mut text = String::new();
    for (r, y) in [(0.3f32, -0.5f32), (0.3, 0.5), (0.1, -0.5), (0.1, 0.5)] {
        for k in 0..segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            text += &format!("v {} {y} {}\n", r * a.cos(), r * a.sin());
        }
    }
    let at = |ring: usize, k: usize| ring * segments + k % segments + 1;
    for k in 0..segments {
        // outer wall, inner wall, bottom cap, top cap: two triangles each
        for (a, b) in [(0, 1), (3, 2), (2, 0), (1, 3)] {
            let (p, q, r, s) = (at(a, k), at(a, k + 1), at(b, k + 1), at(b, k));
            text += &format!("f {p} {q} {r}\nf {p} {r} {s}\n");
        }
    }
    std::fs::write(path, text).unwrap();
}

/// The exemplar's mean colour over depth slices `zs` (depth along z).
fn mean_colour(ex: &solidtex::Volume, zs: std::ops::Range<usize>) -> [f64; 3] {
    let [ex_x, ex_y, _] = ex.dims();
    let n = (zs.len() * ex_x * ex_y) as f64;
    let mut sum = [0.0f64; 3];
    for z in zs {
        for y in 0..ex_y {
            for x in 0..ex_x {
                (0..3).for_each(|c| sum[c] += ex.get(x, y, z, c) as f64 / n);
            }
        }
    }
    sum
}

/// The share of a filled model's surface that shows the skin: the colour at three points
/// of every triangle of its input surface is nearer the exemplar's depth-0 colour than its
/// mid-depth colour. `keep` selects the triangles measured (by their centre).
fn skin_share(model: &Path, exemplar: &str, keep: impl Fn(glam::Vec3) -> bool) -> f64 {
    use solidtex::fill::render;
    let lst = solidtex::io::lst_file::read_lst(model).unwrap();
    let base = model.parent().unwrap();
    let colour: Vec<solidtex::Volume> =
        lst.sources.iter().map(|s| solidtex::io::read_volume(&base.join(&s.volume), u64::MAX).unwrap()).collect();
    let masks: Vec<solidtex::Volume> =
        lst.sources.iter().map(|s| solidtex::library::fill::load_mask(&s.mask, base).unwrap()).collect();
    let textures = render::Textures::new(&colour, &masks);
    let ex = solidtex::io::read_volume(&base.join("built").join(format!("{exemplar}.exr")), u64::MAX).unwrap();
    let (skin, flesh) = (mean_colour(&ex, 0..1), mean_colour(&ex, ex.dims()[2] / 3..2 * ex.dims()[2] / 3));
    let (mut skins, mut all) = (0usize, 0usize);
    let surface = &lst.surface;
    for t in &surface.triangles {
        let [a, b, c] = t.map(|v| surface.vertices[v as usize]);
        if !keep((a + b + c) / 3.0) {
            continue;
        }
        for (u, v) in [(0.2, 0.2), (0.6, 0.2), (0.2, 0.6)] {
            let rgba = render::shade_point(&lst, &textures, a + (b - a) * u + (c - a) * v).unwrap();
            let dist = |k: [f64; 3]| (0..3).map(|i| (rgba[i] as f64 - k[i]).powi(2)).sum::<f64>();
            all += 1;
            skins += usize::from(dist(skin) < dist(flesh));
        }
    }
    skins as f64 / all.max(1) as f64
}

/// Depth 0 holds on the whole surface whatever its triangulation: the bark covers a coarse
/// tube's outer wall (16 sides, one long triangle pair per side; the RBF alone, held only
/// at surface samples, let the wood through in wide bands), and the kiwi's skin covers the
/// whole surface of a genus-1 shape.
#[test]
fn the_skin_covers_the_whole_surface_of_coarse_and_holed_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let tube = d.join("tube.obj");
    coarse_tube(&tube, 16);
    let body = "exemplar = \"trunk\"\nseed = 1\ntets = 8000\n[depth]\nsurface = true\n\
                [[depth.faces]]\nat = [0.1, 0, 0]\ncrease = 30\nvalue = 1\n\
                [[direction]]\npoints = [[0.2, -0.45, 0], [0.2, 0.45, 0]]\n";
    fill(d, &tube.to_string_lossy(), &spec(d, "tube.toml", body), "tube.lst");
    let outer_wall = |p: glam::Vec3| p.x.hypot(p.z) > 0.2 && p.y.abs() < 0.49;
    let share = skin_share(&d.join("tube.lst"), "trunk", outer_wall);
    assert!(share >= 0.95, "bark on {:.1} % of the coarse tube's outer wall", share * 100.0);

    let torus = draw(d, "pipe");
    let body = "exemplar = \"kiwi\"\nseed = 1\ntets = 12000\n[depth]\nsurface = true\n\
                axis = [[[0.75, 0, 0], [0, 0.75, 0], [-0.75, 0, 0], [0, -0.75, 0], [0.75, 0, 0]]]\n\
                [[direction]]\npoints = [[0.75, 0, 0], [0, 0.75, 0]]\n";
    fill(d, &torus, &spec(d, "torus.toml", body), "torus.lst");
    let share = skin_share(&d.join("torus.lst"), "kiwi", |_| true);
    assert!(share >= 0.99, "skin on {:.2} % of the torus' surface", share * 100.0);

    // an animal: the kiwi's axis along the bunny's body, ears and paws off the axis
    if let Some(shared) = crate::mesh::shared_meshes() {
        let bunny = shared.join("libigl_bunny.obj").to_string_lossy().into_owned();
        let body = "exemplar = \"kiwi\"\nseed = 1\ntets = 8000\n[depth]\nsurface = true\n\
                    axis = [[[-0.06, 0.08, 0], [0.03, 0.08, 0]]]\n\
                    [[direction]]\npoints = [[-0.06, 0.08, 0], [0.03, 0.08, 0]]\n";
        fill(d, &bunny, &spec(d, "bunny.toml", body), "bunny.lst");
        let share = skin_share(&d.join("bunny.lst"), "kiwi", |_| true);
        eprintln!("kiwi skin on {:.2} % of the bunny's surface", share * 100.0);
        assert!(share >= 0.99, "skin on {:.2} % of the bunny's surface", share * 100.0);
    }
}

/// Options a fill does not use are named with the reason, not dropped silently: a 2-b
/// kiwi takes its scale from the depth field and its masks from the built library. The
/// share of tets whose scale was raised is reported.
#[test]
fn unused_fill_options_are_named_and_raised_scales_counted() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "fruit");
    let (top, table) = ("scale = 0.01\nmask_falloff = 0.3\n", "[[scale_at]]\npoint = [0.5, 0, 0]\nscale = 0.2\n");
    let spec = spec(d, "kiwi.toml", &format!("{top}{KIWI}{table}"));
    let run = solidtex(&["fill", &mesh, "--spec", &spec, "-o", &at(d, "kiwi.lst")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    for needle in [
        "warning: ",
        "scale is not used by type 2-b",
        "[[scale_at]] is not used by type 2-b",
        "mask_falloff is not used",
        "texture scale raised to 2.5 tet edges in",
    ] {
        assert!(err.contains(needle), "no {needle:?} in {err}");
    }
    let plain = solidtex(&["fill", &mesh, "--spec", &self::spec(d, "plain.toml", KIWI), "-o", &at(d, "plain.lst")]);
    assert!(!stderr(&plain).contains("warning"), "{}", stderr(&plain));
}

/// A plate a fiftieth as thick as wide: at 1,000 tets the lattice is coarser than the
/// plate, and the first spacing with tets inside gives several times more. `fill` says so,
/// naming the mesh and both counts; a fill whose count lands near the target does not.
#[test]
fn a_tet_count_far_from_the_target_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plate = solidtex::mesh::shapes::cuboid(glam::Vec3::ZERO, glam::Vec3::new(1.0, 1.0, 0.02));
    let path = d.join("plate.obj");
    solidtex::io::mesh_file::write_obj(&path, &plate).unwrap();
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\n");
    let fill_with = |tets: &str| {
        let run = solidtex(&["fill", &at(d, "plate.obj"), "--spec", &spec, "--tets", tets, "-o", &at(d, "p.lst")]);
        assert!(run.status.success(), "{}", stderr(&run));
        stderr(&run)
    };
    let far = fill_with("1000");
    assert!(far.contains("warning: ") && far.contains("plate.obj") && far.contains("for the 1000 asked"), "{far}");
    let near = fill_with("10000");
    assert!(!near.contains("asked"), "{near}");
}

/// A cube and, beside it from x = 1.5, a plate `thickness` thick, as an OBJ in `dir`.
fn cube_and_plate(dir: &Path, thickness: f32) -> String {
    let cube = solidtex::mesh::shapes::cuboid(glam::Vec3::ZERO, glam::Vec3::ONE);
    let plate = solidtex::mesh::shapes::cuboid(glam::Vec3::new(1.5, 0.0, 0.0), glam::Vec3::new(3.5, 2.0, thickness));
    let offset = cube.vertices.len() as u32;
    let vertices = cube.vertices.iter().chain(&plate.vertices).copied().collect();
    let triangles =
        cube.triangles.iter().copied().chain(plate.triangles.iter().map(|t| t.map(|i| i + offset))).collect();
    let both = solidtex::mesh::Mesh::new(vertices, triangles).unwrap();
    solidtex::io::mesh_file::write_obj(&dir.join("parts.obj"), &both).unwrap();
    at(dir, "parts.obj")
}

#[test]
fn where_the_tets_stray_over_half_an_edge_from_the_surface_fill_says_where_to_cut() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // a plate far thinner than the lattice at 2,000 tets: it is lost, and its surface lies
    // more than an edge from the tets
    let mesh = cube_and_plate(d, 0.02);
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\nscale = 1.0\n");
    let out = at(d, "p.lst");
    let run = solidtex(&["fill", &mesh, "--spec", &spec, "--tets", "2000", "-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    let said = stderr(&run);
    let line = said.lines().find(|l| l.contains("over half a tet edge")).unwrap_or_else(|| panic!("{said}"));
    assert!(line.contains(&format!("solidtex cut {out} --plane ")), "{line}");
    let plane = line.split("--plane ").nth(1).and_then(|r| r.split(',').next()).unwrap_or_else(|| panic!("{line}"));
    let x: f64 = plane.parse().unwrap();
    assert!((1.5 - 1e-3..=3.5 + 1e-3).contains(&x), "the place named, x = {x}, is not on the plate: {line}");
    // the cube alone strays nowhere that far
    let cube = solidtex::mesh::shapes::cuboid(glam::Vec3::ZERO, glam::Vec3::ONE);
    solidtex::io::mesh_file::write_obj(&d.join("cube.obj"), &cube).unwrap();
    let run = solidtex(&["fill", &at(d, "cube.obj"), "--spec", &spec, "--tets", "2000", "-o", &out]);
    assert!(run.status.success() && !stderr(&run).contains("over half"), "{}", stderr(&run));
}

#[test]
fn a_thin_part_the_tets_lose_is_warned_about_with_a_count_that_keeps_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // a cube and, beside it, a plate far thinner than the lattice spacing at 3,000 tets
    cube_and_plate(d, 0.03);
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\n");
    let fill_with = |tets: &str| {
        let json = at(d, "p.json");
        let run = solidtex(&[
            "fill",
            &at(d, "parts.obj"),
            "--spec",
            &spec,
            "--tets",
            tets,
            "-o",
            &at(d, "p.lst"),
            "--json",
            &json,
        ]);
        assert!(run.status.success(), "{}", stderr(&run));
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (stderr(&run), stats)
    };
    let (lost, stats) = fill_with("3000");
    let share = stats["volume_share"].as_f64().unwrap();
    assert!(share < 0.95, "the plate is kept at 3,000 tets: {share}");
    assert!(lost.contains("parts.obj") && lost.contains("% of the mesh's volume"), "{lost}");
    // the farthest point of the two-sided distance is on the plate
    let farthest: Vec<f64> =
        stats["surface_distance"]["at"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let on_plate = farthest[0] >= 1.5 - 1e-3 && farthest[2] <= 0.08 + 1e-3;
    assert!(on_plate, "the farthest point {farthest:?} is not on the plate");
    let holding = stats["holding_tets"].as_u64().expect("a count that keeps the plate");
    assert!(lost.contains(&format!("--tets {holding}")), "{lost}");
    let (kept, stats) = fill_with(&holding.to_string());
    assert!(stats["volume_share"].as_f64().unwrap() >= 0.95, "{stats}");
    assert!(!kept.contains("volume"), "{kept}");
}

#[test]
fn a_tapered_axis_closes_the_kiwi_core_toward_its_ends() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "fruit");
    // the pale core in a cut along the axis: its length (columns holding pale pixels) and
    // its height in the middle column
    let core = |name: &str, body: &str| {
        let spec = spec(d, &format!("{name}.toml"), body);
        fill(d, &mesh, &spec, &format!("{name}.lst"));
        let png = at(d, &format!("{name}.png"));
        let run =
            solidtex(&["cut", &at(d, &format!("{name}.lst")), "--plane", "0,0,0,0,0,1", "--size", "256", "-o", &png]);
        assert!(run.status.success(), "{}", stderr(&run));
        let img = image::open(&png).unwrap().to_rgb8();
        let pale = |x: u32, y: u32| img.get_pixel(x, y).0.iter().all(|c| *c > 178);
        let columns: Vec<u32> = (0..256).filter(|&x| (0..256).any(|y| pale(x, y))).collect();
        let middle = (0..256).filter(|&y| pale(128, y)).count();
        (columns.len(), middle)
    };
    let (square, square_middle) = core("square", KIWI);
    let tapered =
        KIWI.replace("axis = [[[-0.75, 0, 0], [0.75, 0, 0]]]", "axis = [[[-0.75, 0, 0], [0.75, 0, 0]]]\ntaper = 0.5");
    let (spindle, spindle_middle) = core("spindle", &tapered);
    assert!(spindle as f32 <= 0.7 * square as f32, "core length {spindle} px tapered, {square} px not");
    let ratio = spindle_middle as f32 / square_middle.max(1) as f32;
    assert!(
        (0.8..1.25).contains(&ratio),
        "the middle of the core changed: {spindle_middle} against {square_middle} px"
    );
    // out of range is refused with the field and the range
    let bad = spec(d, "bad.toml", &KIWI.replace("[depth]", "[depth]\ntaper = 0.7"));
    let run = solidtex(&["fill", &mesh, "--spec", &bad, "-o", &at(d, "bad.lst")]);
    assert_fails(&run, &["depth.taper", "0.7", "0.5"]);
}

/// A library of one uniform grey exemplar in `dir` and a spec filling with it (type 0):
/// a filled model's `view` then shows its shading only.
fn grey_spec(dir: &Path, tets: usize) -> String {
    let png = image::RgbImage::from_pixel(32, 32, image::Rgb([200, 200, 200]));
    png.save(dir.join("grey.png")).unwrap();
    let library = "[[exemplar]]\nname = \"grey\"\nrecipe = \"sweep\"\nimage = \"grey.png\"\nlength = 32\naxis = \"z\"\ntype = \"0\"\n";
    std::fs::write(dir.join("grey_library.toml"), library).unwrap();
    let built = at(dir, "grey_built");
    assert!(solidtex(&["build", &at(dir, "grey_library.toml"), "-o", &built]).status.success());
    let body = format!(
        "exemplar = \"grey\"\nlibrary = \"grey_library.toml\"\nbuilt = \"grey_built\"\nseed = 1\ntets = {tets}\n"
    );
    std::fs::write(dir.join("grey.toml"), body).unwrap();
    at(dir, "grey.toml")
}

/// `mesh` filled with the grey exemplar and seen by `view` at 800² from the default
/// camera: the share of shading steps [`solidtex::fill::view::shard_share`] counts, and the
/// same share for the mesh alone drawn in the same grey by the same camera.
fn shards(dir: &Path, mesh: &str, spec: &str, name: &str) -> (f64, f64) {
    use solidtex::fill::view::{DEFAULT_CREASE, Shading, View, mesh_picture, shard_share};
    let model = at(dir, &format!("{name}.lst"));
    let run = solidtex(&["fill", mesh, "--spec", spec, "-o", &model]);
    assert!(run.status.success(), "{}", stderr(&run));
    let png = at(dir, &format!("{name}.png"));
    assert!(solidtex(&["view", &model, "--size", "800", "-o", &png]).status.success());
    let img = image::open(&png).unwrap().to_rgb8();
    let picture = solidtex::render::Rgb8 { width: 800, height: 800, data: img.into_raw() };
    let surface = solidtex::io::lst_file::read_lst(Path::new(&model)).unwrap().surface;
    let camera = (35.0, 25.0);
    let view = View { camera, size: 800, shading: Shading::Smooth { crease: DEFAULT_CREASE } };
    let alone = mesh_picture(&surface, view, |points| Ok(vec![[200.0 / 255.0; 3]; points.len()])).unwrap();
    (shard_share(&picture, &surface, camera, DEFAULT_CREASE), shard_share(&alone, &surface, camera, DEFAULT_CREASE))
}

#[test]
fn filled_models_are_shaded_as_smoothly_as_their_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spec = grey_spec(d, 5000);
    let mut meshes: Vec<(String, String)> =
        ["fruit", "log", "vase"].iter().map(|s| (s.to_string(), draw(d, s))).collect();
    let cake = at(d, "cake");
    assert!(solidtex(&["draw", "cake", "-o", &cake, "--library", &library()]).status.success());
    for layer in ["sponge-low", "cream", "sponge-high", "glaze"] {
        meshes.push((layer.into(), format!("{cake}/{layer}.obj")));
    }
    if let Some(shared) = crate::mesh::shared_meshes() {
        for name in [
            "libigl_bunny",
            "cgal_dragknob",
            "cgal_cactus",
            "cgal_blobby",
            "cgal_blob-closed",
            "cgal_ellipe0.003",
            "cgal_pipe",
        ] {
            meshes.push((name.into(), shared.join(format!("{name}.obj")).to_string_lossy().into_owned()));
        }
    }
    let shares: Vec<(String, (f64, f64))> =
        meshes.iter().map(|(name, mesh)| (name.clone(), shards(d, mesh, &spec, name))).collect();
    eprintln!("shading steps (filled, mesh alone): {shares:?}");
    for (name, (filled, alone)) in &shares {
        // the bunny's ear rims, neck and paws and the cactus' arm joints fold over a few
        // triangles: the mesh drawn alone steps there as much, and the fill may add nothing
        assert!(
            *filled <= 0.003 || *filled <= alone + 0.0005,
            "{name}: {:.2} % of the pixels step by more than 6/255 ({:.2} % for the mesh alone)",
            filled * 100.0,
            alone * 100.0
        );
    }
}

/// A mesh far smaller or larger than the tolerances allow (a tetrahedron 1e-10 or 1e12
/// units across) is refused with its size and the range, by `fill` and `surface` alike
/// (they panicked, or wrote a skin of twice the points asked).
#[test]
fn meshes_outside_the_sizes_solidtex_takes_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, spec) = kiwi_fruit(d);
    let photo = at(d, "grey.png");
    image::RgbImage::from_pixel(32, 32, image::Rgb([90, 90, 90])).save(&photo).unwrap();
    for (name, size) in [("tiny", 1e-10f64), ("huge", 1e12)] {
        let mesh = at(d, &format!("{name}.obj"));
        let corners = [[0.0, 0.0, 0.0], [size, 0.0, 0.0], [0.0, size, 0.0], [0.0, 0.0, size]];
        let mut text: String = corners.iter().map(|[x, y, z]| format!("v {x:e} {y:e} {z:e}\n")).collect();
        text += "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
        std::fs::write(&mesh, text).unwrap();
        let fill = solidtex(&["fill", &mesh, "--spec", &spec, "-o", &at(d, "out.lst")]);
        let surface = solidtex(&["surface", &mesh, "--exemplar", &photo, "--points", "200", "-o", &at(d, "out.ply")]);
        for run in [fill, surface] {
            assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
            assert!(stderr(&run).contains(&format!("{name}.obj: is ")), "{}", stderr(&run));
            assert!(stderr(&run).contains("units across: scale it"), "{}", stderr(&run));
        }
        assert!(!d.join("out.lst").exists() && !d.join("out.ply").exists());
    }
}

/// The volumes and mask files a model reads are its inputs: a bake naming one is a usage
/// error, and the file stays as it was (writing it would change the model silently).
#[test]
fn a_models_exemplar_and_masks_are_never_written_over() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, spec) = kiwi_fruit(d);
    fill(d, &mesh, &spec, "k.lst");
    let model = at(d, "k.lst");
    let lst = solidtex::io::lst_file::read_lst(Path::new(&model)).unwrap();
    let mut read: Vec<std::path::PathBuf> = lst.sources.iter().map(|s| d.join(&s.volume)).collect();
    read.extend(lst.sources.iter().filter_map(|s| match &s.mask {
        solidtex::fill::MaskRef::File(file) => Some(d.join(file)),
        _ => None,
    }));
    assert!(read.len() >= 2, "{read:?}");
    for file in read {
        let before = std::fs::read(&file).unwrap();
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let run = solidtex(&["bake", &model, "--res", "16", "-o", &file.to_string_lossy()]);
        crate::support::assert_usage(&run, &[&name, "input"]);
        assert_eq!(std::fs::read(&file).unwrap(), before, "{name} as it was");
    }
}

/// A depth-varying exemplar whose depth field leaves most of the model near depth 0 (all
/// skin) is warned about, naming the share; the kiwi in its fruit is not.
#[test]
fn a_fill_that_is_mostly_skin_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, kiwi) = kiwi_fruit(d);
    let run = solidtex(&["fill", &mesh, "--spec", &kiwi, "-o", &at(d, "k.lst"), "--json", &at(d, "k.json")]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!stderr(&run).contains("outer layer"), "{}", stderr(&run));
    // the core only at a point near the rim
    let body = KIWI.replace("axis = [[[-0.75, 0, 0], [0.75, 0, 0]]]", "points = [[0, 0.55, 0, 1.0]]");
    let skin = spec(d, "skin.toml", &body);
    let run = solidtex(&["fill", &mesh, "--spec", &skin, "-o", &at(d, "s.lst"), "--json", &at(d, "s.json")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("s.json")).unwrap()).unwrap();
    let share = stats["fill"]["outer_share"].as_f64().unwrap();
    assert!(share > 0.5, "{stats}");
    let said = stderr(&run);
    assert!(said.contains(&format!("{:.0} % of the volume lies in the outer 10 % of depth", share * 100.0)), "{said}");
}

/// A model written by a bare file name (into the folder `fill` runs in) names its volume
/// relative to that folder, so the folder can be moved and the model still cuts.
#[test]
fn a_model_written_by_a_bare_name_moves_with_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let proj = dir.path().join("proj");
    std::fs::create_dir_all(&proj).unwrap();
    let (mesh, spec) = kiwi_fruit(&proj);
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(["fill", &mesh, "--spec", &spec, "-o", "k.lst"])
        .current_dir(&proj)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let model = String::from_utf8_lossy(&std::fs::read(proj.join("k.lst")).unwrap()).into_owned();
    assert!(model.contains("built/kiwi.exr") && !model.contains(&*dir.path().to_string_lossy()), "{model}");
    let moved = dir.path().join("moved");
    std::fs::rename(&proj, &moved).unwrap();
    let cut = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(["cut", "k.lst", "--plane", "0,0,0,1,0,0", "--size", "64", "-o", "k.png"])
        .current_dir(&moved)
        .output()
        .unwrap();
    assert!(cut.status.success(), "{}", stderr(&cut));
}

/// A model written into a folder named with `..` from where `fill` runs names its volume and
/// masks as they are found from the model's own folder: cut from there, it shows the kiwi.
#[test]
fn a_model_written_up_a_folder_finds_its_volume_and_masks() {
    let dir = tempfile::tempdir().unwrap();
    let (proj, renders) = (dir.path().join("proj"), dir.path().join("renders"));
    std::fs::create_dir_all(&proj).unwrap();
    std::fs::create_dir_all(&renders).unwrap();
    let (mesh, spec) = kiwi_fruit(&proj);
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(["fill", &mesh, "--spec", &spec, "-o", "../renders/k.lst"])
        .current_dir(&proj)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let model = String::from_utf8_lossy(&std::fs::read(renders.join("k.lst")).unwrap()).into_owned();
    assert!(model.contains("../proj/built/kiwi.exr"), "the volume as found from renders/: {model}");
    let cut = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(["cut", "k.lst", "--plane", "0,0,0,1,0,0", "--size", "64", "-o", "k.png"])
        .current_dir(&renders)
        .output()
        .unwrap();
    assert!(cut.status.success(), "{}", stderr(&cut));
    let shown = image::open(renders.join("k.png")).unwrap().to_rgba8().pixels().filter(|p| p.0[3] > 0).count();
    assert!(shown > 64 * 64 / 4, "the cut shows the fruit: {shown} pixels");
}

/// A type that leaves `[depth]` unused meshes as if the spec had none: no tets spent
/// refining near the depth axis, the same mesh as without it, and the spec warned about.
#[test]
fn a_type_without_depth_spends_no_tets_on_the_depth_axis() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "fruit");
    let plain = spec(d, "plain.toml", "exemplar = \"marble\"\ntets = 3000\n");
    let with_depth =
        spec(d, "depth.toml", "exemplar = \"marble\"\ntets = 3000\n[depth]\naxis = [[[-0.8, 0, 0], [0.8, 0, 0]]]\n");
    let tets = |spec: &str, name: &str| {
        let (out, json) = (at(d, &format!("{name}.lst")), at(d, &format!("{name}.json")));
        let run = solidtex(&["fill", &mesh, "--spec", spec, "-o", &out, "--json", &json]);
        assert!(run.status.success(), "{}", stderr(&run));
        let stats: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (stderr(&run), stats["refined_tets"].as_u64().unwrap(), stats["fill"]["tets"].as_u64().unwrap())
    };
    let (said, refined, count) = tets(&with_depth, "d");
    assert!(said.contains("[depth] is not used by type 0") && !said.contains("refining near"), "{said}");
    assert_eq!(refined, 0, "{said}");
    assert_eq!(count, tets(&plain, "p").2, "the same tets as a spec without [depth]");
}

/// A fill whose exemplars another build is writing waits for that build (it holds the
/// folder's lock), says so, and then fills with what was built.
#[test]
fn a_fill_waits_for_another_build_of_its_exemplars_then_fills() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "fruit");
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\n");
    std::fs::create_dir_all(d.join("built/.cache")).unwrap();
    let lock = std::fs::File::create(d.join("built/.cache/build.lock")).unwrap();
    lock.lock().unwrap();
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(["fill", &mesh, "--spec", &spec, "-o", &at(d, "m.lst")])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(2));
    drop(lock);
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("waiting for another solidtex build of") && err.contains("built"), "{err}");
    assert!(d.join("built/marble.exr").is_file() && d.join("m.lst").is_file(), "{err}");
}

/// A fill builds the exemplars it needs into a folder holding the user's own report.md:
/// it fills, says the report is left as it is, and leaves the file untouched; `build` into
/// that folder still refuses.
#[test]
fn a_fill_builds_beside_a_users_report_and_leaves_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "block");
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\nscale = 1.0\ntets = 2000\n");
    std::fs::create_dir_all(d.join("built")).unwrap();
    std::fs::write(d.join("built/report.md"), b"my notes").unwrap();
    let run = solidtex(&["fill", &mesh, "--spec", &spec, "-o", &at(d, "m.lst")]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("report.md or report.html solidtex did not write"), "{}", stderr(&run));
    assert_eq!(std::fs::read(d.join("built/report.md")).unwrap(), b"my notes");
    assert!(d.join("built/marble.exr").is_file() && d.join("m.lst").is_file());
    let run = solidtex(&["build", &library(), "--only", "marble", "-o", &at(d, "built")]);
    assert_fails(&run, &["report.md", "not written by solidtex"]);
    assert_eq!(std::fs::read(d.join("built/report.md")).unwrap(), b"my notes");
}

/// Where the fill refines near a depth axis (and so re-meshes at a lower target), the
/// tet count the thin-parts warning names is one that keeps the parts.
#[test]
fn the_thin_parts_advice_names_a_count_that_keeps_them_when_the_fill_refines() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = draw(d, "fruit");
    let body = "exemplar = \"kiwi\"\nseed = 1\n[depth]\naxis = [[[-0.8, 0, 0], [0.8, 0, 0]]]\ntaper = 0.5\n\
                [[direction]]\npoints = [[-0.8, 0, 0], [0.8, 0, 0]]\n";
    let spec = spec(d, "kiwi.toml", body);
    let warned = |tets: &str| {
        let run = solidtex(&["fill", &mesh, "--spec", &spec, "--tets", tets, "-o", &at(d, "k.lst")]);
        stderr(&run)
    };
    let said = warned("500");
    let advice = said.split("--tets ").nth(1).unwrap_or_else(|| panic!("no advice in {said}"));
    let count = advice.split(' ').next().unwrap();
    let again = warned(count);
    assert!(!again.contains("% of the mesh's volume"), "--tets {count} was advised but loses parts: {again}");
}

/// A mesh whose edges are shared by more than two triangles is named non-manifold, apart
/// from open edges.
#[test]
fn a_non_manifold_mesh_is_told_apart_from_an_open_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // two unit cubes that share the edge from (1, 1, 0) to (1, 1, 1) (vertices 3 and 7)
    let obj = "v 0 0 0\nv 0 1 0\nv 1 1 0\nv 1 0 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 1 2 0\nv 2 2 0\nv 2 1 0\n\
               v 2 1 1\nv 2 2 1\nv 1 2 1\nf 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\nf 1 4 6\nf 1 6 5\nf 2 8 7\nf 2 7 3\n\
               f 1 5 8\nf 1 8 2\nf 4 3 7\nf 4 7 6\nf 3 9 10\nf 3 10 11\nf 7 12 13\nf 7 13 14\nf 3 11 12\nf 3 12 7\n\
               f 9 14 13\nf 9 13 10\nf 3 7 14\nf 3 14 9\nf 11 10 13\nf 11 13 12\n";
    let mesh = at(d, "touching.obj");
    std::fs::write(&mesh, obj).unwrap();
    let spec = spec(d, "marble.toml", "exemplar = \"marble\"\ntets = 1000\n");
    let run = solidtex(&["fill", &mesh, "--spec", &spec, "-o", &at(d, "t.lst")]);
    assert_fails(&run, &["touching.obj", "1 edge(s) shared by more than two triangles (non-manifold"]);
    assert!(!stderr(&run).contains("boundary edge"), "{}", stderr(&run));
    assert!(!d.join("t.lst").exists());
}

/// A bake into DDS says the channels the texture holds (R, G, B, A), and warns that the
/// others are not stored.
#[test]
fn a_dds_bake_names_the_channels_it_holds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mesh, spec) = kiwi_fruit(d);
    fill(d, &mesh, &spec, "k.lst");
    let run = solidtex(&["bake", &at(d, "k.lst"), "--res", "32", "-o", &at(d, "b.dds")]);
    let said = stderr(&run);
    assert!(run.status.success(), "{said}");
    let wrote = said.lines().find(|l| l.starts_with("wrote")).unwrap_or_else(|| panic!("{said}"));
    assert!(wrote.contains(", R, G, B, A)") && !wrote.contains("Depth"), "{wrote}");
    assert!(said.contains("Depth not stored"), "{said}");
}
