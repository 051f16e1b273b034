//! Conforming the cut lattice to the surface: boundary vertices move to their closest
//! surface points as far as their tets stay well shaped, tets that would be flattened
//! against the surface are given up, the vertices around poor tets are eased, and at the
//! end the given-up tets that leave a slit under the skin come back where they fit.

use super::closest::Surface;
use super::face_samples;
use super::features::Features;
use crate::fill::tets::{FACES, NONE, TetMesh};
use glam::Vec3;
use rayon::prelude::*;

/// The smallest dihedral angle a vertex move may leave in any tet it touches, in degrees.
/// The lattice tets start at 45°; every move keeps every tet at or above this.
pub(super) const MIN_DIHEDRAL: f32 = 12.0;
/// How many rounds of snapping, giving up and easing there are at most.
const ROUNDS: usize = 16;
/// How many times a blocked move is halved before the vertex stays where it is.
const HALVINGS: usize = 4;
/// The corners of tets with a smaller dihedral angle than this (degrees) are eased.
const EASE_BELOW: f32 = 20.0;
/// The interior corners of tets with a smaller dihedral angle than this (degrees) are
/// smoothed at the end (the untouched lattice tets have 45°).
const SMOOTH_BELOW: f32 = 40.0;
/// How many sweeps of smoothing there are.
const SMOOTHING_PASSES: usize = 2;

/// How far from a crease (in lengths of the boundary edge that crosses it) a vertex may be
/// moved onto it.
const CREASE_REACH: f32 = 0.75;

/// A given-up tet comes back at the end if a face it would close lies deeper than this
/// under the surface (in mean edges), see [`Work::restore`].
const RESTORE_DEPTH: f32 = 0.25;
/// Sweeps over the given-up tets that may come back.
const RESTORE_SWEEPS: usize = 3;
/// A given-up tet flatter than this (smallest dihedral angle, degrees) is not eased back.
const REVIVE_FROM: f32 = 3.0;

/// Moves the boundary vertices of `mesh` onto `surface`, gives up the tets that would be
/// flattened, moves vertices onto the creases the boundary cuts across, eases and smooths,
/// brings back given-up tets that close slits, and drops loose tets and unused vertices.
pub(super) fn conform(mesh: &mut TetMesh, surface: &Surface, features: &Features) {
    let mut work = Work::new(mesh);
    for _ in 0..ROUNDS {
        let stuck = work.snap_boundary(surface);
        let blockers = work.blockers(&stuck, surface);
        if !blockers.is_empty() {
            work.give_up(&blockers);
            continue;
        }
        work.relax(surface, &[]);
        if stuck.is_empty() {
            break;
        }
    }
    let on_crease = work.align_creases(surface, features);
    work.relax(surface, &on_crease);
    work.smooth();
    work.restore(surface, RESTORE_DEPTH * crate::fill::mean_edge(work.mesh), &on_crease);
    work.finish();
}

/// The mesh being conformed, which tets are still in, and its topology.
struct Work<'a> {
    mesh: &'a mut TetMesh,
    neighbours: Vec<[u32; 4]>,
    alive: Vec<bool>,
    /// Whether each vertex lies on a boundary face of the live tets.
    boundary: Vec<bool>,
    /// Whether each vertex was snapped the whole way onto the surface (easing keeps a
    /// boundary vertex there).
    on_surface: Vec<bool>,
    /// The live tets around vertex `v`: `around[offsets[v]..offsets[v + 1]]`.
    offsets: Vec<usize>,
    around: Vec<u32>,
}

impl<'a> Work<'a> {
    fn new(mesh: &'a mut TetMesh) -> Work<'a> {
        let neighbours = mesh.neighbours();
        let alive = vec![true; mesh.tets.len()];
        let on_surface = vec![false; mesh.vertices.len()];
        let mut work =
            Work { mesh, neighbours, alive, boundary: Vec::new(), on_surface, offsets: Vec::new(), around: Vec::new() };
        work.refresh();
        work
    }

    /// Recomputes the boundary vertices and the stars from the live tets.
    fn refresh(&mut self) {
        let n = self.mesh.vertices.len();
        self.boundary = vec![false; n];
        self.offsets = vec![0; n + 1];
        for (t, tet) in self.mesh.tets.iter().enumerate().filter(|(t, _)| self.alive[*t]) {
            tet.iter().for_each(|&v| self.offsets[v as usize + 1] += 1);
            for (k, face) in FACES.iter().enumerate() {
                let across = self.neighbours[t][k];
                if self.open(across) {
                    face.iter().for_each(|&s| self.boundary[tet[s] as usize] = true);
                }
            }
        }
        for v in 0..n {
            self.offsets[v + 1] += self.offsets[v];
        }
        let mut fill = self.offsets.clone();
        self.around = vec![0; self.offsets[n]];
        for (t, tet) in self.mesh.tets.iter().enumerate().filter(|(t, _)| self.alive[*t]) {
            for &v in tet {
                self.around[fill[v as usize]] = t as u32;
                fill[v as usize] += 1;
            }
        }
    }

    /// Whether a face whose neighbour across is `across` is open: no live tet shares it.
    fn open(&self, across: u32) -> bool {
        across == NONE || !self.alive[across as usize]
    }

    fn star(&self, v: u32) -> &[u32] {
        &self.around[self.offsets[v as usize]..self.offsets[v as usize + 1]]
    }

    /// The cosine of the smallest dihedral angle around `v` with `v` put at `p` (see
    /// [`worst_with`]).
    fn worst(&self, v: u32, p: Vec3) -> f32 {
        worst_with(self.mesh, self.star(v), v, p)
    }

    /// Snaps every boundary vertex not yet on the surface, twice (a vertex blocked in the
    /// first sweep may be free once its neighbours moved); the vertices that did not get all
    /// the way, sorted. The closest points are looked up before each sweep (a vertex's
    /// target depends on its own position only), and the moves are made a group of
    /// independent vertices at a time (see [`Work::independent`]).
    fn snap_boundary(&mut self, surface: &Surface) -> Vec<u32> {
        let n = self.mesh.vertices.len() as u32;
        let mut stuck: Vec<u32> =
            (0..n).filter(|&v| self.boundary[v as usize] && !self.on_surface[v as usize]).collect();
        for _ in 0..2 {
            let targets = self.closest_of(&stuck, surface);
            self.move_in_groups(
                &stuck,
                |work, v, i| work.towards(v, targets[i]),
                |work, v, (p, whole)| {
                    work.mesh.vertices[v as usize] = p;
                    work.on_surface[v as usize] = whole;
                },
            );
            stuck.retain(|&v| !self.on_surface[v as usize]);
        }
        stuck
    }

    /// Moves `vertices` a group of independent ones at a time (see [`Work::independent`]):
    /// `to(work, v, i)` says where `v`, the `i`-th of `vertices`, goes (worked out in
    /// parallel for a group, each vertex seeing its neighbours where they are), then
    /// `apply` puts the group's vertices there in turn.
    fn move_in_groups<T: Send>(
        &mut self,
        vertices: &[u32],
        to: impl Fn(&Self, u32, usize) -> T + Sync,
        mut apply: impl FnMut(&mut Self, u32, T),
    ) {
        for group in self.independent(vertices) {
            let moves: Vec<T> = group.par_iter().map(|&i| to(self, vertices[i], i)).collect();
            for (&i, m) in group.iter().zip(moves) {
                apply(self, vertices[i], m);
            }
        }
    }

    /// `vertices` split into groups (of positions in `vertices`) of which no two share a
    /// tet, so that a group's vertices can move at once, each seeing its neighbours where
    /// they are: a greedy colouring, in the order given (each vertex takes the first group
    /// holding none of its neighbours), so the groups, and the moves, are the same on any
    /// thread count.
    fn independent(&self, vertices: &[u32]) -> Vec<Vec<usize>> {
        let mut colour = vec![u32::MAX; self.mesh.vertices.len()];
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut taken = Vec::new();
        for (i, &v) in vertices.iter().enumerate() {
            taken.clear();
            let corners = self.star(v).iter().flat_map(|&t| self.mesh.tets[t as usize]);
            taken.extend(corners.map(|u| colour[u as usize]).filter(|&c| c != u32::MAX));
            // one of these is free (a lattice vertex has at most 14 neighbours)
            let free = (0..=taken.len() as u32).find(|c| !taken.contains(c)).unwrap_or(taken.len() as u32);
            colour[v as usize] = free;
            if groups.len() <= free as usize {
                groups.resize(free as usize + 1, Vec::new());
            }
            groups[free as usize].push(i);
        }
        groups
    }

    /// The closest surface points of `vertices`.
    fn closest_of(&self, vertices: &[u32], surface: &Surface) -> Vec<Vec3> {
        vertices.par_iter().map(|&v| surface.closest(self.mesh.vertices[v as usize])).collect()
    }

    /// Moves `v` the whole way to `target` when that keeps its tets good, else by the largest
    /// of a few halved steps that does, else not at all. Whether it got the whole way.
    fn move_towards(&mut self, v: u32, target: Vec3) -> bool {
        let (p, whole) = self.towards(v, target);
        self.mesh.vertices[v as usize] = p;
        whole
    }

    /// Where [`Work::move_towards`] puts `v`, and whether that is the whole way.
    fn towards(&self, v: u32, target: Vec3) -> (Vec3, bool) {
        let from = self.mesh.vertices[v as usize];
        let mut step = 1.0;
        for _ in 0..=HALVINGS {
            let p = from + (target - from) * step;
            if self.worst(v, p) <= cos_deg(MIN_DIHEDRAL) {
                return (p, step == 1.0);
            }
            step *= 0.5;
        }
        (from, false)
    }

    /// The tets that keep the `stuck` vertices off the surface and whose corners are all
    /// boundary vertices (giving them up exposes no interior vertex), sorted.
    fn blockers(&self, stuck: &[u32], surface: &Surface) -> Vec<u32> {
        let mut found: Vec<u32> = Vec::new();
        for (&v, target) in stuck.iter().zip(self.closest_of(stuck, surface)) {
            let spoilt =
                self.star(v).iter().filter(|&&t| worst_with(self.mesh, &[t], v, target) > cos_deg(MIN_DIHEDRAL));
            found.extend(spoilt.filter(|&&t| self.mesh.tets[t as usize].iter().all(|&u| self.boundary[u as usize])));
        }
        found.sort_unstable();
        found.dedup();
        found
    }

    /// Brings back the given-up tets that would close a face lying deeper than `depth`
    /// under the surface (the floor of a slit or a pocket in a thin part), where their
    /// corners are or after easing the corners that are not `fixed`, as long as every tet
    /// around keeps [`MIN_DIHEDRAL`] and no face around ends up farther from the surface
    /// than `depth` or the farthest one there before. In index order, a few sweeps.
    fn restore(&mut self, surface: &Surface, depth: f32, fixed: &[bool]) {
        // a tet that failed is tried again only once a tet next to its corners came back
        let mut tried = vec![false; self.mesh.tets.len()];
        let mut changed = vec![false; self.mesh.vertices.len()];
        for _ in 0..RESTORE_SWEEPS {
            let worth = |t: u32| !tried[t as usize] || self.mesh.tets[t as usize].iter().any(|&v| changed[v as usize]);
            let deep: Vec<u32> = (0..self.mesh.tets.len() as u32)
                .into_par_iter()
                .filter(|&t| !self.alive[t as usize] && worth(t) && revivable(self.mesh, t as usize))
                .filter(|&t| self.bared_faces(t).any(|c| surface.closest(c).distance(c) > depth))
                .collect();
            changed.iter_mut().for_each(|c| *c = false);
            let mut revived = Vec::new();
            for t in deep {
                tried[t as usize] = true;
                if self.revive(t, surface, depth, fixed, &revived) {
                    self.alive[t as usize] = true;
                    revived.push(t);
                }
            }
            if revived.is_empty() {
                return;
            }
            for &t in &revived {
                for v in self.mesh.tets[t as usize] {
                    self.star(v)
                        .iter()
                        .flat_map(|&u| self.mesh.tets[u as usize])
                        .for_each(|u| changed[u as usize] = true);
                }
            }
            self.refresh();
        }
    }

    /// Whether the given-up tet `t` can come back (see [`Work::restore`]); `revived`: the
    /// tets brought back since the stars were last computed. The corners keep the eased
    /// positions only if it can.
    fn revive(&mut self, t: u32, surface: &Surface, depth: f32, fixed: &[bool], revived: &[u32]) -> bool {
        let tet = self.mesh.tets[t as usize];
        let star_with = |work: &Work, v: u32| {
            let mut star = work.star(v).to_vec();
            star.extend(revived.iter().chain([&t]).filter(|&&u| work.mesh.tets[u as usize].contains(&v)));
            star
        };
        let shaped = |work: &Work| {
            tet.iter().all(|&v| {
                worst_with(work.mesh, &star_with(work, v), v, work.mesh.vertices[v as usize]) <= cos_deg(MIN_DIHEDRAL)
            })
        };
        let off = |c: Vec3| surface.closest(c).distance(c);
        // the farthest sample of the open faces that touch the corners: the faces bringing
        // `t` back closes or opens, and those easing moves
        let farthest = |work: &Work| {
            let mut around: Vec<u32> = tet.iter().flat_map(|&v| star_with(work, v)).collect();
            around.sort_unstable();
            around.dedup();
            let open = around.iter().filter(|&&u| work.alive[u as usize]);
            open.flat_map(|&u| work.open_faces(u, Some(tet))).map(off).fold(0.0f32, f32::max)
        };
        let allowed = farthest(self).max(depth);
        let saved = tet.map(|v| self.mesh.vertices[v as usize]);
        // a pocket closed on all sides gets more sweeps of easing
        let enclosed = self.open_faces(t, None).next().is_none();
        for sweeps in [0, if enclosed { 6 } else { 2 }] {
            for _ in 0..sweeps {
                for v in tet.into_iter().filter(|&v| !fixed.get(v as usize).copied().unwrap_or(false)) {
                    let on_boundary = self.bare_without(v, t, revived);
                    let p = ease_in(self, v, &star_with(self, v), on_boundary.then_some(surface));
                    self.mesh.vertices[v as usize] = p;
                }
            }
            self.alive[t as usize] = true;
            if shaped(self) && farthest(self) <= allowed {
                return true;
            }
            self.alive[t as usize] = false;
        }
        for (v, p) in tet.iter().zip(saved) {
            self.mesh.vertices[*v as usize] = p;
        }
        false
    }

    /// Whether vertex `v` stays on the boundary once tet `t` comes back (it lies on an open
    /// face of a live tet, `revived` counted live, other than one `t` closes, or on an
    /// open face of `t`).
    fn bare_without(&self, v: u32, t: u32, revived: &[u32]) -> bool {
        let open_at_v = |u: u32, open: &dyn Fn(u32) -> bool| {
            let tet = self.mesh.tets[u as usize];
            FACES.iter().zip(self.neighbours[u as usize]).any(|(face, n)| open(n) && face.iter().any(|&s| tet[s] == v))
        };
        let others = self.star(v).iter().chain(revived.iter().filter(|&&u| self.mesh.tets[u as usize].contains(&v)));
        others.copied().any(|u| open_at_v(u, &|n| n != t && self.open(n))) || open_at_v(t, &|n| self.open(n))
    }

    /// The corners, edge midpoints and centres of the faces of tet `t` that no live tet
    /// shares; with `touching`, only the faces with a corner among them.
    fn open_faces(&self, t: u32, touching: Option<[u32; 4]>) -> impl Iterator<Item = Vec3> + '_ {
        let tet = self.mesh.tets[t as usize];
        let touches = move |face: &[usize; 3]| touching.is_none_or(|c| face.iter().any(|&s| c.contains(&tet[s])));
        let open =
            FACES.iter().zip(self.neighbours[t as usize]).filter(move |(face, n)| self.open(*n) && touches(face));
        open.flat_map(move |(face, _)| face_samples(face.map(|s| self.mesh.vertices[tet[s] as usize])))
    }

    /// The centres of the faces tet `t` shares with live tets.
    fn bared_faces(&self, t: u32) -> impl Iterator<Item = Vec3> + '_ {
        let tet = self.mesh.tets[t as usize];
        let shared = FACES.iter().zip(self.neighbours[t as usize]).filter(|(_, n)| !self.open(*n));
        shared.map(move |(face, _)| face.iter().map(|&s| self.mesh.vertices[tet[s] as usize]).sum::<Vec3>() / 3.0)
    }

    fn give_up(&mut self, tets: &[u32]) {
        tets.iter().for_each(|&t| self.alive[t as usize] = false);
        self.refresh();
    }

    /// The corners of the live tets whose smallest dihedral angle is below `limit`, sorted.
    fn corners_of_poor_tets(&self, limit: f32) -> Vec<u32> {
        let quality: Vec<f32> =
            (0..self.mesh.tets.len()).into_par_iter().map(|t| sharpest(self.mesh.corners(t))).collect();
        let poor = (0..self.mesh.tets.len()).filter(|&t| self.alive[t] && quality[t] > cos_deg(limit));
        let mut corners: Vec<u32> = poor.flat_map(|t| self.mesh.tets[t]).collect();
        corners.sort_unstable();
        corners.dedup();
        corners
    }

    /// The edges of the boundary faces of the live tets, each once, sorted.
    fn boundary_edges(&self) -> Vec<(u32, u32)> {
        let mut edges = Vec::new();
        for (t, tet) in self.mesh.tets.iter().enumerate().filter(|(t, _)| self.alive[*t]) {
            for (k, face) in FACES.iter().enumerate() {
                let across = self.neighbours[t][k];
                if self.open(across) {
                    let f = face.map(|s| tet[s]);
                    edges.extend([(f[0], f[1]), (f[1], f[2]), (f[2], f[0])].map(|(a, b)| (a.min(b), a.max(b))));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        edges
    }

    /// Where a boundary edge joins vertices whose closest surface points lie on two
    /// different patches (it cuts across a crease), moves the endpoint nearer the crease
    /// onto it (as far as the tets stay good), so the boundary follows sharp edges.
    /// Which vertices it put on a crease.
    fn align_creases(&mut self, surface: &Surface, features: &Features) -> Vec<bool> {
        if features.creases.is_empty() {
            return Vec::new();
        }
        let vertices = &self.mesh.vertices;
        let patch: Vec<u32> = (0..vertices.len())
            .into_par_iter()
            .map(|v| if self.boundary[v] { features.patch[surface.closest_triangle(vertices[v]).0] } else { u32::MAX })
            .collect();
        // crease indices sorted by the patches on their two sides, to find those between two
        let mut by_pair: Vec<((u32, u32), usize)> = features.sides.iter().copied().zip(0..).collect();
        by_pair.sort_unstable();
        let mut on_crease = vec![false; vertices.len()];
        self.snap_corners(features, &mut on_crease);
        let edges = self.boundary_edges();
        for (a, b) in edges.iter().chain(&edges).copied() {
            let (a, b) = (a as usize, b as usize);
            if on_crease[a] || on_crease[b] || patch[a] == patch[b] {
                continue;
            }
            let (pa, pb) = (self.mesh.vertices[a], self.mesh.vertices[b]);
            let reach = CREASE_REACH * pa.distance(pb);
            // only the creases between the two patches
            let pair = (patch[a].min(patch[b]), patch[a].max(patch[b]));
            let first = by_pair.partition_point(|e| e.0 < pair);
            let run = by_pair[first..].iter().take_while(|e| e.0 == pair);
            let between = run.map(|e| &features.creases[e.1]);
            let (Some(ca), Some(cb)) = (nearest_on(between.clone(), pa), nearest_on(between, pb)) else { continue };
            let mut order = [(a, ca, pa.distance(ca)), (b, cb, pb.distance(cb))];
            if order[1].2 < order[0].2 {
                order.swap(0, 1);
            }
            for (v, target, distance) in order {
                if distance <= reach && self.move_towards(v as u32, target) {
                    on_crease[v] = true;
                    break;
                }
            }
        }
        on_crease
    }

    /// Moves the boundary vertex nearest each corner of the surface (where three creases
    /// meet) onto it, if it is within a lattice cell and the tets stay good.
    fn snap_corners(&mut self, features: &Features, on_crease: &mut [bool]) {
        let boundary: Vec<u32> = (0..self.mesh.vertices.len() as u32).filter(|&v| self.boundary[v as usize]).collect();
        let cell = crate::fill::mean_edge(self.mesh);
        for corner in &features.corners {
            let nearest = boundary.iter().copied().filter(|&v| !on_crease[v as usize]).min_by(|&a, &b| {
                let (da, db) = (
                    self.mesh.vertices[a as usize].distance(*corner),
                    self.mesh.vertices[b as usize].distance(*corner),
                );
                da.total_cmp(&db).then(a.cmp(&b))
            });
            if let Some(v) = nearest
                && self.mesh.vertices[v as usize].distance(*corner) <= cell
                && self.move_towards(v, *corner)
            {
                on_crease[v as usize] = true;
            }
        }
    }

    /// Eases the corners of the poor tets (boundary vertices along the surface), but not
    /// the `fixed` ones, a group of independent vertices at a time.
    fn relax(&mut self, surface: &Surface, fixed: &[bool]) {
        let mut eased = self.corners_of_poor_tets(EASE_BELOW);
        eased.retain(|&v| !fixed.get(v as usize).copied().unwrap_or(false));
        self.move_in_groups(
            &eased,
            |work, v, _| ease(work, v, work.boundary[v as usize].then_some(surface)),
            |work, v, p| work.mesh.vertices[v as usize] = p,
        );
    }

    /// Sweeps of smoothing over the interior corners of the distorted tets: each moves to
    /// the mean of its tets' corners when that raises the smallest angle around it (a group
    /// of independent vertices at a time).
    fn smooth(&mut self) {
        for _ in 0..SMOOTHING_PASSES {
            let mut inner = self.corners_of_poor_tets(SMOOTH_BELOW);
            inner.retain(|&v| !self.boundary[v as usize] && !self.star(v).is_empty());
            self.move_in_groups(
                &inner,
                |work, v, _| work.smoothed(v),
                |work, v, p| {
                    if let Some(p) = p {
                        work.mesh.vertices[v as usize] = p;
                    }
                },
            );
        }
    }

    /// The mean of the corners of `v`'s tets, if putting `v` there raises the smallest
    /// angle around it.
    fn smoothed(&self, v: u32) -> Option<Vec3> {
        let star = self.star(v);
        let corners = star.iter().flat_map(|&t| self.mesh.tets[t as usize]);
        let mean = corners.map(|u| self.mesh.vertices[u as usize]).sum::<Vec3>() / (4 * star.len()) as f32;
        (self.worst(v, mean) < self.worst(v, self.mesh.vertices[v as usize])).then_some(mean)
    }

    /// Keeps the live tets that share a face with another live tet (a tet left hanging by
    /// an edge or a corner once its neighbours were given up goes too), then drops the
    /// vertices no tet uses and renumbers the rest in order.
    fn finish(self) {
        let (alive, neighbours) = (&self.alive, &self.neighbours);
        let attached = |t: usize| neighbours[t].iter().any(|&n| n != NONE && alive[n as usize]);
        let mut t = 0;
        self.mesh.tets.retain(|_| {
            t += 1;
            alive[t - 1] && attached(t - 1)
        });
        drop_unused(self.mesh);
    }
}

/// The closest point to `p` on any of `segments` (none if there are none).
fn nearest_on<'s>(segments: impl Iterator<Item = &'s [Vec3; 2]>, p: Vec3) -> Option<Vec3> {
    let mut best = (f32::INFINITY, None);
    for [a, b] in segments {
        let q = crate::mesh::closest_on_segment(p, *a, *b);
        let distance = q.distance_squared(p);
        if distance < best.0 {
            best = (distance, Some(q));
        }
    }
    best.1
}

/// The position that most raises the smallest dihedral angle around `v`: a pattern search
/// along the axes with steps from a fifth of the mean distance to its tets' corners down to
/// a fortieth; with a surface, every candidate is moved onto it.
fn ease(work: &Work, v: u32, surface: Option<&Surface>) -> Vec3 {
    ease_in(work, v, work.star(v), surface)
}

/// [`ease`] with the tets `star` around `v`.
fn ease_in(work: &Work, v: u32, star: &[u32], surface: Option<&Surface>) -> Vec3 {
    let here = work.mesh.vertices[v as usize];
    let corners = star.iter().flat_map(|&t| work.mesh.tets[t as usize]).map(|u| work.mesh.vertices[u as usize]);
    let mut step = corners.map(|c| c.distance(here)).sum::<f32>() / (3 * star.len()).max(1) as f32 * 0.2;
    // the sharpest tets first: a candidate no better than the best is told after a few
    let mut keyed: Vec<(f32, u32)> = star.iter().map(|&t| (sharpest(work.mesh.corners(t as usize)), t)).collect();
    keyed.sort_by(|a, b| b.0.total_cmp(&a.0));
    let star: Vec<u32> = keyed.into_iter().map(|(_, t)| t).collect();
    let mut best = (worst_with(work.mesh, &star, v, here), here);
    for _ in 0..4 {
        for _ in 0..4 {
            let moves = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|d| best.1 + d * step);
            let mut found = best;
            for p in moves.map(|p| surface.map_or(p, |s| s.closest(p))) {
                let worst = worst_below(work.mesh, &star, v, p, found.0);
                if worst < found.0 {
                    found = (worst, p);
                }
            }
            if found.1 == best.1 {
                break;
            }
            best = found;
        }
        step *= 0.5;
    }
    best.1
}

/// Moves every boundary vertex of `mesh` out along the boundary's normal there by
/// `margin` (or half, a quarter, down to a sixteenth of it, else not at all) as far as
/// every tet around it keeps [`MIN_DIHEDRAL`], in vertex order. The boundary faces are
/// chords of the surface, so a convex part of the surface bulges out between the
/// vertices: moved out, the tets hold the surface, and points on it find their tet
/// without a search for the nearest face.
pub(super) fn inflate(mesh: &mut TetMesh, margin: f32) {
    let neighbours = mesh.neighbours();
    let mut normals = vec![Vec3::ZERO; mesh.vertices.len()];
    for [a, b, c] in mesh.boundary_faces(&neighbours) {
        let [pa, pb, pc] = [a, b, c].map(|v| mesh.vertices[v as usize]);
        let weighted = (pb - pa).cross(pc - pa);
        [a, b, c].iter().for_each(|&v| normals[v as usize] += weighted);
    }
    let (offsets, stars) = mesh.vertex_tets();
    let floor = cos_deg(MIN_DIHEDRAL);
    for v in 0..mesh.vertices.len() {
        let Some(normal) = normals[v].try_normalize() else { continue };
        let star = &stars[offsets[v]..offsets[v + 1]];
        let from = mesh.vertices[v];
        let moved = (0..=HALVINGS)
            .map(|k| from + normal * (margin / (1 << k) as f32))
            .find(|&p| worst_below(mesh, star, v as u32, p, floor) <= floor);
        if let Some(p) = moved {
            mesh.vertices[v] = p;
        }
    }
}

/// The cosine of the smallest dihedral angle of the tets `star` with vertex `v` put at `p`
/// (lower is better); 2 when one of them is inverted or flat. Comparing cosines spares the
/// arc cosines.
fn worst_with(mesh: &TetMesh, star: &[u32], v: u32, p: Vec3) -> f32 {
    worst_below(mesh, star, v, p, f32::INFINITY)
}

/// [`worst_with`], or any value at least `bound` once it is clear the result is.
fn worst_below(mesh: &TetMesh, star: &[u32], v: u32, p: Vec3, bound: f32) -> f32 {
    let mut worst = -1.0f32;
    for &t in star {
        let c = mesh.tets[t as usize].map(|i| if i == v { p } else { mesh.vertices[i as usize] });
        if (c[1] - c[0]).cross(c[2] - c[0]).dot(c[3] - c[0]) <= 0.0 {
            return 2.0;
        }
        worst = worst.max(sharpest(c));
        if worst >= bound {
            return worst;
        }
    }
    worst
}

/// Whether given-up tet `t` is worth trying to bring back: positive, and not flatter than
/// [`REVIVE_FROM`].
fn revivable(mesh: &TetMesh, t: usize) -> bool {
    mesh.volume_of(t) > 0.0 && sharpest(mesh.corners(t)) <= cos_deg(REVIVE_FROM)
}

/// The cosine of the smallest dihedral angle of a tet (as in
/// [`min_dihedral`](crate::fill::tets::min_dihedral)).
fn sharpest(c: [Vec3; 4]) -> f32 {
    let normals = FACES.map(|[a, b, d]| (c[b] - c[a]).cross(c[d] - c[a]).normalize_or_zero());
    let mut largest = -1.0f32;
    for i in 0..4 {
        for j in i + 1..4 {
            largest = largest.max(-normals[i].dot(normals[j]));
        }
    }
    largest
}

/// The cosine of an angle in degrees.
fn cos_deg(degrees: f32) -> f32 {
    degrees.to_radians().cos()
}

/// Drops the vertices no tet uses and renumbers the rest in order.
fn drop_unused(mesh: &mut TetMesh) {
    let mut new_index = vec![u32::MAX; mesh.vertices.len()];
    mesh.tets.iter().flatten().for_each(|&v| new_index[v as usize] = 0);
    for (next, slot) in new_index.iter_mut().filter(|s| **s == 0).enumerate() {
        *slot = next as u32;
    }
    let old = std::mem::take(&mut mesh.vertices);
    mesh.vertices = old.into_iter().zip(&new_index).filter(|(_, n)| **n != u32::MAX).map(|(p, _)| p).collect();
    mesh.tets.iter_mut().flatten().for_each(|v| *v = new_index[*v as usize]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    #[test]
    fn independent_groups_share_no_tet_and_keep_the_order() {
        let mut mesh = cube_lattice([4, 4, 4], 0.25);
        let work = Work::new(&mut mesh);
        let vertices: Vec<u32> = (0..work.mesh.vertices.len() as u32).rev().step_by(2).collect();
        let groups: Vec<Vec<u32>> =
            work.independent(&vertices).iter().map(|g| g.iter().map(|&i| vertices[i]).collect()).collect();
        let mut seen: Vec<u32> = groups.concat();
        seen.sort_unstable();
        let mut want = vertices.clone();
        want.sort_unstable();
        assert_eq!(seen, want);
        for group in &groups {
            assert!(group.windows(2).all(|p| p[0] > p[1]), "the order given is kept");
            for (t, tet) in work.mesh.tets.iter().enumerate() {
                let inside = tet.iter().filter(|v| group.contains(v)).count();
                assert!(inside <= 1, "tet {t} has {inside} corners in one group");
            }
        }
        // the lattice's vertices have at most 14 neighbours
        assert!(groups.len() > 1 && groups.len() <= 15, "{}", groups.len());
    }
}
