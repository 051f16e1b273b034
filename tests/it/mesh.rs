//! Meshes: loaders on every format, orientation, voxelization accuracy, bad meshes.

use glam::{Affine3A, Vec3};
use solidtex::io::mesh_file::{read_mesh, write_mesh, write_obj, write_ply, write_stl};
use solidtex::mesh::{Coverage, Mesh, voxelize};
use std::f32::consts::PI;
use std::path::{Path, PathBuf};

/// A closed, outward-facing UV sphere: two poles and `rings - 1` circles of `segments`
/// corners; `2 * segments * (rings - 1)` triangles.
fn uv_sphere(center: Vec3, radius: f32, rings: u32, segments: u32) -> Mesh {
    let mut vertices = vec![center + Vec3::Z * radius];
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = 2.0 * PI * j as f32 / segments as f32;
            let dir = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            vertices.push(center + dir * radius);
        }
    }
    vertices.push(center - Vec3::Z * radius);
    let south = vertices.len() as u32 - 1;
    let at = |ring: u32, j: u32| 1 + (ring - 1) * segments + j % segments;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, at(1, j), at(1, j + 1)]);
        for ring in 1..rings - 1 {
            let (u0, u1, l0, l1) = (at(ring, j), at(ring, j + 1), at(ring + 1, j), at(ring + 1, j + 1));
            triangles.extend([[u0, l0, l1], [u0, l1, u1]]);
        }
        triangles.push([south, at(rings - 1, j + 1), at(rings - 1, j)]);
    }
    Mesh::new(vertices, triangles).unwrap()
}

/// The sphere of the accuracy tests: radius 10 voxels, 2016 triangles, off the lattice.
fn test_sphere() -> Mesh {
    uv_sphere(Vec3::new(16.2, 15.9, 16.1), 10.0, 22, 48)
}

/// A mesh writer.
type Writer = fn(&Path, &Mesh) -> solidtex::Result<()>;

fn solid_voxels(cover: &Coverage) -> usize {
    cover.alpha.iter().filter(|&&a| a >= 0.5).count()
}

fn message<T: std::fmt::Debug>(result: solidtex::Result<T>) -> String {
    result.unwrap_err().to_string()
}

#[test]
fn a_sphere_of_radius_10_covers_its_volume_within_2_percent() {
    let sphere = test_sphere();
    assert_eq!(sphere.triangles.len(), 2016);
    assert_eq!(sphere.boundary_edges(), 0);
    let cover = voxelize(&sphere, [32, 32, 32], 4);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 1000.0;
    let error = (cover.volume() - exact).abs() / exact;
    assert!(error < 0.02, "covered {} voxels, a ball holds {exact:.1}", cover.volume());
    assert_eq!((cover.origin, cover.dims), ([6, 5, 6], [21, 21, 21]));
    assert!(cover.alpha.iter().all(|a| (0.0..=1.0).contains(a)));
}

#[test]
fn obj_ply_and_stl_round_trips_give_identical_voxels() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = test_sphere();
    let expected = voxelize(&sphere, [32, 32, 32], 2);
    let writers: [(&str, Writer); 4] =
        [("s.obj", write_obj), ("s.ply", write_ply), ("s.stl", write_stl), ("S.PLY", write_mesh)];
    for (name, write) in writers {
        let path = dir.path().join(name);
        write(&path, &sphere).unwrap();
        let back = read_mesh(&path).unwrap();
        assert_eq!(back.triangles.len(), sphere.triangles.len(), "{name}");
        assert_eq!(back.boundary_edges(), 0, "{name}");
        assert_eq!(voxelize(&back, [32, 32, 32], 2), expected, "{name}");
    }
}

#[test]
fn ascii_stl_and_binary_ply_read_like_the_obj() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = uv_sphere(Vec3::splat(8.3), 5.0, 8, 12);
    let expected = voxelize(&sphere, [16, 16, 16], 2);

    let mut stl = String::from("solid ball\n");
    for t in &sphere.triangles {
        stl.push_str("  facet normal 0 0 0\n    outer loop\n");
        for &i in t {
            let v = sphere.vertices[i as usize];
            stl.push_str(&format!("      vertex {:e} {} {}\n", v.x, v.y, v.z));
        }
        stl.push_str("    endloop\n  endfacet\n");
    }
    stl.push_str("endsolid ball\n");
    let path = dir.path().join("ascii.StL");
    std::fs::write(&path, stl).unwrap();
    assert_eq!(voxelize(&read_mesh(&path).unwrap(), [16, 16, 16], 2), expected);

    // Doubles, an extra property to skip, an edge element to skip, and quads split again.
    let mut ply = format!(
        "ply\r\nformat binary_little_endian 1.0\r\ncomment test\r\nelement vertex {}\r\nproperty double x\r\n\
         property double y\r\nproperty double z\r\nproperty uchar red\r\nelement face {}\r\n\
         property list uchar int vertex_indices\r\nproperty float quality\r\nelement edge 1\r\n\
         property int vertex1\r\nproperty int vertex2\r\nend_header\r\n",
        sphere.vertices.len(),
        sphere.triangles.len()
    )
    .into_bytes();
    for v in &sphere.vertices {
        for x in v.to_array() {
            ply.extend_from_slice(&f64::from(x).to_le_bytes());
        }
        ply.push(200);
    }
    for t in &sphere.triangles {
        ply.push(3);
        for &i in t {
            ply.extend_from_slice(&(i as i32).to_le_bytes());
        }
        ply.extend_from_slice(&0.5f32.to_le_bytes());
    }
    ply.extend_from_slice(&[0, 0, 0, 0, 1, 0, 0, 0]);
    let path = dir.path().join("binary.ply");
    std::fs::write(&path, ply).unwrap();
    assert_eq!(voxelize(&read_mesh(&path).unwrap(), [16, 16, 16], 2), expected);
}

#[test]
fn obj_quads_are_fan_triangulated_and_negative_indices_work() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cube.obj");
    let obj = "# unit cube from 1 to 3\nv 1 1 1\nv 3 1 1\nv 3 3 1\nv 1 3 1\nv 1 1 3\nv 3 1 3\nv 3 3 3\nv 1 3 3\n\
               vt 0 0\nvn 0 0 1\ng cube\nf 1//1 4//1 3//1 2//1\nf 5/1 6/1 7/1 8/1 # top\nf 1 2 6 5\n\
               f 2 3 7 6\nf 3 4 8 7\nf -8 -4 -1 -5\n";
    std::fs::write(&path, obj).unwrap();
    let cube = read_mesh(&path).unwrap();
    assert_eq!((cube.triangles.len(), cube.boundary_edges()), (12, 0));
    assert!((cube.signed_volume() - 8.0).abs() < 1e-5);
    let cover = voxelize(&cube, [4, 4, 4], 3);
    assert_eq!((cover.origin, cover.dims, cover.volume()), ([1; 3], [2; 3], 8.0));
}

#[test]
fn an_inverted_mesh_oriented_gives_the_original_voxels() {
    let sphere = test_sphere();
    let flipped: Vec<[u32; 3]> = sphere.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
    let inverted = Mesh::new(sphere.vertices.clone(), flipped).unwrap();
    assert!(inverted.signed_volume() < 0.0);
    let fixed = inverted.oriented();
    assert!(fixed.signed_volume() > 0.0);
    assert_eq!(fixed, sphere);
    assert_eq!(voxelize(&fixed, [32, 32, 32], 2), voxelize(&sphere, [32, 32, 32], 2));
    let mirrored = sphere.transformed(Affine3A::from_scale(Vec3::new(1.0, -1.0, 1.0)));
    assert!(mirrored.signed_volume() > 0.0);
}

#[test]
fn boundary_edges_count_the_holes_of_an_open_sphere() {
    let sphere = test_sphere();
    assert_eq!(sphere.boundary_edges(), 0);
    let gone = [0usize, 500, 1000];
    let kept = sphere.triangles.iter().enumerate().filter(|(i, _)| !gone.contains(i)).map(|(_, t)| *t).collect();
    let open = Mesh::new(sphere.vertices.clone(), kept).unwrap();
    assert_eq!(open.boundary_edges(), 9);
    let inside = Vec3::new(16.2, 15.9, 16.1);
    assert!(open.contains(inside) && open.winding_number(inside) < 1.0);
}

#[test]
fn bad_meshes_are_refused_with_the_culprit_named() {
    let tri = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
    let mut nan = tri.clone();
    nan[2].z = f32::NAN;
    let err = message(Mesh::new(nan, vec![[0, 1, 2]]));
    assert!(err.contains("vertex 2") && err.contains("NaN") && err.contains("finite"), "{err}");
    let err = message(Mesh::new(Vec::new(), Vec::new()));
    assert!(err.contains("no triangles"), "{err}");
    let err = message(Mesh::new(tri, vec![[0, 1, 7]]));
    assert!(err.contains("index 7") && err.contains("0..=2"), "{err}");
}

#[test]
fn bad_mesh_files_are_refused_with_the_file_and_problem_named() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, body: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, body).unwrap();
        path
    };
    let cases: Vec<(PathBuf, Vec<&str>)> = vec![
        (file("empty.obj", b"# nothing\n"), vec!["empty.obj", "no triangles"]),
        (file("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), vec!["range.obj", "index 8", "0..=2"]),
        (file("nan.obj", b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"), vec!["nan.obj", "vertex 1", "NaN"]),
        (file("word.obj", b"v 0 0 zero\n"), vec!["word.obj", "line 1", "\"zero\""]),
        (file("shape.xyz", b"v 0 0 0\n"), vec!["shape.xyz", ".xyz", ".obj, .stl, .ply"]),
        (file("header.ply", b"ply\nformat ascii 1.0\nelement vertex many\nend_header\n"), vec!["header.ply", "line 3"]),
        (file("big.ply", b"ply\nformat binary_big_endian 1.0\nend_header\n"), vec!["line 2", "binary_little_endian"]),
    ];
    for (path, needles) in cases {
        let err = message(read_mesh(&path));
        for n in needles {
            assert!(err.contains(n), "{err:?} does not mention {n:?}");
        }
    }
    let stl = dir.path().join("cut.stl");
    write_stl(&stl, &test_sphere()).unwrap();
    let bytes = std::fs::read(&stl).unwrap();
    std::fs::write(&stl, &bytes[..bytes.len() - 30]).unwrap();
    let err = message(read_mesh(&stl));
    let size = (bytes.len() - 30).to_string();
    for n in ["cut.stl", "2016 triangles", size.as_str(), "bytes"] {
        assert!(err.contains(n), "{err:?} does not mention {n:?}");
    }
}

/// The shared sample meshes, or `None` (with a note) when the folder is absent.
pub fn shared_meshes() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/meshes");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipped: ../shared/data/meshes not present");
        None
    }
}

#[test]
fn the_cgal_sphere_gives_the_same_voxels_from_obj_ply_and_stl() {
    let Some(dir) = shared_meshes() else { return };
    let place = Affine3A::from_scale_rotation_translation(Vec3::splat(20.0), Default::default(), Vec3::splat(16.0));
    let counts: Vec<usize> = ["obj", "ply", "stl"]
        .iter()
        .map(|ext| {
            let mesh = read_mesh(&dir.join(format!("cgal_sphere.{ext}"))).unwrap();
            solid_voxels(&voxelize(&mesh.transformed(place), [32, 32, 32], 2))
        })
        .collect();
    assert!(counts[0] > 3000, "{counts:?}");
    for c in &counts[1..] {
        assert!(c.abs_diff(counts[0]) * 100 <= counts[0], "{counts:?}");
    }
}

#[test]
fn every_shared_mesh_is_closed_and_the_ellipsoid_is_inverted() {
    let Some(dir) = shared_meshes() else { return };
    let mut names: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    for path in &names {
        let mesh = read_mesh(path).unwrap();
        assert_eq!(mesh.boundary_edges(), 0, "{}", path.display());
    }
    let ellipse = read_mesh(&dir.join("cgal_ellipe0.003.obj")).unwrap();
    assert!(ellipse.signed_volume() < 0.0);
    assert!(ellipse.oriented().signed_volume() > 0.0);
    let bunny = read_mesh(&dir.join("libigl_bunny.obj")).unwrap();
    assert_eq!(bunny.triangles.len() + bunny.dropped_degenerate(), 6966);
    assert!(bunny.oriented().signed_volume() > 0.0);
}
