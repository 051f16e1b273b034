//! Neighbourhood search with k-coherence candidates.
//!
//! For voxel v and axis i, the candidates are the coherence sets of the exemplar
//! pixels that v's own match and its four in-plane edge neighbours' matches predict for
//! v (`P[u] + (v - u)`), plus one random centre. The best (and second best) by PCA
//! distance win. In layered mode the two-best-match rule keeps the x and y matches from
//! pointing at the same pixel.
//!
//! A fresh pass (the first at a finer level of a homogeneous run) ignores the previous
//! matches: its candidates are the exemplar's nearest neighbourhood by the leading PCA
//! components (a kd-tree lookup over all centres) and the random centre.

use super::exemplar::Prepared;
use super::grid::Grid;
use crate::noise::{hash3, mix64};
use crate::progress::Progress;
use crate::volume::Axis;
use rayon::prelude::*;

/// Per-axis matches: the exemplar centre pixel of every voxel and its distance.
#[derive(Debug, Clone, Default)]
pub struct Matches {
    /// Centre pixel index in the axis' exemplar.
    pub pixel: Vec<u32>,
    /// Euclidean distance in PCA space.
    pub dist: Vec<f32>,
}

/// The exemplars and switches a search pass uses.
pub struct SearchSetup<'a> {
    /// Exemplar per axis (`None` for an axis not searched).
    pub exemplars: [Option<&'a Prepared>; 3],
    /// Apply the two-best-match rule between the x and y axes.
    pub anti_sweeping: bool,
    /// Seed for the random candidates of this pass.
    pub seed: u64,
    /// Look candidates up in the whole exemplar instead of following the previous matches.
    pub fresh: bool,
}

/// The best match and the best one that lies elsewhere in the exemplar (`u32::MAX`: none).
#[derive(Clone, Copy)]
struct Best {
    first: (f32, u32),
    second: (f32, u32),
}

/// The in-plane neighbours whose matches propose candidates: the voxel and its four
/// edge neighbours. The four diagonal ones cost 45 % more distances and gave the same
/// slice energy on the photos (within 0.01; docs/PERFORMANCE.md).
const SOURCES: [(i64, i64); 5] = [(0, -1), (-1, 0), (0, 0), (1, 0), (0, 1)];

/// How many of the closest candidates are kept to find a second best elsewhere.
const TOP: usize = 6;

/// Whether two centre pixels are so close that their neighbourhoods largely overlap.
fn near(ex: &Prepared, a: u32, b: u32) -> bool {
    let (w, r) = (ex.width as i64, (ex.n / 2) as i64);
    let (ax, ay, bx, by) = (a as i64 % w, a as i64 / w, b as i64 % w, b as i64 / w);
    (ax - bx).abs().max((ay - by).abs()) < r
}

/// One z-slice's matches per axis as (distance, pixel), and its summed distance.
type SliceMatches = ([Vec<(f32, u32)>; 3], f64);

/// Search every voxel; returns new matches per axis and the summed distance, or `None`
/// when `progress` asks to stop (polled before each z-slice; told the share of slices
/// searched after each).
pub fn search(
    grid: &Grid,
    previous: &[Matches; 3],
    setup: &SearchSetup,
    progress: &dyn Progress,
) -> Option<([Matches; 3], f64)> {
    let [dx, dy, dz] = grid.dims;
    let searched = std::sync::atomic::AtomicUsize::new(0);
    let slices: Vec<Option<SliceMatches>> = (0..dz)
        .into_par_iter()
        .map(|z| {
            let found = (!progress.cancelled()).then(|| search_slice(grid, previous, setup, z))?;
            let count = searched.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress.update("searching", count as f32 / dz as f32);
            Some(found)
        })
        .collect();
    let slices: Vec<SliceMatches> = slices.into_iter().collect::<Option<_>>()?;
    let mut out: [Matches; 3] = Default::default();
    let mut total = 0.0;
    for (axis, m) in out.iter_mut().enumerate() {
        if setup.exemplars[axis].is_some() {
            m.pixel.reserve(dx * dy * dz);
            m.dist.reserve(dx * dy * dz);
        }
    }
    for (parts, sum) in slices {
        total += sum;
        for (m, part) in out.iter_mut().zip(parts) {
            m.dist.extend(part.iter().map(|p| p.0));
            m.pixel.extend(part.iter().map(|p| p.1));
        }
    }
    Some((out, total))
}

/// Search one z-slice: per axis a list of (distance, pixel), and the slice's summed distance.
/// On a CPU with AVX2 the same code runs compiled for it: eight lanes in one register
/// instead of two. No fused multiply-add is enabled and every lane adds in the same
/// order, so both copies give bit-identical results.
fn search_slice(grid: &Grid, previous: &[Matches; 3], setup: &SearchSetup, z: usize) -> SliceMatches {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, the one feature the copy is compiled with.
        #[allow(unsafe_code)]
        return unsafe { search_slice_avx2(grid, previous, setup, z) };
    }
    search_slice_in(grid, previous, setup, z)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn search_slice_avx2(grid: &Grid, previous: &[Matches; 3], setup: &SearchSetup, z: usize) -> SliceMatches {
    search_slice_in(grid, previous, setup, z)
}

#[inline(always)]
fn search_slice_in(grid: &Grid, previous: &[Matches; 3], setup: &SearchSetup, z: usize) -> SliceMatches {
    let [dx, dy, _] = grid.dims;
    let mut out: [Vec<(f32, u32)>; 3] = Default::default();
    let mut seen: [Vec<u32>; 3] = Default::default();
    let mut stamp = 0u32;
    let (mut taps, mut proj, mut query) = (Vec::new(), Vec::new(), Vec::new());
    let mut sum = 0.0f64;
    for axis in 0..3 {
        if let Some(ex) = setup.exemplars[axis] {
            seen[axis] = vec![0; ex.centres.len()];
            out[axis].reserve(dx * dy);
        }
    }
    let mut bests: Vec<[Option<Best>; 3]> = vec![[None; 3]; dx];
    for y in 0..dy {
        for axis in 0..3 {
            let Some(ex) = setup.exemplars[axis] else { continue };
            grid.project_row(ex, Axis::ALL[axis], y, z, &mut taps, &mut proj);
            for (x, best) in bests.iter_mut().enumerate() {
                query.clear();
                query.extend((0..ex.pca.dims).map(|k| proj[k * dx + x]));
                stamp += 1;
                let v = [x, y, z];
                let context = Context { ex, previous: &previous[axis], axis, seed: setup.seed, fresh: setup.fresh };
                best[axis] = Some(best_two(grid, &context, v, &query, &mut seen[axis], stamp));
            }
        }
        for best in &bests {
            let chosen = choose(best, setup.anti_sweeping, setup.exemplars[0]);
            for axis in 0..3 {
                if let Some(c) = chosen[axis] {
                    sum += c.0 as f64;
                    out[axis].push(c);
                }
            }
        }
    }
    (out, sum)
}

/// What the search of one axis reads.
struct Context<'a> {
    ex: &'a Prepared,
    previous: &'a Matches,
    axis: usize,
    seed: u64,
    fresh: bool,
}

/// The two best distinct candidates for voxel `v` on the context's axis.
#[inline(always)]
fn best_two(grid: &Grid, cx: &Context, v: [usize; 3], query: &[f32], seen: &mut [u32], stamp: u32) -> Best {
    let (ex, previous, axis, seed) = (cx.ex, cx.previous, cx.axis, cx.seed);
    let (a, b) = Axis::ALL[axis].plane_axes();
    let mut top = [(f32::INFINITY, u32::MAX); TOP];
    let mut seen = Seen { marks: seen, stamp };
    let width = ex.width as u32;
    let sources: &[(i64, i64)] = if cx.fresh { &[] } else { &SOURCES };
    if cx.fresh {
        for (_, slot) in ex.lookup.nearest(&query[..ex.lookup.dims()], 1) {
            consider(ex, query, &mut seen, slot as usize, &mut top);
        }
    }
    for &(da, db) in sources {
        let (Some(ua), Some(ub)) = (grid.inside(a, v[a] as i64 + da), grid.inside(b, v[b] as i64 + db)) else {
            continue;
        };
        let mut u = v;
        u[a] = ua;
        u[b] = ub;
        let p = previous.pixel[grid.index(u[0], u[1], u[2])];
        let py = (p / width) as i64;
        let px = p as i64 - py * width as i64;
        let slot = ex.clamped_slot(px - da, py - db);
        for c in ex.coherence_of(slot) {
            consider(ex, query, &mut seen, c as usize, &mut top);
        }
    }
    let voxel = grid.index(v[0], v[1], v[2]) as i64;
    consider(ex, query, &mut seen, ex.random_slot(hash3(seed, voxel, axis as i64, 0)), &mut top);
    let first = top[0];
    let second = top[1..].iter().find(|c| c.1 != u32::MAX && !near(ex, c.1, first.1)).copied();
    let second = second.unwrap_or((f32::INFINITY, u32::MAX));
    Best { first: (first.0.sqrt(), first.1), second: (second.0.sqrt(), second.1) }
}

/// The candidates already measured for the current voxel: those whose mark is `stamp`.
struct Seen<'a> {
    marks: &'a mut [u32],
    stamp: u32,
}

/// Measure candidate `slot` against `query` (once per voxel) and keep it if it is close.
/// A function, not a closure, so that it is compiled into the AVX2 copy of the search.
#[inline(always)]
fn consider(ex: &Prepared, query: &[f32], seen: &mut Seen, slot: usize, top: &mut [(f32, u32); TOP]) {
    if seen.marks[slot] == seen.stamp {
        return;
    }
    seen.marks[slot] = seen.stamp;
    let d = super::knn::squared(query, ex.projection(slot));
    insert(top, (d, ex.centres[slot]));
}

/// Insert into the sorted top list (ties go to the lower pixel index).
#[inline(always)]
fn insert(top: &mut [(f32, u32); TOP], hit: (f32, u32)) {
    let before = |a: (f32, u32), b: (f32, u32)| a.0 < b.0 || (a.0 == b.0 && a.1 < b.1);
    if !before(hit, top[TOP - 1]) {
        return;
    }
    let at = top.iter().position(|t| before(hit, *t)).unwrap_or(TOP - 1);
    top.copy_within(at..TOP - 1, at + 1);
    top[at] = hit;
}

/// The match per axis. With the rule on, when the x and y best matches point to the
/// same place in the exemplar, the closer one keeps it and the other axis takes its
/// best match elsewhere.
fn choose(best: &[Option<Best>; 3], anti_sweeping: bool, ex: Option<&Prepared>) -> [Option<(f32, u32)>; 3] {
    let mut chosen = best.map(|b| b.map(|b| b.first));
    if let (true, Some(bx), Some(by), Some(ex)) = (anti_sweeping, best[0], best[1], ex)
        && near(ex, bx.first.1, by.first.1)
    {
        if bx.first.0 <= by.first.0 && by.second.1 != u32::MAX {
            chosen[1] = Some(by.second);
        } else if bx.second.1 != u32::MAX {
            chosen[0] = Some(bx.second);
        }
    }
    chosen
}

/// A seed for one search pass from the run seed, the level and the iteration.
pub fn pass_seed(seed: u64, level: usize, iteration: usize) -> u64 {
    mix64(seed ^ mix64(((level as u64) << 32) | iteration as u64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::exemplar::PrepareOptions;
    use crate::volume::{Channel, Image2d};

    /// On an exact copy of the exemplar, search finds the copy's matches at distance ~0,
    /// repairing scattered wrong matches from their neighbours' predictions.
    #[test]
    fn search_locks_onto_an_exact_copy() {
        let (w, h) = (32, 28);
        let data: Vec<f32> = (0..w * h).map(|i| (mix64(i as u64) % 1000) as f32 / 1000.0).collect();
        let image = Image2d::from_data(w, h, Channel::grey(), data.clone()).unwrap();
        let ex = Prepared::new(&image, &[1.0], PrepareOptions { n: 4, variance: 0.999, max_dims: 16, k: 4 });
        let (gw, gh, ox, oy) = (12, 10, 9, 8);
        let copy: Vec<f32> = (0..gw * gh).map(|i| data[(i / gw + oy) * w + i % gw + ox]).collect();
        let grid = Grid { dims: [gw, gh, 1], channels: 1, data: copy, wrap: [false; 3] };
        let truth: Vec<u32> = (0..gw * gh).map(|i| ((i / gw + oy) * w + i % gw + ox) as u32).collect();
        let centre = ex.centres[ex.centres.len() / 2];
        let damaged: Vec<u32> = truth.iter().enumerate().map(|(i, p)| if i % 7 == 3 { centre } else { *p }).collect();
        let mut previous =
            [Matches::default(), Matches::default(), Matches { pixel: damaged, dist: vec![1.0; gw * gh] }];
        let setup = SearchSetup { exemplars: [None, None, Some(&ex)], anti_sweeping: false, seed: 1, fresh: false };
        let (found, _) = search(&grid, &previous, &setup, &crate::progress::NoProgress).unwrap();
        previous = found;
        let inner = |i: usize| (2..gw - 2).contains(&(i % gw)) && (2..gh - 2).contains(&(i / gw));
        for i in (0..gw * gh).filter(|i| inner(*i)) {
            assert_eq!(previous[2].pixel[i], truth[i], "voxel {i}");
            assert!(previous[2].dist[i] < 1e-2, "voxel {i}: {}", previous[2].dist[i]);
        }
    }
    /// The AVX2 copy of the search and the plain one give the same bits: a volume made on
    /// a machine without AVX2 equals one made with it. Three RGB axes, 6 PCA dimensions
    /// (groups of 4 and 2) and a row of 21 voxels (two blocks of 8 lanes and 5 more).
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_search_equals_the_plain_one() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let (w, h) = (24, 20);
        let data: Vec<f32> = (0..w * h * 3).map(|i| (mix64(i as u64) % 1000) as f32 / 1000.0).collect();
        let image = Image2d::from_data(w, h, Channel::rgb(), data).unwrap();
        let ex = Prepared::new(&image, &[1.0; 3], PrepareOptions { n: 4, variance: 1.0, max_dims: 6, k: 3 });
        assert_eq!(ex.pca.dims, 6);
        let dims = [21, 6, 5];
        let count = dims.iter().product::<usize>();
        let samples = (0..count * 3).map(|i| (mix64(i as u64 ^ 77) % 1000) as f32 / 1000.0).collect();
        let grid = Grid { dims, channels: 3, data: samples, wrap: [true, false, true] };
        let previous: [Matches; 3] = std::array::from_fn(|a| Matches {
            pixel: (0..count)
                .map(|i| ex.centres[(mix64((i * 3 + a) as u64) % ex.centres.len() as u64) as usize])
                .collect(),
            dist: vec![1.0; count],
        });
        for (z, fresh) in (0..dims[2]).flat_map(|z| [(z, false), (z, true)]) {
            let setup = SearchSetup { exemplars: [Some(&ex); 3], anti_sweeping: true, seed: 5, fresh };
            // SAFETY: AVX2 was detected above.
            #[allow(unsafe_code)]
            let (fast, sum_fast) = unsafe { search_slice_avx2(&grid, &previous, &setup, z) };
            let (plain, sum_plain) = search_slice_in(&grid, &previous, &setup, z);
            assert_eq!(sum_fast.to_bits(), sum_plain.to_bits(), "slice {z}");
            for axis in 0..3 {
                let bits = |m: &[(f32, u32)]| m.iter().map(|(d, p)| (d.to_bits(), *p)).collect::<Vec<_>>();
                assert_eq!(bits(&fast[axis]), bits(&plain[axis]), "slice {z}, axis {axis}");
            }
        }
    }
}
