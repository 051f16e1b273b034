//! Where a point of a filled model takes its texture: the tet holding it or, for a point of
//! the input solid that no tet holds (the tets approximate the input surface to within a
//! fraction of a tet edge), the tet of the nearest boundary face, its affine map extended
//! past the face (barycentric weights not clamped).
//!
//! ```text
//!   p --TetGrid--> tet holding p ? --yes--> (tet, weights ≥ 0)
//!                                  --no---> nearest boundary face (the cell's list of faces
//!                                           that can be nearest, else rings of cells)
//!                                           -> (its tet, weights)
//! ```
//!
//! Extending the nearest face's map keeps the texture continuous across the face; where the
//! nearest face changes from one tet to its neighbour, the two maps agree on their shared
//! edge and differ away from it by the distance times the difference of their gradients,
//! so a point a fraction of an edge outside sees a step of a fraction of that difference.

use super::tets::{FACES, NONE, TetGrid, TetMesh, cell_in};
use crate::mesh::closest_on_triangle;
use glam::{Mat3, Vec3};
use std::sync::OnceLock;

/// A point's tet and its barycentric weights there (some negative outside the tets).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Location {
    /// The tet whose patches colour the point.
    pub tet: u32,
    /// Barycentric weights of the point in the tet (they sum to 1).
    pub weights: [f32; 4],
    /// Whether the tet holds the point.
    pub inside: bool,
}

/// The tets and boundary faces of a mesh, binned for point queries.
#[derive(Debug, Clone)]
pub struct Locator {
    tets: TetGrid,
    /// Per tet, its first corner and the inverse of its edge matrix.
    frames: Vec<(Vec3, Mat3)>,
    cells: Cells,
    faces: Vec<Face>,
    /// Per cell, the faces whose boxes meet it.
    listed: Lists,
    /// Per cell, its number among the cells that list a face (`NONE` for the others).
    busy: Vec<u32>,
    /// Per cell that lists a face, the faces that can be nearest to a point of the cell,
    /// made when first asked for.
    near: Vec<OnceLock<Near>>,
}

/// The nearest face found so far: squared distance, its tet, the face.
type Best = (f32, u32, u32);

/// The faces that can be nearest to a point of a cell: (squared distance from the cell to
/// the face's box, face), nearest boxes first.
type Near = Box<[(f32, u32)]>;

/// The grid shared with the tets': corner, cell side, cells per axis.
#[derive(Debug, Clone, Copy)]
struct Cells {
    lo: Vec3,
    side: f32,
    dims: [usize; 3],
}

impl Cells {
    /// The cell holding `p`, clamped into the grid.
    fn of(&self, p: Vec3) -> [usize; 3] {
        cell_in(self.lo, self.side, self.dims, p)
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// The box of cell `c`.
    fn bounds(&self, [x, y, z]: [usize; 3]) -> (Vec3, Vec3) {
        let lo = self.lo + Vec3::new(x as f32, y as f32, z as f32) * self.side;
        (lo, lo + self.side)
    }

    /// Whether `p` lies in the grid's box.
    fn holds(&self, p: Vec3) -> bool {
        let hi = self.lo + Vec3::new(self.dims[0] as f32, self.dims[1] as f32, self.dims[2] as f32) * self.side;
        p.cmpge(self.lo).all() && p.cmplt(hi).all()
    }

    /// The cells within `r` of `c` (Chebyshev), clipped to the grid.
    fn around(&self, c: [usize; 3], r: usize) -> impl Iterator<Item = [usize; 3]> + '_ {
        let lo = c.map(|v| v.saturating_sub(r));
        let hi = [0, 1, 2].map(|k| (c[k] + r).min(self.dims[k] - 1));
        (lo[2]..=hi[2]).flat_map(move |z| (lo[1]..=hi[1]).flat_map(move |y| (lo[0]..=hi[0]).map(move |x| [x, y, z])))
    }
}

/// Lists of numbers per cell: `items[offsets[i]..offsets[i + 1]]`.
#[derive(Debug, Clone)]
struct Lists {
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl Lists {
    /// From (cell, item) pairs sorted by cell, over `cells` cells.
    fn new(pairs: &[(u32, u32)], cells: usize) -> Lists {
        let mut offsets = vec![0u32; cells + 1];
        pairs.iter().for_each(|p| offsets[p.0 as usize + 1] += 1);
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        Lists { offsets, items: pairs.iter().map(|p| p.1).collect() }
    }

    fn of(&self, i: usize) -> &[u32] {
        &self.items[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// A boundary face: its tet, corners and bounding box.
#[derive(Debug, Clone)]
struct Face {
    tet: u32,
    corners: [Vec3; 3],
    lo: Vec3,
    hi: Vec3,
}

impl Face {
    /// The squared distance from `p` to the face's box.
    fn box_distance(&self, p: Vec3) -> f32 {
        (self.lo - p).max(p - self.hi).max(Vec3::ZERO).length_squared()
    }
}

impl Locator {
    /// The locator of `mesh`: its tets on a grid of about one tet per cell (coarser when
    /// long tets would need too many entries), its boundary faces on the same cells, and
    /// for each cell a face passes through, the faces that can be nearest to its points.
    pub fn new(mesh: &TetMesh) -> Locator {
        let tets = [128, 32, 8, 1]
            .into_iter()
            .find_map(|cells| TetGrid::at_most(mesh, cells).ok())
            .unwrap_or_else(|| TetGrid::at_most(mesh, 1).expect("one cell holds every tet once"));
        let (lo, side, dims) = tets.layout();
        let cells = Cells { lo, side, dims };
        let frames = (0..mesh.tets.len())
            .map(|t| {
                let c = mesh.corners(t);
                (c[0], Mat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]).inverse())
            })
            .collect();
        let faces = boundary_faces(mesh);
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (i, f) in faces.iter().enumerate() {
            let (a, b) = (cells.of(f.lo), cells.of(f.hi));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        pairs.push((cells.index([x, y, z]) as u32, i as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let listed = Lists::new(&pairs, cells.dims.iter().product());
        let mut count = 0u32;
        let busy: Vec<u32> = (0..cells.dims.iter().product())
            .map(|i| {
                if listed.of(i).is_empty() {
                    return NONE;
                }
                count += 1;
                count - 1
            })
            .collect();
        let near = (0..count).map(|_| OnceLock::new()).collect();
        Locator { tets, frames, cells, faces, listed, busy, near }
    }

    /// The faces of cell `i` as near to some point of it as the nearest face: those whose
    /// boxes lie within `u` of the cell, `u` the least over the faces the cell lists of
    /// their farthest distance from its corners (the distance to a triangle is convex, so
    /// over the box it peaks at a corner). Empty for a cell that lists no face.
    fn near_cell(&self, i: usize) -> Near {
        let [nx, ny, _] = self.cells.dims;
        let c = [i % nx, (i / nx) % ny, i / (nx * ny)];
        let (lo, hi) = self.cells.bounds(c);
        let corners = (0..8).map(|k| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][k >> 2]));
        let farthest = |f: u32| {
            let f = &self.faces[f as usize];
            corners.clone().map(|q| q.distance(closest_on_triangle(q, f.corners))).fold(0.0, f32::max)
        };
        let u = self.listed.of(i).iter().map(|&f| farthest(f)).fold(f32::INFINITY, f32::min);
        let (a, b) = (self.cells.of(lo - u), self.cells.of(hi + u));
        let cells = (a[2]..=b[2]).flat_map(|z| (a[1]..=b[1]).flat_map(move |y| (a[0]..=b[0]).map(move |x| [x, y, z])));
        let mut near: Vec<(f32, u32)> = cells
            .flat_map(|cell| self.listed.of(self.cells.index(cell)).iter().copied())
            .map(|f| {
                let face = &self.faces[f as usize];
                ((face.lo - hi).max(lo - face.hi).max(Vec3::ZERO).length_squared(), f)
            })
            .filter(|&(gap, _)| gap.sqrt() <= u * (1.0 + 1e-5) + 1e-6)
            .collect();
        // nearest boxes first, so that a query stops once the boxes left are farther than
        // the best face found
        near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        near.dedup();
        near.into()
    }

    /// The barycentric weights of `p` in tet `t` (as [`TetMesh::barycentric`] gives them).
    fn weights(&self, t: u32, p: Vec3) -> [f32; 4] {
        let (origin, inverse) = self.frames[t as usize];
        let l = inverse * (p - origin);
        [1.0 - l.x - l.y - l.z, l.x, l.y, l.z]
    }

    /// Where `p` takes its texture; `None` for a point that is not finite or a mesh
    /// without tets.
    pub fn locate(&self, p: Vec3) -> Option<Location> {
        self.locate_near(p, &mut None)
    }

    /// [`Locator::locate`] for a point near the last one located with the same `hint`: the
    /// search for the nearest boundary face starts from the face found then (the answer is
    /// the same; the search stops sooner), and `hint` keeps the face found now.
    pub fn locate_near(&self, p: Vec3, hint: &mut Option<u32>) -> Option<Location> {
        if !p.is_finite() {
            return None;
        }
        for &t in self.tets.candidates(p) {
            let weights = self.weights(t, p);
            if weights.iter().all(|w| *w >= -1e-5) {
                return Some(Location { tet: t, weights, inside: true });
            }
        }
        let mut best = None;
        if let Some(f) = hint.filter(|&f| (f as usize) < self.faces.len()) {
            self.nearest_of(&[f], p, &mut best);
        }
        let (_, tet, face) = self.nearest_face(p, best)?;
        *hint = Some(face);
        Some(Location { tet, weights: self.weights(tet, p), inside: false })
    }

    /// The boundary face nearest `p` (the lowest tet among equals), searched from `best`:
    /// (squared distance, tet, face).
    fn nearest_face(&self, p: Vec3, mut best: Option<Best>) -> Option<Best> {
        let cell = self.cells.index(self.cells.of(p));
        if self.cells.holds(p) && self.busy[cell] != NONE {
            let near = self.near[self.busy[cell] as usize].get_or_init(|| self.near_cell(cell));
            for &(gap, f) in near.iter() {
                if best.is_some_and(|(b, ..)| gap > b) {
                    break;
                }
                self.nearest_of(std::slice::from_ref(&f), p, &mut best);
            }
            return best;
        }
        self.search_rings(p, &mut best);
        best
    }

    /// The nearest face by growing rings of cells around `p` until no cell left can hold a
    /// nearer face (for points far from the faces).
    fn search_rings(&self, p: Vec3, best: &mut Option<Best>) {
        let centre = self.cells.of(p).map(|c| c as i64);
        let dims = self.cells.dims.map(|d| d as i64);
        for r in 0.. {
            let lo = centre.map(|c| c - r);
            let hi = centre.map(|c| c + r);
            for cell in self.cells.around(centre.map(|c| c as usize), r as usize) {
                let ring = cell.iter().zip(centre).any(|(v, c)| (*v as i64 - c).abs() == r);
                if ring {
                    self.nearest_of(self.listed.of(self.cells.index(cell)), p, best);
                }
            }
            // faces not yet seen lie in cells beyond one of the box's sides inside the grid
            let mut bound = f32::INFINITY;
            for k in 0..3 {
                if lo[k] > 0 {
                    bound = bound.min(p[k] - (self.cells.lo[k] + lo[k] as f32 * self.cells.side));
                }
                if hi[k] < dims[k] - 1 {
                    bound = bound.min(self.cells.lo[k] + (hi[k] + 1) as f32 * self.cells.side - p[k]);
                }
            }
            if bound == f32::INFINITY || best.is_some_and(|(d, ..)| d <= bound * bound.abs()) {
                break;
            }
        }
    }

    /// Keeps in `best` the nearer of it and the faces `list` (the lower tet among equals).
    fn nearest_of(&self, list: &[u32], p: Vec3, best: &mut Option<Best>) {
        for &f in list {
            let face = &self.faces[f as usize];
            if best.is_some_and(|(b, ..)| face.box_distance(p) > b) {
                continue;
            }
            let d = p.distance_squared(closest_on_triangle(p, face.corners));
            if best.is_none_or(|(b, t, _)| d < b || (d == b && face.tet < t)) {
                *best = Some((d, face.tet, f));
            }
        }
    }
}

/// The boundary faces of `mesh` with their tets, in tet order.
fn boundary_faces(mesh: &TetMesh) -> Vec<Face> {
    let neighbours = mesh.neighbours();
    let mut faces = Vec::new();
    for (t, tet) in mesh.tets.iter().enumerate() {
        for (k, face) in FACES.iter().enumerate() {
            if neighbours[t][k] == NONE {
                let corners = face.map(|s| mesh.vertices[tet[s] as usize]);
                let (lo, hi) = (corners[0].min(corners[1]).min(corners[2]), corners[0].max(corners[1]).max(corners[2]));
                faces.push(Face { tet: t as u32, corners, lo, hi });
            }
        }
    }
    faces
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    #[test]
    fn points_inside_find_their_tet_and_points_outside_the_nearest_face() {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let locator = Locator::new(&mesh);
        let inside = locator.locate(Vec3::new(0.3, 0.6, 0.45)).unwrap();
        assert!(inside.inside && inside.weights.iter().all(|w| *w >= -1e-5));
        // just above the top face: the tet under it, one weight a little below 0
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut points = vec![Vec3::new(0.4, 1.02, 0.6), Vec3::new(-0.05, 0.5, 0.5), Vec3::new(1.3, 1.3, 1.3)];
        // just outside each side, and anywhere around
        for _ in 0..300 {
            let (a, b, side) = (next(), next(), (next() * 6.0) as usize % 6);
            let out = if side % 2 == 0 { -0.03 * next() } else { 1.0 + 0.03 * next() };
            let mut q = [a, b, a];
            q[side / 2] = out;
            points.push(Vec3::from(q));
            points.push(Vec3::new(next(), next(), next()) * 2.0 - 0.5);
        }
        for p in points.into_iter().filter(|p| !(p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all())) {
            let l = locator.locate(p).unwrap();
            assert!(!l.inside, "{p}");
            let c = mesh.corners(l.tet as usize);
            let near =
                FACES.iter().map(|f| p.distance(closest_on_triangle(p, f.map(|s| c[s])))).fold(f32::INFINITY, f32::min);
            // no tet of the mesh comes nearer
            let nearest = (0..mesh.tets.len())
                .flat_map(|t| {
                    let c = mesh.corners(t);
                    FACES.map(|f| p.distance(closest_on_triangle(p, f.map(|s| c[s]))))
                })
                .fold(f32::INFINITY, f32::min);
            assert!((near - nearest).abs() < 1e-6, "{p}: {near} against {nearest}");
            let back: Vec3 = (0..4).map(|k| c[k] * l.weights[k]).sum();
            assert!(back.distance(p) < 1e-5, "the weights extend the tet's map to {p}");
        }
        assert_eq!(locator.locate(Vec3::NAN), None);
    }

    /// A walk around the lattice with a hint finds what each point alone finds, whether the
    /// hint is the last point's face, a far face, no face of the mesh or none.
    #[test]
    fn a_hint_changes_no_answer() {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let locator = Locator::new(&mesh);
        let mut hint = None;
        for i in 0..400 {
            let a = i as f32 * 0.05;
            let p = Vec3::new(0.5 + 0.62 * a.cos(), 0.5 + 0.62 * a.sin(), (i % 23) as f32 / 22.0 * 1.2 - 0.1);
            let alone = locator.locate(p);
            assert_eq!(locator.locate_near(p, &mut hint), alone, "{p}");
            if i % 50 == 0 {
                hint = Some((i / 50) as u32 % locator.faces.len() as u32);
            }
            if i == 125 {
                hint = Some(u32::MAX);
            }
        }
        assert!(hint.is_some(), "points outside leave their face as the hint");
    }
}
