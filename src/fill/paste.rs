//! The paste loop (thesis §6.2.3–6.2.7): pick an uncovered seed tet, map it into texture
//! space, grow a clump over neighbours that touch the mask, warp the clump along the field,
//! regrow if the warp uncovered mask, accumulate coverage, repeat until every tet is
//! covered.
//!
//! ```text
//!   uncovered queue --least priority--> rigid map --grow--> clump --optimize--> coords
//!        ^                                                       ^         |
//!        |                                                       +-regrow--+
//!        +----- remove tets whose 165 samples all reach full alpha <--- coverage (record)
//! ```
//! Coverage uses the 165 points `(i, j, k, l) / 8` with `i + j + k + l = 8` in every tet; a
//! patch adds `255 x alpha` (saturating) at each. Everything random comes from the caller's
//! seed mixed with a tet and an attempt, so a patch's placement depends on its seed tet and
//! attempt alone: the next patch is placed while the last is recorded. Per-tet work is
//! collected in order, so the result does not depend on the thread count.

use super::field::Field;
use super::patch::{
    BATCHED, local_index, mask_at_samples, orthogonal, prune, random_frame, sample_batches, sample_points, to_byte,
    touches, vertices_of,
};
pub use super::patch::{Patch, SAMPLES};
use super::sampler::{AlphaBounds, BATCH, Sampler};
use super::tets::{NONE, TetMesh};
use super::warp::{Frame, Rigid, Warp, jacobian};
use crate::TextureType;
use crate::error::{Error, Result};
use crate::noise::hash3;
use crate::progress::Progress;
use crate::volume::Volume;
use glam::Vec3;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Times a seed tet may stay uncovered by its own patch before it is given up.
const STRIKES: u8 = 6;
/// Each time a seed tet stays uncovered, its next patch is this much larger.
const GROWTH: f32 = 1.4;
/// Growth stops at neighbours whose tensor turns more than 45 degrees from the seed's (cosine).
const ALIKE: f32 = 0.7;
/// Regrowing a warped patch stops only at tensors turned more than 90 degrees (cosine).
const NOT_OPPOSED: f32 = 0.0;
/// A warped patch is regrown over the tets it reaches and warped again at most this many
/// times (it takes 2-3 on the repository's fills); the last regrowth's tets are kept.
const WARPS: usize = 8;
/// A regrowth adding fewer than one tet in this many of the clump's is kept without
/// another warp (those tets' coordinates extrapolated from their neighbours').
const SETTLED: usize = 20;

/// Where a tet stands in a regrowth.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Standing {
    Outside,
    Clump,
    Joined,
}

/// How to paste.
#[derive(Debug, Clone)]
pub struct Params {
    /// The texture type (decides which axes follow the field).
    pub kind: TextureType,
    /// Texture axes (0 = x, 1 = y, 2 = z) of the primary, secondary and third directions.
    pub axes: [usize; 3],
    /// Seed of the random stream.
    pub seed: u64,
}

/// What the loop did, for the report.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Patches pasted.
    pub patches: usize,
    /// Tets given up after repeated seeding (0 when the fill is complete).
    pub forced: usize,
    /// Mean tets per clump.
    pub mean_clump: f64,
    /// Mean patches listed per tet.
    pub mean_layers: f64,
    /// Mean angle (degrees) between warped texture axes and the field, over the (tet, patch)
    /// pairs where the patch shows with alpha of at least one half.
    pub angle_mean: f64,
    /// 95th percentile of that angle.
    pub angle_p95: f64,
}

/// The result: patches and, per tet, the patches that touch it in paste order.
#[derive(Debug, Clone, PartialEq)]
pub struct Pasted {
    /// Every patch.
    pub patches: Vec<Patch>,
    /// Per tet, indices into `patches`, bottom first.
    pub tet_patches: Vec<Vec<u32>>,
    /// Figures.
    pub stats: Stats,
}

/// What a fill reads and never changes: the mesh, its field and the masks.
struct Context<'a> {
    mesh: &'a TetMesh,
    neighbours: Vec<[u32; 4]>,
    field: &'a Field,
    masks: Vec<Sampler>,
    bounds: Vec<AlphaBounds>,
    params: Params,
    samples: Vec<[f32; 4]>,
    /// The same samples in batches.
    batches: Vec<[[f32; BATCH]; 4]>,
}

/// A patch placed but not yet recorded: its texture coordinates over its tets (sorted), and
/// the seed frame it follows (none for a patch pasted by hand).
struct Placed {
    patch: Patch,
    tets: Vec<u32>,
    frame: Option<Frame>,
}

/// What a fill changes: the coverage and what it made.
struct State {
    coverage: Vec<u8>,
    /// The tets whose coverage the last patch recorded added to.
    recorded: Vec<u32>,
    out: Pasted,
    angles: Vec<f32>,
}

/// A fill under way.
pub struct Paster<'a> {
    ctx: Context<'a>,
    state: State,
}

impl<'a> Paster<'a> {
    /// Ready to paste into `mesh`; `masks` are one splotch, or outer/middle/inner for the
    /// depth-varying types (source `i` uses mask `i`).
    pub fn new(mesh: &'a TetMesh, field: &'a Field, masks: &[Volume], params: Params) -> Result<Paster<'a>> {
        let want = if field.depth.is_some() { 3 } else { 1 };
        if masks.len() < want {
            return Err(Error::invalid(format!("type {} needs {want} mask(s), got {}", params.kind, masks.len())));
        }
        let tets = mesh.tets.len();
        let out = Pasted { patches: Vec::new(), tet_patches: vec![Vec::new(); tets], stats: Stats::default() };
        let masks: Vec<Sampler> = masks.iter().map(Sampler::mask).collect();
        let bounds = masks.iter().map(AlphaBounds::new).collect();
        let ctx = Context {
            mesh,
            neighbours: mesh.neighbours(),
            field,
            masks,
            bounds,
            params,
            samples: sample_points(),
            batches: sample_batches(),
        };
        let state = State { coverage: vec![0; tets * SAMPLES], recorded: Vec::new(), out, angles: Vec::new() };
        Ok(Paster { ctx, state })
    }

    /// Pastes until every tet is covered. The seed of each patch is the uncovered tet of
    /// least priority, a random number per tet and attempt (so a uniformly random uncovered
    /// tet); a patch's placement depends on its seed and attempt alone. While one patch is
    /// recorded, the patch of the seed that comes next if the recording covers neither it
    /// nor brings the last seed back is placed beside it, and kept when that seed does come
    /// next: the result is the same on one thread (which places nothing ahead) and on many.
    pub fn fill(&mut self, progress: &dyn Progress) -> Result<()> {
        let tets = self.ctx.mesh.tets.len();
        let key = self.ctx.params.seed;
        let priority = |t: usize, strike: u8| hash3(key, t as i64, strike as i64, 0);
        let mut queue: BinaryHeap<Reverse<(u64, u32)>> =
            (0..tets).map(|t| Reverse((priority(t, 0), t as u32))).collect();
        let mut strikes = vec![0u8; tets];
        // a tet leaves the queue once covered or struck out; only a patch's own tets and its
        // seed can change that
        let mut done = vec![false; tets];
        let (mut left, ahead_at_all) = (tets, rayon::current_num_threads() > 1);
        let mut ahead: Option<(usize, u8, Placed)> = None;
        while let Some(seed) = next_seed(&mut queue, &done) {
            if progress.cancelled() {
                return Err(Error::Cancelled);
            }
            let placed = match ahead.take() {
                Some((s, strike, placed)) if s == seed && strike == strikes[seed] => placed,
                _ => self.ctx.place(seed, strikes[seed]),
            };
            let guess = if ahead_at_all { peek_seed(&mut queue, &done) } else { None };
            let (ctx, state, tried) = (&self.ctx, &mut self.state, &strikes);
            (_, ahead) =
                rayon::join(|| state.record(ctx, placed), || guess.map(|s| (s, tried[s], ctx.place(s, tried[s]))));
            strikes[seed] += 1;
            if strikes[seed] >= STRIKES && !state.covered(seed) {
                state.out.stats.forced += 1;
            }
            for &t in state.recorded.iter().chain([&(seed as u32)]) {
                let now = state.covered(t as usize) || strikes[t as usize] >= STRIKES;
                left -= usize::from(now && !done[t as usize]);
                done[t as usize] = now;
            }
            if !done[seed] {
                queue.push(Reverse((priority(seed, strikes[seed]), seed as u32)));
            }
            progress.update("pasting", 1.0 - left as f32 / tets as f32);
        }
        Ok(())
    }

    /// Pastes one patch by hand: texture centre at `at`, rigid (not warped).
    pub fn paste_manual(&mut self, at: Vec3, frame: Frame, source: u16) -> Result<()> {
        let ctx = &self.ctx;
        let (seed, _) = super::field::locate(ctx.mesh, at);
        if ctx.masks.get(source as usize).is_none() {
            return Err(Error::invalid(format!("paste source {source} has no mask")));
        }
        let map = Rigid::new(&frame, ctx.params.axes, at, Vec3::splat(0.5));
        let coords = |v: u32| map.apply(ctx.mesh.vertices[v as usize]);
        let tets = ctx.grow(seed, &coords, source, None);
        let vertices = vertices_of(ctx.mesh, &tets);
        let all: Vec<Vec3> = vertices.iter().map(|&v| coords(v)).collect();
        self.state.record(ctx, Placed { patch: Patch { source, vertices, coords: all }, tets, frame: None });
        Ok(())
    }

    /// The result so far.
    pub fn finish(self) -> Pasted {
        let State { mut out, mut angles, .. } = self.state;
        let stats = &mut out.stats;
        stats.patches = out.patches.len();
        let layers: usize = out.tet_patches.iter().map(Vec::len).sum();
        stats.mean_layers = layers as f64 / out.tet_patches.len().max(1) as f64;
        angles.sort_by(f32::total_cmp);
        if !angles.is_empty() {
            stats.angle_mean = angles.iter().map(|a| *a as f64).sum::<f64>() / angles.len() as f64;
            stats.angle_p95 = angles[(angles.len() * 95 / 100).min(angles.len() - 1)] as f64;
        }
        out
    }
}

impl State {
    fn covered(&self, t: usize) -> bool {
        self.coverage[t * SAMPLES..(t + 1) * SAMPLES].iter().all(|c| *c == 255)
    }

    /// Adds a patch: samples its mask in each clump tet, accumulates coverage, lists it
    /// where it shows, and measures how well it follows the field.
    fn record(&mut self, ctx: &Context, placed: Placed) {
        let Placed { patch, tets, frame } = placed;
        let tets = &tets[..];
        let (mask, bounds) = (&ctx.masks[patch.source as usize], &ctx.bounds[patch.source as usize]);
        let mut alphas = vec![0u8; tets.len() * SAMPLES];
        let mut angles = vec![None; tets.len()];
        let local = local_index(ctx.mesh, &patch.vertices);
        let corners_of = |t: u32| ctx.mesh.tets[t as usize].map(|v| patch.coords[local[v as usize] as usize]);
        alphas.par_chunks_mut(SAMPLES).zip(&mut angles).zip(tets).for_each(|((a, angle), &t)| {
            let corners = corners_of(t);
            if self.covered(t as usize) {
                // nothing to add: only whether the patch shows there (and shows half) matters
                a.fill(0);
                a[0] = tet_shows(mask, bounds, &ctx.samples, corners);
            } else {
                let coverage = &self.coverage[t as usize * SAMPLES..(t as usize + 1) * SAMPLES];
                tet_alphas(mask, bounds, &ctx.batches, corners, coverage, a);
            }
            if let (Some(f), true) = (&frame, a.iter().any(|x| *x >= 128)) {
                *angle = Some(ctx.angle(t as usize, corners, f));
            }
        });
        let index = self.out.patches.len() as u32;
        self.recorded.clear();
        for ((&t, a), angle) in tets.iter().zip(alphas.chunks_exact(SAMPLES)).zip(angles) {
            if a.iter().all(|x| *x == 0) {
                continue;
            }
            let cov = &mut self.coverage[t as usize * SAMPLES..(t as usize + 1) * SAMPLES];
            cov.iter_mut().zip(a).for_each(|(c, x)| *c = c.saturating_add(*x));
            self.recorded.push(t);
            self.out.tet_patches[t as usize].push(index);
            self.angles.extend(angle);
        }
        self.out.stats.mean_clump += (tets.len() as f64 - self.out.stats.mean_clump) / (index as f64 + 1.0);
        self.out.patches.push(prune(patch, &local, ctx.mesh, tets, &alphas));
    }
}

impl Context<'_> {
    fn depth_at(&self, v: u32) -> Option<f32> {
        self.field.depth.as_ref().map(|d| d[v as usize])
    }

    /// Which source (mask) a seed uses: outer, middle or inner by its mean depth (thesis
    /// §6.2.7). A seed tet that its own patch left uncovered (it spans more depth than one
    /// mask, where the depth field is steep) tries the next mask on each later attempt.
    fn source_for(&self, seed: usize, strike: u8) -> u16 {
        match self.field.depth.as_ref() {
            None => 0,
            Some(d) => {
                let depth = self.mesh.tets[seed].iter().map(|&v| d[v as usize]).sum::<f32>() / 4.0;
                let base = if depth < 1.0 / 3.0 {
                    0
                } else if depth < 2.0 / 3.0 {
                    1
                } else {
                    2
                };
                ((base + strike) % 3) as u16
            }
        }
    }

    /// The frame of a patch seeded at tet `t` on its `strike`-th attempt: the field's,
    /// completed or replaced by a random frame of that seed and attempt.
    fn seed_frame(&self, t: usize, strike: u8) -> Frame {
        let random = random_frame(&mut Pcg64Mcg::seed_from_u64(hash3(self.params.seed, t as i64, strike as i64, 1)));
        let r = self.field.primary[t];
        let s = self.field.secondary[t];
        let dirs = if r == Vec3::ZERO {
            random
        } else if s == Vec3::ZERO {
            let s = orthogonal(random[1], r);
            [r, s, r.cross(s)]
        } else {
            [r, s, r.cross(s)]
        };
        Frame { dirs, scale: self.field.scale[t] }
    }

    /// The target frame of tet `t` for a patch seeded with `seed_frame`.
    fn frame_of(&self, t: usize, seed_frame: &Frame, boost: f32) -> Frame {
        let (r, s) = (self.field.primary[t], self.field.secondary[t]);
        let dirs = match (r == Vec3::ZERO, s == Vec3::ZERO) {
            (true, _) => seed_frame.dirs,
            (false, true) => {
                let s = orthogonal(seed_frame.dirs[1], r);
                [r, s, r.cross(s)]
            }
            (false, false) => [r, s, r.cross(s)],
        };
        Frame { dirs, scale: self.field.scale[t] * boost }
    }

    /// The patch of `seed` at its `strike`-th attempt: a rigid map of a frame from the field
    /// (random where the field gives none), grown, warped along the field and regrown.
    fn place(&self, seed: usize, strike: u8) -> Placed {
        let mut frame = self.seed_frame(seed, strike);
        frame.scale *= GROWTH.powi(strike as i32);
        let axes = self.params.axes;
        let anchor = self.mesh.centroid(seed);
        let mut centre = Vec3::splat(0.5);
        let fixed = self.field.depth.as_ref().map(|_| axes[0]);
        if let Some(axis) = fixed {
            centre[axis] = self.mesh.tets[seed].iter().map(|&v| self.depth_at(v).unwrap_or(0.5)).sum::<f32>() / 4.0;
        }
        let map = Rigid::new(&frame, axes, anchor, centre);
        let source = self.source_for(seed, strike);
        let place = |v: u32| self.with_depth(v, map.apply(self.mesh.vertices[v as usize]));
        let mut tets = self.grow(seed, &place, source, Some(&frame));
        let mut vertices = vertices_of(self.mesh, &tets);
        let mut coords: Vec<Vec3> = vertices.iter().map(|&v| place(v)).collect();
        let boost = frame.scale / self.field.scale[seed];
        for round in 1..=WARPS {
            if self.field.primary[seed] != Vec3::ZERO {
                let frames: Vec<Frame> = tets.iter().map(|&t| self.frame_of(t as usize, &frame, boost)).collect();
                let pin = (tets.iter().position(|&t| t as usize == seed).unwrap_or(0), centre);
                let warp =
                    Warp { mesh: self.mesh, tets: &tets, vertices: &vertices, frames: &frames, axes, pin, fixed };
                warp.solve(&mut coords);
            }
            let local = local_index(self.mesh, &vertices);
            let added = self.regrow(seed, &frame, &tets, &local, &coords, source);
            if added.is_empty() {
                break;
            }
            let settled = added.len() * SETTLED < tets.len();
            (tets, vertices, coords) = self.extend(tets, &vertices, local, &coords, &added);
            if settled || round == WARPS {
                break;
            }
        }
        Placed { patch: Patch { source, vertices, coords }, tets, frame: Some(frame) }
    }

    fn with_depth(&self, v: u32, mut w: Vec3) -> Vec3 {
        if let Some(d) = self.depth_at(v) {
            w[self.params.axes[0]] = d;
        }
        w
    }

    /// Grows a clump from `seed` over face neighbours that touch the mask under `coords`
    /// and (for an oriented fill) whose tensor is close to the seed's; sorted. Whether a tet
    /// joins depends on the tet alone, so the clump is the same whatever order it grows in:
    /// a ring of neighbours at a time, tested in parallel.
    fn grow(&self, seed: usize, coords: &(dyn Fn(u32) -> Vec3 + Sync), source: u16, frame: Option<&Frame>) -> Vec<u32> {
        let mask = &self.masks[source as usize];
        let mut seen = vec![false; self.mesh.tets.len()];
        seen[seed] = true;
        let (mut clump, mut ring) = (vec![seed as u32], vec![seed as u32]);
        while !ring.is_empty() {
            let mut next: Vec<u32> = ring.iter().flat_map(|&t| self.neighbours[t as usize]).collect();
            // each neighbour once, and never again
            next.retain(|&n| n != NONE && !std::mem::replace(&mut seen[n as usize], true));
            let joins: Vec<bool> = next
                .par_iter()
                .map(|&n| {
                    self.alike(seed, n as usize, frame, ALIKE) && touches(mask, self.mesh.tets[n as usize].map(coords))
                })
                .collect();
            ring = next.into_iter().zip(joins).filter(|(_, j)| *j).map(|(n, _)| n).collect();
            clump.extend(&ring);
        }
        clump.sort_unstable();
        clump
    }

    /// Whether tet `t`'s tensor turns from the seed's by an angle of cosine at least `cos`
    /// (always, for a fill without a field).
    fn alike(&self, seed: usize, t: usize, frame: Option<&Frame>, cos: f32) -> bool {
        frame.is_none()
            || self.field.primary[seed] == Vec3::ZERO
            || self.field.primary[t].dot(self.field.primary[seed]) >= cos
                && self.field.secondary[t].dot(self.field.secondary[seed])
                    >= cos.min(self.field.secondary[seed].length())
    }

    /// The tets outside the clump that the warped patch reaches, with their corner
    /// coordinates, sorted: a flood from the clump over face neighbours that touch the
    /// mask, each new tet's new corners extrapolated by the map of the tet it was reached
    /// from. These join unless their tensor opposes the seed's (the first growth asks
    /// [`ALIKE`]): the thesis adds the tets the warped patch lacks (§6.2.5), and a patch cut
    /// off at a tet face where its mask is still high leaves a hard seam; an opposed tensor
    /// means the patch would wrap around a singular axis (the kiwi's core). `local` gives
    /// each mesh vertex's index in `coords` ([`local_index`]).
    fn regrow(
        &self,
        seed: usize,
        frame: &Frame,
        tets: &[u32],
        local: &[u32],
        coords: &[Vec3],
        source: u16,
    ) -> Vec<(u32, [Vec3; 4])> {
        let mask = &self.masks[source as usize];
        // where each tet stands: in the clump, joined, neither
        let mut state = vec![Standing::Outside; self.mesh.tets.len()];
        tets.iter().for_each(|&t| state[t as usize] = Standing::Clump);
        let mut ring: Vec<(u32, [Vec3; 4])> = tets
            .par_iter()
            .map(|&t| (t, self.mesh.tets[t as usize].map(|v| coords[local[v as usize] as usize])))
            .collect();
        // the open neighbours of tet `t` (coordinates `w_t`) not opposed to the seed's
        // tensor that the map of `t`, extended over them, makes touch the mask, with their
        // corners' coordinates (corners in the clump keep theirs)
        let offers = |state: &[Standing], t: u32, w_t: [Vec3; 4]| -> Vec<(u32, [Vec3; 4])> {
            let open = |n: u32| n != NONE && state[n as usize] == Standing::Outside;
            let neighbours = self.neighbours[t as usize];
            if !neighbours.iter().any(|&n| open(n)) {
                return Vec::new();
            }
            let jac = jacobian(self.mesh, t as usize, w_t);
            let origin = self.mesh.vertices[self.mesh.tets[t as usize][0] as usize];
            let reach = |n: u32| {
                self.mesh.tets[n as usize].map(|v| match local[v as usize] {
                    NONE => self.with_depth(v, w_t[0] + jac * (self.mesh.vertices[v as usize] - origin)),
                    i => coords[i as usize],
                })
            };
            let alike = |n: u32| self.alike(seed, n as usize, Some(frame), NOT_OPPOSED);
            let joining = neighbours.into_iter().filter(|&n| open(n) && alike(n)).map(|n| (n, reach(n)));
            joining.filter(|(_, w)| touches(mask, *w)).collect()
        };
        let mut added: Vec<(u32, [Vec3; 4])> = Vec::new();
        // a ring at a time, its tets in order: each offers its neighbours (tested side by
        // side), and the first offer for a tet wins, as a flood one tet at a time in the
        // same order would decide
        while !ring.is_empty() {
            let before = &state;
            let offers: Vec<Vec<(u32, [Vec3; 4])>> = ring.par_iter().map(|&(t, w_t)| offers(before, t, w_t)).collect();
            let first = added.len();
            for (n, w) in offers.into_iter().flatten() {
                if state[n as usize] == Standing::Outside {
                    state[n as usize] = Standing::Joined;
                    added.push((n, w));
                }
            }
            ring = added[first..].to_vec();
        }
        added.sort_unstable_by_key(|a| a.0);
        added
    }

    /// The clump with the `added` tets: its tets, vertices and their coordinates (each new
    /// corner's from the first added tet that has it), sorted by tet and vertex; `at` is
    /// the [`local_index`] of `vertices`.
    fn extend(
        &self,
        tets: Vec<u32>,
        vertices: &[u32],
        mut at: Vec<u32>,
        coords: &[Vec3],
        added: &[(u32, [Vec3; 4])],
    ) -> (Vec<u32>, Vec<u32>, Vec<Vec3>) {
        let mut all = tets;
        all.extend(added.iter().map(|a| a.0));
        all.sort_unstable();
        let mut new_coords: Vec<Vec3> = coords.to_vec();
        let mut new: Vec<u32> = Vec::new();
        for (t, w) in added {
            for (v, x) in self.mesh.tets[*t as usize].into_iter().zip(w) {
                if at[v as usize] == NONE {
                    at[v as usize] = new_coords.len() as u32;
                    new_coords.push(*x);
                    new.push(v);
                }
            }
        }
        let mut new_vertices = [vertices, &new].concat();
        new_vertices.sort_unstable();
        let sorted_coords = new_vertices.iter().map(|&v| new_coords[at[v as usize] as usize]).collect();
        (all, new_vertices, sorted_coords)
    }

    /// The largest angle (degrees) between a field axis mapped by the patch (its texture
    /// coordinates at tet `t`'s `corners`) and its texture axis: the primary for 1-a/1-b,
    /// primary and secondary for 2-a/2-b, none for type 0.
    fn angle(&self, t: usize, corners: [Vec3; 4], seed_frame: &Frame) -> f32 {
        let checked = match self.params.kind {
            TextureType::T0 => 0,
            TextureType::T1a | TextureType::T1b => 1,
            _ => 2,
        };
        let frame = self.frame_of(t, seed_frame, 1.0);
        let jac = jacobian(self.mesh, t, corners);
        (0..checked)
            .map(|k| {
                let image = (jac * frame.dirs[k]).normalize_or_zero();
                image[self.params.axes[k]].clamp(-1.0, 1.0).acos().to_degrees()
            })
            .fold(0.0, f32::max)
    }
}

/// The uncovered tet of least priority, taken off the queue (entries of tets done since
/// they were queued are dropped).
fn next_seed(queue: &mut BinaryHeap<Reverse<(u64, u32)>>, done: &[bool]) -> Option<usize> {
    peek_seed(queue, done).inspect(|_| {
        queue.pop();
    })
}

/// The uncovered tet of least priority, left on the queue.
fn peek_seed(queue: &mut BinaryHeap<Reverse<(u64, u32)>>, done: &[bool]) -> Option<usize> {
    while let Some(Reverse((_, t))) = queue.peek() {
        if !done[*t as usize] {
            return Some(*t as usize);
        }
        queue.pop();
    }
    None
}

/// A mask value at least this high shows as full coverage (255) at every sample.
const FULL: f32 = 0.999;

/// The coverage byte every sample of a tet takes, when the `range` of the mask's values
/// over it (see [`bounds_of`]) decides it (0 or 255) without sampling.
fn decided(range: (f32, f32)) -> Option<u8> {
    match range {
        (_, most) if most <= 0.0 => Some(0),
        (least, _) if least >= FULL => Some(255),
        _ => None,
    }
}

/// The least and greatest mask value anywhere in a tet whose corners have texture
/// coordinates `w` (conservative).
fn bounds_of(bounds: &AlphaBounds, w: &[Vec3; 4]) -> (f32, f32) {
    let lo = w[0].min(w[1]).min(w[2].min(w[3]));
    let hi = w[0].max(w[1]).max(w[2].max(w[3]));
    bounds.range(lo, hi)
}

/// The coverage byte of sample `b` (barycentric) of a tet with texture coordinates `w`.
fn sample(mask: &Sampler, w: &[Vec3; 4], b: &[f32; 4]) -> u8 {
    to_byte(mask.alpha(w[0] * b[0] + w[1] * b[1] + w[2] * b[2] + w[3] * b[3]))
}

/// The largest coverage byte of a tet whose corners have texture coordinates `w`, as far as
/// it matters: the first of at least 128 found ends the search, and where the mask's block
/// bounds keep every sample under 128, the first above 0 does (or the bounds alone decide).
fn tet_shows(mask: &Sampler, bounds: &AlphaBounds, samples: &[[f32; 4]], w: [Vec3; 4]) -> u8 {
    let range = bounds_of(bounds, &w);
    if let Some(all) = decided(range) {
        return all;
    }
    let (least, most) = (to_byte(range.0), to_byte(range.1));
    if least >= 1 && (least >= 128 || most < 128) {
        return least;
    }
    let enough = if most < 128 { 1 } else { 128 };
    let mut found = 0;
    for b in samples {
        found = found.max(sample(mask, &w, b));
        if found >= enough {
            break;
        }
    }
    found
}

/// The coverage bytes of a tet whose corners have texture coordinates `w`, into `out`: 0
/// or 255 at once where the mask's block bounds decide every sample, else every sample
/// looked up (in batches). Where the tet's `coverage` is already full (255), a byte only
/// tells whether the patch shows there and shows at least half: those bytes are kept only
/// until one shows half (the rest left 0).
fn tet_alphas(
    mask: &Sampler,
    bounds: &AlphaBounds,
    batches: &[[[f32; BATCH]; 4]],
    w: [Vec3; 4],
    coverage: &[u8],
    out: &mut [u8],
) {
    if let Some(all) = decided(bounds_of(bounds, &w)) {
        out.fill(all);
        return;
    }
    let mut alphas = [0.0; BATCHED];
    mask_at_samples(mask, &w, batches, &mut alphas);
    let mut half = false;
    for ((o, a), _) in out.iter_mut().zip(alphas).zip(coverage).filter(|(_, c)| **c < 255) {
        *o = to_byte(a);
        half |= *o >= 128;
    }
    for ((o, a), _) in out.iter_mut().zip(alphas).zip(coverage).filter(|(_, c)| **c == 255) {
        if half {
            break;
        }
        *o = to_byte(a);
        half = *o >= 128;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::field::{self, Constraints};
    use crate::fill::tets::cube_lattice;
    use crate::mask;
    use crate::progress::NoProgress;
    use rand::RngExt;

    fn fill(kind: TextureType, c: &Constraints, masks: &[Volume], seed: u64) -> (TetMesh, Pasted) {
        let mesh = cube_lattice([6, 6, 6], 1.0 / 6.0);
        let field = field::build(&mesh, kind, c, None).unwrap();
        let mut paster = Paster::new(&mesh, &field, masks, Params { kind, axes: [1, 0, 2], seed }).unwrap();
        paster.fill(&NoProgress).unwrap();
        let out = paster.finish();
        (mesh, out)
    }

    #[test]
    fn every_tet_is_covered_and_the_fill_replays() {
        let masks = [mask::splotch(16, 0.1, 1).unwrap()];
        let c = Constraints { scale: 0.5, ..Default::default() };
        let (mesh, a) = fill(TextureType::T0, &c, &masks, 3);
        assert_eq!(a.stats.forced, 0);
        assert!(a.tet_patches.iter().all(|l| !l.is_empty()));
        assert!(a.stats.patches > 3 && a.stats.patches < mesh.tets.len(), "{:?}", a.stats);
        let (_, b) = fill(TextureType::T0, &c, &masks, 3);
        assert_eq!(a, b);
        let (_, other) = fill(TextureType::T0, &c, &masks, 4);
        assert_ne!(a.patches, other.patches);
    }

    /// Two strokes across the lattice, along x at one end and turned 45 degrees at the
    /// other: a field that bends, at texture scale `scale`.
    fn bent(scale: f32) -> Constraints {
        Constraints {
            directions: vec![(Vec3::new(0.1, 0.5, 0.5), Vec3::X), (Vec3::new(0.9, 0.5, 0.5), Vec3::new(1.0, 1.0, 0.0))],
            scale,
            ..Default::default()
        }
    }

    #[test]
    fn warped_patches_follow_the_field() {
        let masks = [mask::splotch(16, 0.1, 1).unwrap()];
        let (_, out) = fill(TextureType::T1a, &bent(0.5), &masks, 5);
        assert_eq!(out.stats.forced, 0);
        assert!(out.stats.angle_mean < 8.0 && out.stats.angle_p95 < 20.0, "{:?}", out.stats);
    }

    /// The next patch placed beside the recording of the last (on more than one thread)
    /// gives the fill of one thread, which places each patch when its seed comes up.
    #[test]
    fn placing_the_next_patch_ahead_changes_nothing() {
        let masks = [mask::splotch(16, 0.1, 1).unwrap()];
        let c = bent(0.3);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| fill(TextureType::T1a, &c, &masks, 9).1)
        };
        let one = on(1);
        assert!(one.stats.patches > 10, "{:?}", one.stats);
        assert_eq!(one, on(3));
    }

    /// Every sample, as if none were skipped.
    fn exact(mask: &Sampler, w: [Vec3; 4]) -> Vec<u8> {
        sample_points().iter().map(|b| sample(mask, &w, b)).collect()
    }

    #[test]
    fn skipped_samples_change_neither_coverage_nor_where_a_patch_shows() {
        let volume = mask::splotch(16, 0.1, 2).unwrap();
        let mask = Sampler::mask(&volume);
        let bounds = AlphaBounds::new(&mask);
        let samples = sample_points();
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let (mut skipped, mut partly) = (0, 0);
        for _ in 0..400 {
            let centre = Vec3::new(rng.random(), rng.random(), rng.random()) * 1.2 - 0.1;
            let w = [0, 1, 2, 3].map(|_| centre + (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 0.3);
            let all = exact(&mask, w);
            let shows = |a: &[u8]| (a.iter().any(|x| *x > 0), a.iter().any(|x| *x >= 128));
            // already full everywhere
            let found = tet_shows(&mask, &bounds, &samples, w);
            assert_eq!(shows(&[found]), shows(&all), "{w:?}");
            // full at some samples: the open ones exact, the sums and what shows the same
            let coverage: Vec<u8> =
                (0..SAMPLES).map(|_| if rng.random::<bool>() { 255 } else { rng.random() }).collect();
            let mut out = vec![0; SAMPLES];
            tet_alphas(&mask, &bounds, &sample_batches(), w, &coverage, &mut out);
            let sum = |a: &[u8]| coverage.iter().zip(a).map(|(c, x)| c.saturating_add(*x)).collect::<Vec<u8>>();
            assert_eq!(sum(&out), sum(&all));
            assert_eq!(shows(&out), shows(&all));
            skipped += out.iter().zip(&all).filter(|(o, a)| o != a).count();
            partly += usize::from(shows(&all).0 && !shows(&all).1);
        }
        // the skipping and the partial showing both happen
        assert!(skipped > 1000 && partly > 5, "{skipped} {partly}");
    }
}
