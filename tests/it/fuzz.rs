//! Mutation fuzzing of every reader of untrusted bytes, on stable Rust.
//!
//! Each reader gets valid seed files made by the crate's own writers (or small
//! hand-written ones for the variants the writers do not make). Every case mutates one
//! seed (bit flips, byte overwrites, truncation, inserted, duplicated and deleted chunks,
//! interesting numbers in text and in binary fields), writes it to a file and calls the
//! reader. An `Err` is the expected outcome; a panic, an abort, a hang, or an error whose
//! message is empty or does not name the file is a failure.
//!
//! Each reader runs in a child process (this test binary again, running the ignored
//! `fuzz::worker` test) under a 2 GiB address-space limit, so an abort or a runaway
//! allocation is caught and reported instead of killing the test run or the machine.
//! The parent kills a child that spends more than 10 s on one case. After a crash or a
//! hang the child is restarted at the next case, so one run reports every failure; each
//! failing input is saved under `target/fuzz-failures/`.
//!
//! | variable                 | meaning                                              |
//! |--------------------------|------------------------------------------------------|
//! | `SOLIDTEX_FUZZ_CASES`    | cases per reader (default [`DEFAULT_CASES`])         |
//! | `SOLIDTEX_FUZZ_READERS`  | comma-separated reader names to run (default all)    |
//! | `SOLIDTEX_FUZZ_SECONDS`  | stop each reader after this many seconds             |
//! | `SOLIDTEX_FUZZ_SEED`     | base seed of the mutations (default 1)               |
//!
//! The mutations of case N depend only on the base seed, the reader and N, so a case can
//! be replayed by running that reader with the same seed.

use crate::support::{assert_fails, at, listing, random_volume, solidtex};
use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use solidtex::fill::{LstModel, MaskRef, Source, mesher, model::DepthBumps, paste::Patch};
use solidtex::io::{self, fill_spec, lst_file, manifest, mesh_file, snapshot_file};
use solidtex::mask::Layer;
use solidtex::mesh::{Mesh, shapes};
use solidtex::volume::Axis;
use solidtex::{Channel, TextureType, Volume};
use std::cell::Cell;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Once};
use std::time::{Duration, Instant};

/// Cases per reader in a plain `cargo test`.
const DEFAULT_CASES: u64 = 10_000;
/// The voxel budget every volume read gets: no case may allocate more than this for samples.
const BUDGET: u64 = 1 << 20;
/// A case running longer than this is a hang.
const HANG: Duration = Duration::from_secs(10);
/// Address-space limit of a worker, in KiB (2 GiB): a runaway allocation fails fast.
const MEMORY_KIB: u64 = 2 << 20;
/// Failures of one kind (same message apart from numbers) saved and listed per worker;
/// later ones are only counted.
const SHOWN: u32 = 3;
/// Marks the worker's report lines on its standard output.
const TAG: &str = "FUZZ";

// ------------------------------------------------------------------------------ readers

/// A seed or a case: the files it consists of, by name (one file, or a folder's files).
type Files = Vec<(String, Vec<u8>)>;

/// One reader under test.
struct Target {
    /// Name used in reports, reproducer names and `SOLIDTEX_FUZZ_READERS`.
    name: &'static str,
    /// Name of the case file, or of the case folder for a slice stack.
    case: &'static str,
    /// The case is a folder of files rather than one file.
    folder: bool,
    /// Re-checksum PNG chunks after most mutations, so cases get past the CRC check.
    png: bool,
    /// A guided cache's header length: the blake3 checksum after it is recomputed after
    /// most mutations, so cases reach the body's checks.
    sealed: Option<usize>,
    /// Valid seeds, made in the given scratch folder.
    seeds: fn(&Path) -> Vec<Files>,
    /// The reader; `Ok` and `Err` are both fine.
    read: fn(&Path) -> solidtex::Result<()>,
}

const fn file(name: &'static str, case: &'static str, seeds: fn(&Path) -> Vec<Files>, read: Reader) -> Target {
    Target { name, case, folder: false, png: false, sealed: None, seeds, read }
}

type Reader = fn(&Path) -> solidtex::Result<()>;

const TARGETS: [Target; 20] = [
    file("obj", "case.obj", obj_seeds, read_mesh),
    file("stl_binary", "case.stl", stl_binary_seeds, read_mesh),
    file("stl_ascii", "case.stl", stl_ascii_seeds, read_mesh),
    file("ply_ascii", "case.ply", ply_ascii_seeds, read_mesh),
    file("ply_binary", "case.ply", ply_binary_seeds, read_mesh),
    file("ply_skin", "case.ply", ply_skin_seeds, read_skin),
    file("nrrd", "case.nrrd", nrrd_seeds, read_volume),
    file("vol", "case.vol", vol_seeds, read_volume),
    file("exr", "case.exr", exr_seeds, read_volume),
    file("vdb", "case.vdb", vdb_seeds, read_volume),
    file("dds", "case.dds", dds_seeds, read_volume),
    Target { png: true, ..file("png_atlas", "case.png", png_atlas_seeds, read_volume) },
    Target { png: true, folder: true, ..file("png_stack", "case", png_stack_seeds, read_volume) },
    file("manifest", "case.toml", manifest_seeds, read_manifest),
    file("fill_spec", "case.toml", fill_spec_seeds, read_fill_spec),
    file("lst", "case.lst", lst_seeds, read_lst),
    Target { sealed: Some(39), ..file("guided_cube", "case.cache", guided_cube_seeds, read_guided_cube) },
    Target { sealed: Some(48), ..file("guided_bricks", "case.cache", guided_brick_seeds, read_guided_bricks) },
    file("snapshot", "case.snap", snapshot_seeds, read_snapshot),
    file("snapshot_check", "case.snap", snapshot_check_seeds, check_snapshot),
];

fn read_mesh(path: &Path) -> solidtex::Result<()> {
    mesh_file::read_mesh(path).map(drop)
}

/// The key, side and channels of the guided cube seeds.
const CUBE: (u64, usize, usize) = (7, 3, 3);

fn read_guided_cube(path: &Path) -> solidtex::Result<()> {
    io::guided_cache::read_cube(path, CUBE.0, (CUBE.1, CUBE.2), (0.0, 1.0), io::guided_cache::CACHE_HINT).map(drop)
}

/// A guided-synthesis cube as `guided --cache` keeps it.
fn guided_cube_seeds(dir: &Path) -> Vec<Files> {
    let (key, side, channels) = CUBE;
    let colours: Vec<f32> = (0..side * side * side * channels).map(|i| (i % 10) as f32 / 10.0).collect();
    vec![written(dir, "cube.cache", |p| io::guided_cache::write_cube(p, key, side, channels, &colours))]
}

/// The key and level sizes of the guided brick seeds.
const BRICKS: (u64, [[usize; 3]; 2]) = (9, [[5, 4, 4], [10, 8, 7]]);

fn read_guided_bricks(path: &Path) -> solidtex::Result<()> {
    io::guided_cache::read(path, BRICKS.0, &BRICKS.1, &[[40; 3]; 2], 1 << 20).map(drop)
}

/// A guided-synthesis cache of two levels' bricks as `guided --cache` keeps it.
fn guided_brick_seeds(dir: &Path) -> Vec<Files> {
    use solidtex::synth::region::{Mask, Sparse};
    let (key, dims) = BRICKS;
    let value = |v: [usize; 3]| solidtex::synth::coords::Held {
        slot: [v[0] as u32, v[1] as u32, v[2] as u32 + 3],
        shown: (v[0] % 4) as u8,
    };
    let mut fine = Mask::empty(dims[1]);
    [[9, 7, 6], [0, 0, 0], [3, 5, 1]].into_iter().for_each(|v| fine.insert(v));
    let levels = [Sparse::compute(&Mask::full(dims[0]), value), Sparse::compute(&fine, value)];
    vec![written(dir, "bricks.cache", |p| io::guided_cache::write(p, key, &levels, true))]
}

fn read_skin(path: &Path) -> solidtex::Result<()> {
    mesh_file::read_coloured_ply(path).map(drop)
}

fn read_volume(path: &Path) -> solidtex::Result<()> {
    io::read_volume(path, BUDGET).map(drop)
}

fn read_manifest(path: &Path) -> solidtex::Result<()> {
    manifest::read_plan(path).map(drop)
}

fn read_fill_spec(path: &Path) -> solidtex::Result<()> {
    fill_spec::read_fill_spec(path).map(drop)
}

fn read_lst(path: &Path) -> solidtex::Result<()> {
    lst_file::read_lst(path).map(drop)
}

fn read_snapshot(path: &Path) -> solidtex::Result<()> {
    snapshot_file::read(path).map(drop)
}

/// Compare the snapshot's volume with the snapshot, within a tolerance (statistics and
/// thumbnails are read; the exact comparison only compares the hash text).
fn check_snapshot(path: &Path) -> solidtex::Result<()> {
    snapshot_file::check(path, &snapshot_volume(), 0.01)
}

// -------------------------------------------------------------------------------- seeds

/// Write with one of the crate's writers into `dir`, and return the bytes.
fn written(dir: &Path, name: &str, write: impl FnOnce(&Path) -> solidtex::Result<()>) -> Files {
    let path = dir.join(name);
    write(&path).unwrap_or_else(|e| panic!("the seed {name} can be written: {e}"));
    vec![(name.to_string(), std::fs::read(&path).unwrap())]
}

fn text(content: &str) -> Files {
    vec![(String::new(), content.as_bytes().to_vec())]
}

/// Small volumes of 1, 3 and 4 channels; the last has a type and provenance.
fn volumes() -> Vec<Volume> {
    let mut typed = random_volume([3, 2, 5], Channel::rgba(), 3);
    typed.meta.texture_type = Some(TextureType::T2b);
    typed.meta.set("seed", "3");
    vec![random_volume([5, 4, 3], Channel::rgb(), 1), random_volume([4, 4, 4], Channel::grey(), 2), typed]
}

/// The volume the snapshot seeds describe.
fn snapshot_volume() -> Volume {
    volumes().swap_remove(0)
}

fn volume_seeds(dir: &Path, ext: &str, volumes: &[Volume]) -> Vec<Files> {
    volumes.iter().enumerate().map(|(i, v)| written(dir, &format!("{i}{ext}"), |p| io::write_volume(p, v))).collect()
}

fn nrrd_seeds(dir: &Path) -> Vec<Files> {
    let mut list = volumes();
    list.push(random_volume([2, 3, 2], vec![Channel::R, Channel::G, Channel::B, Channel::A, Channel::Depth], 4));
    volume_seeds(dir, ".nrrd", &list)
}

fn vdb_seeds(dir: &Path) -> Vec<Files> {
    let mut list = volumes();
    list.push(random_volume([9, 3, 2], vec![Channel::R, Channel::G, Channel::B, Channel::A, Channel::Depth], 5));
    volume_seeds(dir, ".vdb", &list)
}

fn dds_seeds(dir: &Path) -> Vec<Files> {
    let list = volumes();
    let mut seeds = volume_seeds(dir, ".dds", &list);
    for (i, format) in [io::dds::DdsFormat::Rgba8, io::dds::DdsFormat::Rgba32F].into_iter().enumerate() {
        seeds.push(written(dir, &format!("f{i}.dds"), |p| io::dds::write(p, &list[2], format)));
    }
    seeds
}

fn exr_seeds(dir: &Path) -> Vec<Files> {
    let mut list = volumes();
    list.push(random_volume([2, 3, 2], vec![Channel::R, Channel::Depth, Channel::Displacement], 4));
    volume_seeds(dir, ".exr", &list)
}

fn png_atlas_seeds(dir: &Path) -> Vec<Files> {
    volume_seeds(dir, ".png", &volumes())
}

fn vol_seeds(dir: &Path) -> Vec<Files> {
    let cubes = [
        random_volume([3, 3, 3], Channel::rgb(), 1),
        random_volume([4, 4, 4], Channel::grey(), 2),
        random_volume([2, 2, 2], vec![Channel::R, Channel::G, Channel::B, Channel::A, Channel::Depth], 3),
    ];
    let mut seeds = volume_seeds(dir, ".vol", &cubes);
    seeds.push(vec![(String::new(), byte_vol())]);
    seeds
}

/// A 2³ `.vol` with one byte per sample (the writer always uses f32).
fn byte_vol() -> Vec<u8> {
    let mut bytes = vec![0u8; 4096];
    bytes[0..4].copy_from_slice(b"VOLU");
    bytes[4..8].copy_from_slice(&4i32.to_le_bytes());
    bytes[8..12].copy_from_slice(b"kiwi");
    for (at, value) in [(268, 2i32), (272, 1), (276, 1)] {
        bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
    }
    bytes.extend_from_slice(&[0, 51, 102, 153, 204, 255, 0, 255]);
    bytes
}

/// Each slice stack as its folder's files, sorted by name.
fn png_stack_seeds(dir: &Path) -> Vec<Files> {
    volumes()
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let folder = dir.join(format!("stack{i}"));
            io::write_volume(&folder, v).unwrap_or_else(|e| panic!("the seed stack can be written: {e}"));
            let mut files: Files = std::fs::read_dir(&folder)
                .unwrap()
                .map(|e| e.unwrap())
                .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
                .collect();
            files.sort();
            files
        })
        .collect()
}

/// A tetrahedron and an axis-aligned box.
fn meshes() -> Vec<Mesh> {
    let corners = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    let tetrahedron = Mesh::new(corners, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).unwrap();
    vec![tetrahedron, shapes::cuboid(Vec3::new(-1.0, -0.5, -0.5), Vec3::new(1.0, 0.5, 0.5))]
}

fn obj_seeds(dir: &Path) -> Vec<Files> {
    let mut seeds: Vec<Files> = meshes()
        .iter()
        .enumerate()
        .map(|(i, m)| written(dir, &format!("{i}.obj"), |p| mesh_file::write_obj(p, m)))
        .collect();
    seeds.push(text(
        "# corners with texture and normal indices, negative indices and a quad\no shape\n\
         v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n\
         f 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\nf -4 -3 -1\nf 2 3 4 # last\n\
         v 2 2 2\nv 3 2 2\nv 3 3 2\nv 2 3 2\ng quad\nf 5 6 7 8\n",
    ));
    seeds
}

fn stl_binary_seeds(dir: &Path) -> Vec<Files> {
    meshes()
        .iter()
        .enumerate()
        .map(|(i, m)| written(dir, &format!("{i}.stl"), |p| mesh_file::write_stl(p, m)))
        .collect()
}

fn stl_ascii_seeds(_: &Path) -> Vec<Files> {
    meshes().iter().map(|m| text(&ascii_stl(m))).collect()
}

/// An ASCII STL (the crate writes binary ones only).
fn ascii_stl(mesh: &Mesh) -> String {
    let mut out = String::from("solid shape\n");
    for t in &mesh.triangles {
        out += "  facet normal 0 0 0\n    outer loop\n";
        for v in t.map(|i| mesh.vertices[i as usize]) {
            out += &format!("      vertex {} {} {}\n", v.x, v.y, v.z);
        }
        out += "    endloop\n  endfacet\n";
    }
    out + "endsolid shape\n"
}

fn ply_ascii_seeds(dir: &Path) -> Vec<Files> {
    let mut seeds: Vec<Files> = meshes()
        .iter()
        .enumerate()
        .map(|(i, m)| written(dir, &format!("{i}.ply"), |p| mesh_file::write_ply(p, m)))
        .collect();
    seeds.push(text(
        "ply\nformat ascii 1.0\ncomment normals, an extra list element and vertex_index\nobj_info test\n\
         element vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n\
         element face 2\nproperty uchar flags\nproperty list uchar uint vertex_index\n\
         element material 1\nproperty list uchar float values\nend_header\n\
         0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n7 3 0 2 1\n7 4 0 1 3 2\n2 0.5 0.25\n",
    ));
    seeds
}

fn ply_binary_seeds(_: &Path) -> Vec<Files> {
    let [tetrahedron, cuboid] = <[Mesh; 2]>::try_from(meshes()).unwrap();
    vec![vec![(String::new(), binary_ply(&tetrahedron, false))], vec![(String::new(), binary_ply(&cuboid, true))]]
}

/// Skins as `surface` writes them: binary PLYs with a colour per vertex.
fn ply_skin_seeds(dir: &Path) -> Vec<Files> {
    let [tetrahedron, cuboid] = <[Mesh; 2]>::try_from(meshes()).unwrap();
    let skin = |mesh: Mesh| {
        let colours = (0..mesh.vertices.len()).map(|i| [i as f32 / 8.0 % 1.0, 0.5, 1.0]).collect();
        mesh_file::ColouredMesh { mesh, colours }
    };
    vec![
        written(dir, "small.ply", |p| mesh_file::write_coloured_ply(p, &skin(tetrahedron))),
        written(dir, "box.ply", |p| mesh_file::write_coloured_ply(p, &skin(cuboid))),
    ]
}

/// A little-endian binary PLY (the crate writes ASCII ones only); `wide` uses doubles,
/// a `ushort` list count and an extra property after the list.
fn binary_ply(mesh: &Mesh, wide: bool) -> Vec<u8> {
    let (coord, list, extra) = match wide {
        true => ("double", "ushort uint vertex_indices", "property uchar flags\n"),
        false => ("float", "uchar int vertex_indices", ""),
    };
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment binary seed\nelement vertex {}\nproperty {coord} x\n\
         property {coord} y\nproperty {coord} z\nproperty uchar red\nelement face {}\nproperty list {list}\n{extra}\
         element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    let mut out = header.into_bytes();
    for v in &mesh.vertices {
        for x in v.to_array() {
            match wide {
                true => out.extend_from_slice(&f64::from(x).to_le_bytes()),
                false => out.extend_from_slice(&x.to_le_bytes()),
            }
        }
        out.push(200);
    }
    for t in &mesh.triangles {
        match wide {
            true => out.extend_from_slice(&3u16.to_le_bytes()),
            false => out.push(3),
        }
        t.iter().for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
        if wide {
            out.push(1);
        }
    }
    [0i32, 1].iter().for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
    out
}

fn repository_text(name: &str) -> Files {
    text(&std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap())
}

fn manifest_seeds(_: &Path) -> Vec<Files> {
    vec![
        repository_text("exemplars/library.toml"),
        text(
            "[[exemplar]]\nname = \"block\"\nrecipe = \"procedural:wood\"\nsize = [16, 16, 8]\nseed = 2\n\
             type = \"1-b\"\nmasks = [\"splotch\", \"layered\"]\nmask_falloff = 0.2\nexports = [\"nrrd\", \"slices\"]\n\n\
             [[exemplar.steps]]\nstamp = \"seed.obj\"\nat = \"8,8,4\"\nrotate = \"0,0,1,30\"\nscale = \"2,1,1\"\n\
             color = \"#ff8000\"\n\n[[exemplar.steps]]\nscatter = \"seed.obj\"\ncount = 5\n\
             region = \"box:0,0,0,8,8,8\"\nscale = \"1..2\"\ncolor = \"0.1,0.2,0.3\"\nseed = 4\n\n\
             [[exemplar]]\nname = \"grown\"\nrecipe = \"synth-layered\"\nimage = \"a.png\"\n\
             depth_image = \"d.png\"\nsize = 16\nlevels = 2\nmax_exemplar = 64\n\n\
             [[exemplar]]\nname = \"loaded\"\nrecipe = \"load\"\nvolume = \"v.exr\"\n",
        ),
    ]
}

fn fill_spec_seeds(_: &Path) -> Vec<Files> {
    let mut seeds: Vec<Files> = ["kiwi", "strata", "trunk"]
        .iter()
        .map(|name| repository_text(&format!("exemplars/{name}_fill.toml")))
        .collect();
    seeds.push(text(
        "exemplar = \"kiwi\"\ntype = \"2-b\"\nseed = 4\ntets = 3000\naxes = \"z,x\"\nscale = 0.4\n\
         mask_falloff = 0.2\n[[direction]]\npoints = [[0, 0, -1], [0, 0, 1]]\n\
         [depth]\nsurface = true\naxis = [[[0, 0, -0.8], [0, 0, 0.8]]]\npoints = [[0.1, 0, 0, 0.5]]\n\
         [[depth.faces]]\nat = [0, 1, 0]\ncrease = 20\nvalue = 1\n[[scale_at]]\npoint = [0, 0, 0]\nscale = 0.3\n\
         [[paste]]\nexemplar = \"marble\"\nat = [0, 0, 0]\nrotate = \"0,1,0,45\"\nscale = 0.5\n",
    ));
    seeds
}

/// A model over a tetrahedralized box with all three kinds of mask reference, a
/// patch over every vertex and a patch over the first tet only.
fn lst_seeds(dir: &Path) -> Vec<Files> {
    let [_, cuboid] = <[Mesh; 2]>::try_from(meshes()).unwrap();
    let mesh = mesher::tetrahedralize(&cuboid, 100).unwrap();
    let source = |mask| Source { exemplar: "marble".into(), volume: "marble.exr".into(), mask };
    let sources = vec![
        source(MaskRef::Splotch { size: 16, falloff: 0.2, seed: 3 }),
        source(MaskRef::Layered { layer: Layer::Middle, depth: Axis::Z, size: 16, falloff: 0.2, seed: 3 }),
        source(MaskRef::File("masks/marble.exr".into())),
    ];
    let all: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
    let mut first: Vec<u32> = mesh.tets[0].to_vec();
    first.sort();
    let patches = vec![
        Patch { source: 0, coords: all.iter().map(|&v| mesh.vertices[v as usize]).collect(), vertices: all },
        Patch { source: 2, coords: vec![Vec3::splat(0.5); 4], vertices: first },
    ];
    let mut tet_patches = vec![vec![0]; mesh.tets.len()];
    tet_patches[0].push(1);
    let edges = (0..mesh.tets.len()).map(|t| [0.01 * (t % 7) as f32, -0.02, 0.0, 0.03, 0.0, 0.1]).collect();
    let model = LstModel::new(mesh, cuboid, sources, patches, tet_patches);
    let plain = model.clone();
    let smooth = model.with_depth(DepthBumps { axis: 2, sources: 2, edges });
    vec![
        written(dir, "model.lst", |p| lst_file::write_lst(p, &plain)),
        written(dir, "depth.lst", |p| lst_file::write_lst(p, &smooth)),
    ]
}

fn snapshot_seeds(dir: &Path) -> Vec<Files> {
    let [first, grey, typed] = <[Volume; 3]>::try_from(volumes()).unwrap();
    vec![
        written(dir, "same.snap", |p| snapshot_file::write(p, &first)),
        written(dir, "grey.snap", |p| snapshot_file::write(p, &grey)),
        written(dir, "typed.snap", |p| snapshot_file::write(p, &typed)),
    ]
}

/// Snapshots of [`snapshot_volume`]: exact, and with one sample nudged by 0.002.
fn snapshot_check_seeds(dir: &Path) -> Vec<Files> {
    let mut nudged = snapshot_volume();
    nudged.set(2, 2, 1, 0, nudged.get(2, 2, 1, 0) + 0.002);
    vec![
        written(dir, "same.snap", |p| snapshot_file::write(p, &snapshot_volume())),
        written(dir, "nudged.snap", |p| snapshot_file::write(p, &nudged)),
    ]
}

// ---------------------------------------------------------------------------- mutations

/// Numbers that break size arithmetic and parsers, as text.
const TEXT_NUMBERS: [&str; 28] = [
    "0",
    "-1",
    "1",
    "-0",
    "2",
    "255",
    "256",
    "65535",
    "65536",
    "1048576",
    "1e8",
    "1e308",
    "-1e308",
    "1e-45",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "18446744073709551615",
    "99999999999999999999",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "0.0",
    "",
];

/// Integers and float bit patterns that break size arithmetic, for 4-byte fields.
const WORDS: [u32; 22] = [
    0,
    1,
    2,
    3,
    4,
    0xff,
    0x100,
    0xffff,
    0x1_0000,
    0x3fff_ffff,
    0x4000_0000,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_fffe,
    0xffff_ffff,
    0x7fc0_0000, // f32 NaN
    0x7f80_0000, // f32 infinity
    0xff80_0000, // f32 -infinity
    0x7f7f_ffff, // f32::MAX
    0x3f80_0000, // 1.0
    0x0000_0001, // smallest subnormal
    0xbf80_0000, // -1.0
];

/// The same for 8-byte fields.
const LONG_WORDS: [u64; 10] = [
    0,
    1,
    0xffff_ffff,
    0x1_0000_0000,
    0x7fff_ffff_ffff_ffff,
    0x8000_0000_0000_0000,
    u64::MAX,
    0x7ff8_0000_0000_0000, // f64 NaN
    0x7ff0_0000_0000_0000, // f64 infinity
    0x3ff0_0000_0000_0000, // 1.0
];

/// Bytes that matter to parsers: separators, signs, digits, NUL and the extremes.
const SPECIAL_BYTES: [u8; 14] = [0, 0xff, 0x7f, 0x80, b'\n', b'\r', b' ', b'-', b'.', b'9', b'0', b'#', b'"', b'='];

/// The kinds of mutation, each applied at a random place.
#[derive(Clone, Copy, Debug)]
enum Mutation {
    FlipBits,
    OverwriteBytes,
    Truncate,
    InsertBytes,
    DuplicateChunk,
    DeleteChunk,
    TextNumber,
    BinaryWord,
}

const MUTATIONS: [Mutation; 8] = [
    Mutation::FlipBits,
    Mutation::OverwriteBytes,
    Mutation::Truncate,
    Mutation::InsertBytes,
    Mutation::DuplicateChunk,
    Mutation::DeleteChunk,
    Mutation::TextNumber,
    Mutation::BinaryWord,
];

fn pick<T: Copy>(rng: &mut Pcg64, list: &[T]) -> T {
    list[rng.random_range(0..list.len())]
}

/// A position in `bytes`, half the time within the first 512 bytes (where headers are).
fn position(rng: &mut Pcg64, bytes: &[u8], inclusive_end: bool) -> usize {
    let end = bytes.len() + usize::from(inclusive_end);
    if end == 0 {
        return 0;
    }
    let reach = if rng.random_bool(0.5) { end.min(512) } else { end };
    rng.random_range(0..reach)
}

fn mutate(rng: &mut Pcg64, bytes: &mut Vec<u8>, kind: Mutation) {
    match kind {
        Mutation::FlipBits => flip_bits(rng, bytes),
        Mutation::OverwriteBytes => overwrite_bytes(rng, bytes),
        Mutation::Truncate => bytes.truncate(position(rng, bytes, false)),
        Mutation::InsertBytes => insert_bytes(rng, bytes),
        Mutation::DuplicateChunk => duplicate_chunk(rng, bytes),
        Mutation::DeleteChunk => delete_chunk(rng, bytes),
        Mutation::TextNumber => text_number(rng, bytes),
        Mutation::BinaryWord => binary_word(rng, bytes),
    }
}

fn flip_bits(rng: &mut Pcg64, bytes: &mut [u8]) {
    for _ in 0..rng.random_range(1..=8) {
        if bytes.is_empty() {
            return;
        }
        let at = position(rng, bytes, false);
        bytes[at] ^= 1 << rng.random_range(0..8);
    }
}

fn overwrite_bytes(rng: &mut Pcg64, bytes: &mut [u8]) {
    if bytes.is_empty() {
        return;
    }
    let at = position(rng, bytes, false);
    let end = (at + rng.random_range(1..=8)).min(bytes.len());
    for b in &mut bytes[at..end] {
        *b = if rng.random_bool(0.5) { pick(rng, &SPECIAL_BYTES) } else { rng.random() };
    }
}

fn insert_bytes(rng: &mut Pcg64, bytes: &mut Vec<u8>) {
    let at = position(rng, bytes, true);
    let count = rng.random_range(1..=64);
    let new: Vec<u8> =
        (0..count).map(|_| if rng.random_bool(0.5) { pick(rng, &SPECIAL_BYTES) } else { rng.random() }).collect();
    bytes.splice(at..at, new);
}

/// Copy a chunk of the file (up to 256 bytes) to another place, possibly several times.
fn duplicate_chunk(rng: &mut Pcg64, bytes: &mut Vec<u8>) {
    if bytes.is_empty() {
        return;
    }
    let start = position(rng, bytes, false);
    let end = (start + rng.random_range(1..=256)).min(bytes.len());
    let chunk = bytes[start..end].to_vec();
    let at = position(rng, bytes, true);
    let copies = pick(rng, &[1, 1, 1, 2, 8, 64]);
    bytes.splice(at..at, chunk.iter().copied().cycle().take(chunk.len() * copies));
}

fn delete_chunk(rng: &mut Pcg64, bytes: &mut Vec<u8>) {
    if bytes.is_empty() {
        return;
    }
    let start = position(rng, bytes, false);
    let end = (start + rng.random_range(1..=256)).min(bytes.len());
    bytes.drain(start..end);
}

/// Replace a run of number characters holding a digit (`12`, `-0.8`, `1e-3`) with an
/// interesting number; with no such run, insert one.
fn text_number(rng: &mut Pcg64, bytes: &mut Vec<u8>) {
    let runs = number_runs(bytes);
    let new = pick(rng, &TEXT_NUMBERS).as_bytes();
    match runs.is_empty() {
        true => {
            let at = position(rng, bytes, true);
            bytes.splice(at..at, new.iter().copied());
        }
        false => {
            let (start, end) = runs[rng.random_range(0..runs.len())];
            bytes.splice(start..end, new.iter().copied());
        }
    }
}

fn number_runs(bytes: &[u8]) -> Vec<(usize, usize)> {
    let in_number = |b: u8| b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.' | b'e' | b'E');
    let mut runs = Vec::new();
    let mut at = 0;
    while at < bytes.len() {
        let len = bytes[at..].iter().position(|b| !in_number(*b)).unwrap_or(bytes.len() - at);
        if bytes[at..at + len].iter().any(u8::is_ascii_digit) {
            runs.push((at, at + len));
        }
        at += len.max(1);
    }
    runs
}

/// Write an interesting 2-, 4- or 8-byte value (or nudge the 4-byte value there), mostly
/// at an aligned offset, little-endian or (for PNG and the like) big-endian.
fn binary_word(rng: &mut Pcg64, bytes: &mut Vec<u8>) {
    let size = pick(rng, &[2usize, 4, 4, 4, 8]);
    if bytes.len() < size {
        bytes.resize(size, 0);
    }
    let at = position(rng, &bytes[..bytes.len() - size + 1], false);
    let at = if rng.random_bool(0.75) { at / size * size } else { at };
    let big = rng.random_bool(0.3);
    let new: Vec<u8> = match size {
        2 => {
            let v = pick(rng, &WORDS) as u16;
            if big { v.to_be_bytes().to_vec() } else { v.to_le_bytes().to_vec() }
        }
        4 => {
            let old = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
            let v = match rng.random_bool(0.25) {
                true => old.wrapping_add(rng.random_range(1..=16)).wrapping_sub(8),
                false => pick(rng, &WORDS),
            };
            if big { v.to_be_bytes().to_vec() } else { v.to_le_bytes().to_vec() }
        }
        _ => {
            let v = pick(rng, &LONG_WORDS);
            if big { v.to_be_bytes().to_vec() } else { v.to_le_bytes().to_vec() }
        }
    };
    bytes[at..at + size].copy_from_slice(&new);
}

/// Recompute the CRC of every whole chunk of a PNG, so a mutated chunk is parsed
/// rather than refused at its checksum.
fn fix_png_crcs(bytes: &mut [u8]) {
    let mut at = 8;
    while at + 12 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let Some(end) = at.checked_add(8 + len).filter(|end| end + 4 <= bytes.len()) else { return };
        let crc = crc32(&bytes[at + 4..end]);
        bytes[end..end + 4].copy_from_slice(&crc.to_be_bytes());
        at = end + 4;
    }
}

/// CRC-32 (ISO-HDLC, as PNG uses).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xedb8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// The random source of one case: depends only on the base seed, the reader and the case.
fn case_rng(seed: u64, reader: &str, case: u64) -> Pcg64 {
    let name = reader.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
    Pcg64::seed_from_u64(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ name ^ case.wrapping_mul(0xd605_bbb5_8c8a_bbfd))
}

/// One case: a mutated copy of a random seed. One to four mutations hit one file; in a
/// folder a file is sometimes dropped or doubled instead.
fn make_case(target: &Target, seeds: &[Files], rng: &mut Pcg64) -> Files {
    let mut files = seeds[rng.random_range(0..seeds.len())].clone();
    if files.len() > 1 && rng.random_bool(0.1) {
        let k = rng.random_range(0..files.len());
        match rng.random_bool(0.5) {
            true => drop(files.remove(k)),
            false => files.push((format!("y{k}.png"), files[k].1.clone())),
        }
        return files;
    }
    let k = rng.random_range(0..files.len());
    let bytes = &mut files[k].1;
    for _ in 0..pick(rng, &[1, 1, 1, 2, 2, 3, 4]) {
        let kind = pick(rng, &MUTATIONS);
        mutate(rng, bytes, kind);
    }
    if target.png && rng.random_bool(0.8) {
        fix_png_crcs(bytes);
    }
    if let Some(header) = target.sealed
        && bytes.len() >= header + 32
        && rng.random_bool(0.8)
    {
        let sum = blake3::Hasher::new().update(&bytes[..header]).update(&bytes[header + 32..]).finalize();
        bytes[header..header + 32].copy_from_slice(sum.as_bytes());
    }
    files
}

/// Put the case where the reader will look: one file, or a fresh folder of files.
/// The old file is removed rather than truncated: on ext4, truncating and rewriting a
/// file flushes it to disk on close, which would make each case wait for the disk.
fn write_case(target: &Target, path: &Path, files: &Files) {
    if !target.folder {
        let _ = std::fs::remove_file(path);
        std::fs::write(path, &files[0].1).unwrap();
        return;
    }
    let _ = std::fs::remove_dir_all(path);
    std::fs::create_dir(path).unwrap();
    for (name, bytes) in files {
        std::fs::write(path.join(name), bytes).unwrap();
    }
}

// ------------------------------------------------------------------------- running cases

thread_local! {
    /// Set while a case runs on this thread: its panics are recorded, not printed.
    static IN_CASE: Cell<bool> = const { Cell::new(false) };
}

/// The case being run in this process.
static CASE: AtomicU64 = AtomicU64::new(u64::MAX);

/// The message of the last panic inside a case.
static PANIC: Mutex<Option<String>> = Mutex::new(None);

/// Record panics inside cases quietly; leave every other panic to the previous hook.
fn install_panic_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| match IN_CASE.with(Cell::get) {
            true => *PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(info.to_string()),
            false => previous(info),
        }));
    });
}

/// Run the reader on the case at `path`: whether it read without error, or what is wrong
/// with the outcome.
fn run_case(target: &Target, path: &Path) -> Result<bool, String> {
    IN_CASE.with(|c| c.set(true));
    let outcome = panic::catch_unwind(AssertUnwindSafe(|| (target.read)(path)));
    IN_CASE.with(|c| c.set(false));
    match outcome {
        Ok(Ok(())) => Ok(true),
        Ok(Err(e)) => error_problem(&e.to_string(), path).map_or(Ok(false), Err),
        Err(_) => Err(PANIC.lock().unwrap_or_else(|e| e.into_inner()).take().unwrap_or_else(|| "panic".into())),
    }
}

/// What makes failures the same kind: the message up to its first line break, without
/// numbers.
fn kind_of(problem: &str) -> String {
    let first = problem.split(" | ").next().unwrap_or_default();
    first.chars().filter(|c| !c.is_ascii_digit()).take(160).collect()
}

/// An error must say something and name the file (or the folder) it is about.
fn error_problem(message: &str, path: &Path) -> Option<String> {
    if message.trim().is_empty() {
        Some("the error message is empty".into())
    } else if !message.contains(&*path.to_string_lossy()) {
        Some(format!("the error does not name the file: {message}"))
    } else {
        None
    }
}

/// Copy the case to `folder/READER-CASE[.ext]` and return that path.
fn save_reproducer(target: &Target, case: u64, path: &Path, folder: &Path) -> PathBuf {
    std::fs::create_dir_all(folder).unwrap();
    let ext = Path::new(target.case).extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    let saved = folder.join(format!("{}-{case}{ext}", target.name));
    if target.folder {
        let _ = std::fs::remove_dir_all(&saved);
        std::fs::create_dir(&saved).unwrap();
        for entry in std::fs::read_dir(path).into_iter().flatten().flatten() {
            let _ = std::fs::copy(entry.path(), saved.join(entry.file_name()));
        }
    } else {
        let _ = std::fs::copy(path, &saved);
    }
    saved
}

/// Checks that every seed reads without error, so the mutations start from valid files.
fn checked_seeds(target: &Target, dir: &Path) -> Vec<Files> {
    let scratch = dir.join("seeds");
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir(&scratch).unwrap();
    let seeds = (target.seeds)(&scratch);
    let path = dir.join(target.case);
    for (i, seed) in seeds.iter().enumerate() {
        write_case(target, &path, seed);
        if let Err(e) = (target.read)(&path) {
            panic!("seed {i} of the {} reader does not read: {e}", target.name);
        }
    }
    seeds
}

/// Run a job's cases, reporting to `out` a `FUZZ case N FINE` line before each case
/// (FINE: how many cases so far read without error), a `FUZZ fail` line per failure, and
/// `FUZZ done COUNT FINE` at the end.
fn run_cases(job: &Job, out: &mut dyn Write) {
    let (target, dir) = (job.target, job.dir);
    install_panic_hook();
    let seeds = checked_seeds(target, dir);
    let path = dir.join(target.case);
    let started = Instant::now();
    let base = base_seed();
    let (mut done, mut fine, mut kinds) = (0, 0, HashMap::new());
    for case in job.from..job.to {
        if job.seconds.is_some_and(|s| started.elapsed().as_secs_f64() > s) {
            break;
        }
        writeln!(out, "{TAG} case {case} {fine}").unwrap();
        out.flush().unwrap();
        CASE.store(case, Ordering::SeqCst);
        done += 1;
        let files = make_case(target, &seeds, &mut case_rng(base, target.name, case));
        write_case(target, &path, &files);
        match run_case(target, &path) {
            Ok(read) => fine += u64::from(read),
            Err(problem) => {
                let problem = problem.replace('\n', " | ");
                let seen = kinds.entry(kind_of(&problem)).or_insert(0);
                *seen += 1;
                if *seen > SHOWN {
                    writeln!(out, "{TAG} again {case}").unwrap();
                    continue;
                }
                let saved = save_reproducer(target, case, &path, job.saved);
                writeln!(out, "{TAG} fail {case} {}\t{problem}", saved.display()).unwrap();
            }
        }
    }
    writeln!(out, "{TAG} done {done} {fine}").unwrap();
}

// ------------------------------------------------------------------------------ settings

fn env_number<T: std::str::FromStr>(name: &str) -> Option<T> {
    let text = std::env::var(name).ok()?;
    Some(text.trim().parse().unwrap_or_else(|_| panic!("{name}={text:?} is not a number")))
}

fn base_seed() -> u64 {
    env_number("SOLIDTEX_FUZZ_SEED").unwrap_or(1)
}

fn case_count() -> u64 {
    env_number("SOLIDTEX_FUZZ_CASES").unwrap_or(DEFAULT_CASES)
}

/// Whether `SOLIDTEX_FUZZ_READERS` (if set) selects `name`; unknown names are an error.
fn selected(name: &str) -> bool {
    let Ok(list) = std::env::var("SOLIDTEX_FUZZ_READERS") else { return true };
    let names: Vec<&str> = list.split(',').map(str::trim).filter(|s| !s.is_empty()).collect();
    let known: Vec<&str> = TARGETS.iter().map(|t| t.name).collect();
    if let Some(bad) = names.iter().find(|n| !known.contains(n)) {
        panic!("SOLIDTEX_FUZZ_READERS names {bad:?}; the readers are {}", known.join(", "));
    }
    names.contains(&name)
}

fn target(name: &str) -> &'static Target {
    TARGETS.iter().chain([&PLANTED]).find(|t| t.name == name).unwrap_or_else(|| panic!("no fuzz target {name}"))
}

// ------------------------------------------------------------------------ worker process

/// The child side: run the cases the parent asks for. Run directly (without
/// `SOLIDTEX_FUZZ_WORKER`) it runs every selected reader in this process instead, which
/// catches panics but not aborts.
#[test]
#[ignore = "run by the fuzz tests in a child process"]
fn worker() {
    let mut out = std::io::stdout();
    let seconds = env_number("SOLIDTEX_FUZZ_SECONDS");
    let Ok(name) = std::env::var("SOLIDTEX_FUZZ_WORKER") else {
        for target in TARGETS.iter().filter(|t| selected(t.name)) {
            let dir = scratch();
            let (saved, to) = (failure_folder(), case_count());
            run_cases(&Job { target, from: 0, to, seconds, dir: dir.path(), saved: &saved, hang: HANG }, &mut out);
        }
        return;
    };
    let path = |name: &str| PathBuf::from(std::env::var(name).unwrap_or_else(|_| panic!("{name} is set")));
    let (dir, saved) = (path("SOLIDTEX_FUZZ_DIR"), path("SOLIDTEX_FUZZ_SAVED"));
    let from = env_number("SOLIDTEX_FUZZ_FROM").expect("SOLIDTEX_FUZZ_FROM is set");
    let to = env_number("SOLIDTEX_FUZZ_TO").expect("SOLIDTEX_FUZZ_TO is set");
    run_cases(&Job { target: target(&name), from, to, seconds, dir: &dir, saved: &saved, hang: HANG }, &mut out);
}

/// What the parent learns from one worker process.
#[derive(Default)]
struct Report {
    /// Cases run (including one that crashed or hung).
    executed: u64,
    /// Cases that read without error.
    fine: u64,
    /// One line per failing case shown.
    failures: Vec<String>,
    /// Further failures of kinds already shown.
    repeats: u64,
    /// The case the process died or hung on, and how.
    crash: Option<(Option<u64>, String)>,
}

/// The parent's view of a running worker, shared with the thread reading its output.
#[derive(Default)]
struct Progress {
    /// The case being run, plus one (0: none yet).
    case: AtomicU64,
    /// Milliseconds since the worker started at the last `case` line.
    tick: AtomicU64,
    /// Cases read without error so far.
    fine: AtomicU64,
    /// The count of its `done` line.
    done: Mutex<Option<u64>>,
    failures: Mutex<Vec<String>>,
    repeats: AtomicU64,
}

/// This test binary; on Linux through `/proc`, which still reaches it when a rebuild has
/// replaced the file meanwhile.
fn own_executable() -> PathBuf {
    let linked = PathBuf::from(format!("/proc/{}/exe", std::process::id()));
    if linked.exists() { linked } else { std::env::current_exe().unwrap() }
}

/// The test binary running the worker test, under the address-space limit where `sh`
/// can set one.
fn worker_command() -> Command {
    let exe = own_executable();
    let args = ["fuzz::worker", "--exact", "--ignored", "--nocapture", "--test-threads", "1", "-q"];
    let mut cmd = match cfg!(unix) {
        true => {
            let mut cmd = Command::new("sh");
            cmd.arg("-c").arg(format!("ulimit -v {MEMORY_KIB} 2>/dev/null; exec \"$0\" \"$@\"")).arg(exe);
            cmd
        }
        false => Command::new(exe),
    };
    cmd.args(args).stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    cmd
}

/// One worker's assignment.
struct Job<'a> {
    target: &'a Target,
    from: u64,
    to: u64,
    /// Stop after this many seconds.
    seconds: Option<f64>,
    /// Scratch folder for seeds and the case.
    dir: &'a Path,
    /// Where reproducers go.
    saved: &'a Path,
    /// A case running longer than this is a hang.
    hang: Duration,
}

/// Run a job in a worker process and watch it.
fn run_worker(job: &Job) -> Report {
    let mut cmd = worker_command();
    cmd.env("SOLIDTEX_FUZZ_WORKER", job.target.name)
        .env("SOLIDTEX_FUZZ_FROM", job.from.to_string())
        .env("SOLIDTEX_FUZZ_TO", job.to.to_string())
        .env("SOLIDTEX_FUZZ_DIR", job.dir)
        .env("SOLIDTEX_FUZZ_SAVED", job.saved)
        .env_remove("SOLIDTEX_FUZZ_SECONDS");
    if let Some(s) = job.seconds {
        cmd.env("SOLIDTEX_FUZZ_SECONDS", s.to_string());
    }
    let mut child = cmd.spawn().expect("the fuzz worker starts");
    let started = Instant::now();
    let progress = Arc::new(Progress::default());
    let stdout = child.stdout.take().unwrap();
    let reading = std::thread::spawn({
        let progress = progress.clone();
        move || read_worker_output(stdout, &progress, started)
    });
    let mut stderr = child.stderr.take().unwrap();
    let errors = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stderr.read_to_string(&mut text);
        text
    });
    let (status, hung) = watch(&mut child, &progress, started, job.hang);
    reading.join().unwrap();
    let stderr = errors.join().unwrap();
    let case = progress.case.load(Ordering::SeqCst).checked_sub(1);
    let mut report = Report {
        fine: progress.fine.load(Ordering::SeqCst),
        repeats: progress.repeats.load(Ordering::SeqCst),
        failures: std::mem::take(&mut *progress.failures.lock().unwrap()),
        ..Report::default()
    };
    let done = *progress.done.lock().unwrap();
    match (done, hung) {
        (Some(n), false) if status.success() => report.executed = n,
        _ => {
            report.executed = case.map_or(0, |c| c + 1 - job.from);
            let how = match hung {
                true => format!("hang: no progress for {} s, killed", job.hang.as_secs_f64()),
                false => format!("crash ({status}): {}", tail(&stderr)),
            };
            report.crash = Some((case, how));
        }
    }
    report
}

/// Wait for the worker to exit, killing it when one case takes longer than `hang`.
fn watch(child: &mut std::process::Child, progress: &Progress, started: Instant, hang: Duration) -> (ExitStatus, bool) {
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return (status, false);
        }
        let since = started.elapsed().saturating_sub(Duration::from_millis(progress.tick.load(Ordering::SeqCst)));
        if since > hang {
            let _ = child.kill();
            return (child.wait().unwrap(), true);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn read_worker_output(stdout: impl Read, progress: &Progress, started: Instant) {
    for line in BufReader::new(stdout).lines() {
        let Ok(line) = line else { break };
        let Some(rest) = line.strip_prefix(TAG).map(str::trim_start) else { continue };
        if let Some([n, fine]) = rest.strip_prefix("case ").and_then(numbers) {
            progress.case.store(n + 1, Ordering::SeqCst);
            progress.fine.store(fine, Ordering::SeqCst);
            progress.tick.store(started.elapsed().as_millis() as u64, Ordering::SeqCst);
        } else if let Some([n, fine]) = rest.strip_prefix("done ").and_then(numbers) {
            progress.fine.store(fine, Ordering::SeqCst);
            *progress.done.lock().unwrap() = Some(n);
        } else if let Some(failure) = rest.strip_prefix("fail ") {
            progress.failures.lock().unwrap().push(failure.to_string());
        } else if rest.starts_with("again ") {
            progress.repeats.fetch_add(1, Ordering::SeqCst);
        }
    }
}

/// Two numbers separated by a space.
fn numbers(text: &str) -> Option<[u64; 2]> {
    let (a, b) = text.split_once(' ')?;
    Some([a.parse().ok()?, b.parse().ok()?])
}

/// The last lines of a worker's standard error (where an abort's message goes).
fn tail(stderr: &str) -> String {
    let lines: Vec<&str> = stderr.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
    lines[lines.len().saturating_sub(4)..].join(" | ")
}

/// What the runs of one reader found.
struct Outcome {
    /// Cases run.
    executed: u64,
    /// Cases that read without error.
    fine: u64,
    /// One line per failing case shown: its number, the reproducer and the problem.
    failures: Vec<String>,
    /// Further failures of kinds already shown.
    repeats: u64,
}

/// Run cases `0..cases` of `target` in workers, restarting after each crash or hang,
/// within `seconds` if given; reproducers go to `saved`.
fn run_all(target: &Target, cases: u64, seconds: Option<f64>, hang: Duration, saved: &Path) -> Outcome {
    let dir = scratch();
    let started = Instant::now();
    let mut found = Outcome { executed: 0, fine: 0, failures: Vec::new(), repeats: 0 };
    let mut from = 0;
    while from < cases {
        let left = seconds.map(|s| s - started.elapsed().as_secs_f64());
        if left.is_some_and(|s| s <= 0.0) {
            break;
        }
        let job = Job { target, from, to: cases, seconds: left, dir: dir.path(), saved, hang };
        let report = run_worker(&job);
        found.executed += report.executed;
        found.fine += report.fine;
        found.repeats += report.repeats;
        found.failures.extend(report.failures);
        let Some((case, how)) = report.crash else { break };
        let Some(case) = case else {
            found.failures.push(format!("the worker failed before its first case: {how}"));
            break;
        };
        let copy = save_reproducer(target, case, &dir.path().join(target.case), saved);
        found.failures.push(format!("{case} {}\t{how}", copy.display()));
        from = case + 1;
    }
    found
}

/// A scratch folder for seeds and cases: in memory (`/dev/shm`) where there is one, since
/// every case is written to a file.
fn scratch() -> tempfile::TempDir {
    let memory = Path::new("/dev/shm");
    match memory.is_dir() {
        true => tempfile::tempdir_in(memory).or_else(|_| tempfile::tempdir()).unwrap(),
        false => tempfile::tempdir().unwrap(),
    }
}

/// Where failing inputs are kept.
fn failure_folder() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-failures")
}

/// Fuzz one reader, print its executions, and fail with every failure found.
fn fuzz(name: &str) {
    if !selected(name) {
        println!("fuzz {name}: skipped (not in SOLIDTEX_FUZZ_READERS)");
        return;
    }
    let started = Instant::now();
    let seconds = env_number::<f64>("SOLIDTEX_FUZZ_SECONDS");
    let found = run_all(target(name), case_count(), seconds, HANG, &failure_folder());
    let secs = started.elapsed().as_secs_f64();
    let failed = found.failures.len() as u64 + found.repeats;
    println!(
        "fuzz {name}: {} cases ({} read without error) in {secs:.1} s ({:.0}/s), {failed} failure(s)",
        found.executed,
        found.fine,
        found.executed as f64 / secs.max(1e-9),
    );
    let mut summary: Vec<String> = found.failures.iter().map(|f| format!("  {name} case {f}")).collect();
    if found.repeats > 0 {
        summary.push(format!("  and {} more of the same kinds (not saved)", found.repeats));
    }
    assert!(failed == 0, "{failed} failure(s) in the {name} reader:\n{}", summary.join("\n"));
}

#[test]
fn obj_reader_survives_mutated_files() {
    fuzz("obj");
}

#[test]
fn binary_stl_reader_survives_mutated_files() {
    fuzz("stl_binary");
}

#[test]
fn ascii_stl_reader_survives_mutated_files() {
    fuzz("stl_ascii");
}

#[test]
fn ascii_ply_reader_survives_mutated_files() {
    fuzz("ply_ascii");
}

#[test]
fn binary_ply_reader_survives_mutated_files() {
    fuzz("ply_binary");
}

#[test]
fn guided_cube_reader_survives_mutated_files() {
    fuzz("guided_cube");
}

#[test]
fn guided_brick_cache_reader_survives_mutated_files() {
    fuzz("guided_bricks");
}

#[test]
fn ply_skin_reader_survives_mutated_files() {
    fuzz("ply_skin");
}

#[test]
fn nrrd_reader_survives_mutated_files() {
    fuzz("nrrd");
}

#[test]
fn vol_reader_survives_mutated_files() {
    fuzz("vol");
}

#[test]
fn exr_reader_survives_mutated_files() {
    fuzz("exr");
}

#[test]
fn vdb_reader_survives_mutated_files() {
    fuzz("vdb");
}

#[test]
fn dds_reader_survives_mutated_files() {
    fuzz("dds");
}

#[test]
fn png_atlas_reader_survives_mutated_files() {
    fuzz("png_atlas");
}

#[test]
fn png_stack_reader_survives_mutated_files() {
    fuzz("png_stack");
}

#[test]
fn manifest_reader_survives_mutated_files() {
    fuzz("manifest");
}

#[test]
fn fill_spec_reader_survives_mutated_files() {
    fuzz("fill_spec");
}

#[test]
fn lst_reader_survives_mutated_files() {
    fuzz("lst");
}

#[test]
fn snapshot_reader_survives_mutated_files() {
    fuzz("snapshot");
}

#[test]
fn snapshot_check_survives_mutated_files() {
    fuzz("snapshot_check");
}

// ----------------------------------------------------------------- the harness itself

/// A reader with every kind of failure planted, by case number: 3 panics, 5 aborts,
/// 7 hangs, 9 returns an error that does not name the file.
const PLANTED: Target = file("planted", "case.txt", |_| vec![text("seed")], planted_read);

fn planted_read(path: &Path) -> solidtex::Result<()> {
    match CASE.load(Ordering::SeqCst) {
        3 => panic!("planted panic"),
        5 => std::process::abort(),
        7 => std::thread::sleep(Duration::from_secs(60)),
        9 => return Err(solidtex::Error::invalid("planted error")),
        10 => return Err(solidtex::Error::file(path, "an error naming the file is fine")),
        _ => {}
    }
    Ok(())
}

#[test]
fn the_harness_reports_panics_aborts_hangs_and_nameless_errors() {
    let saved = tempfile::tempdir().unwrap();
    let found = run_all(&PLANTED, 12, None, Duration::from_secs(2), saved.path());
    assert_eq!(found.executed, 12, "{:?}", found.failures);
    let cases: Vec<&str> = found.failures.iter().map(|f| f.split(' ').next().unwrap()).collect();
    assert_eq!(cases, ["3", "5", "7", "9"], "{:?}", found.failures);
    for (failure, what) in found.failures.iter().zip(["planted panic", "crash", "hang", "does not name the file"]) {
        assert!(failure.contains(what), "{failure:?} does not say {what:?}");
    }
    for case in [3, 5, 7, 9] {
        assert!(saved.path().join(format!("planted-{case}.txt")).is_file(), "no reproducer for case {case}");
    }
}

#[test]
fn mutations_are_deterministic_and_change_the_seed() {
    let target = target("nrrd");
    let seeds = vec![vec![(String::new(), b"NRRD0004\nsizes: 4 5 6\n\n0123456789".to_vec())]];
    let case = |n| make_case(target, &seeds, &mut case_rng(1, "nrrd", n));
    assert_eq!(case(7), case(7), "a case depends only on the seed, the reader and its number");
    let changed = (0..200).filter(|n| case(*n) != seeds[0]).count();
    assert!(changed > 180, "only {changed} of 200 cases differ from the seed");
}

#[test]
fn text_numbers_replace_whole_runs() {
    assert_eq!(number_runs(b"sizes: 4 -0.8 1e-3 x9"), [(7, 8), (9, 13), (14, 18), (20, 21)]);
    let mut rng = Pcg64::seed_from_u64(3);
    for _ in 0..50 {
        let mut bytes = b"size = 64".to_vec();
        text_number(&mut rng, &mut bytes);
        let tail = String::from_utf8(bytes[7..].to_vec()).unwrap();
        assert!(TEXT_NUMBERS.contains(&tail.as_str()), "{tail:?}");
    }
}

#[test]
fn png_checksums_are_recomputed() {
    let dir = tempfile::tempdir().unwrap();
    let files = written(dir.path(), "a.png", |p| io::write_volume(p, &random_volume([2, 2, 2], Channel::rgb(), 1)));
    let mut bytes = files[0].1.clone();
    bytes[16] ^= 0x40; // the IHDR width: the stored CRC no longer matches
    let broken = bytes.clone();
    fix_png_crcs(&mut bytes);
    assert_ne!(bytes, broken);
    assert_eq!(crc32(b"IEND"), 0xae42_6082);
}

#[test]
fn a_reader_error_must_name_the_file() {
    let path = Path::new("/tmp/x/case.obj");
    assert_eq!(error_problem("/tmp/x/case.obj: line 3: bad", path), None);
    assert!(error_problem("line 3: bad", path).unwrap().contains("does not name the file"));
    assert!(error_problem(" ", path).unwrap().contains("empty"));
}

// ------------------------------------------------------------------ regression tests

/// `snapshot --check` against a snapshot cut short after its first statistics line
/// fails with exit code 1 and names the snapshot, and writes nothing.
#[test]
fn checking_against_a_truncated_snapshot_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let volume = at(d, "v.exr");
    io::write_volume(Path::new(&volume), &random_volume([6, 5, 4], Channel::rgb(), 5)).unwrap();
    let text = solidtex::snapshot::Snapshot::of(&random_volume([6, 5, 4], Channel::rgb(), 5)).to_text();
    let cut = text.find("stat G").expect("a stat line for G");
    std::fs::write(d.join("short.snap"), &text[..cut]).unwrap();
    let before = listing(d);
    let out = solidtex(&["snapshot", &volume, "--check", &at(d, "short.snap"), "--tolerance", "0.01"]);
    assert_fails(&out, &["short.snap"]);
    assert_eq!(listing(d), before, "the check left files behind");
}
