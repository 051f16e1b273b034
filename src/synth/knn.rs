//! A k-nearest-neighbour kd-tree over points of any (runtime) dimension: exact, or among
//! the first points a search weighs within a budget. An exact search breaks ties by the
//! lower point index, so its answers never depend on build order.
//!
//! Points equal bit for bit are kept once, with the indices of their copies: an exemplar's
//! flat areas give thousands of equal neighbourhoods, and a search in one of them would
//! otherwise weigh every copy to settle the tie (tens of times the time of a textured
//! exemplar). A point with copies weighs as many points as it has against a budget, so
//! the answers are those of the tree over every copy.

use std::collections::HashMap;

/// A kd-tree over `count` points of `dims` f32 values each.
#[derive(Debug, Clone)]
pub struct KdTree {
    dims: usize,
    points: Vec<f32>,
    order: Vec<u32>,
    nodes: Vec<Node>,
    /// Per distinct point (in first-seen order), where its copies start in `copies`.
    starts: Vec<u32>,
    /// The indices of every distinct point's copies, each list ascending.
    copies: Vec<u32>,
    /// Per leaf position, its point's lowest index and how many copies it has (most points
    /// have one: a search reads these side by side with the points, without `copies`).
    firsts: Vec<(u32, u32)>,
}

#[derive(Debug, Clone, Copy)]
enum Node {
    Leaf { start: u32, end: u32 },
    Split { axis: u32, value: f32, left: u32, right: u32 },
}

const LEAF: usize = 12;

/// A neighbour: squared distance and point index.
pub type Hit = (f32, u32);

impl KdTree {
    /// Build over row-major `points` (length a multiple of `dims`).
    pub fn build(points: Vec<f32>, dims: usize) -> KdTree {
        let (points, starts, copies) = distinct(points, dims);
        let count = starts.len() - 1;
        let order = (0..count as u32).collect();
        let mut tree = KdTree { dims, points, order, nodes: Vec::new(), starts, copies, firsts: Vec::new() };
        tree.split(0, count);
        // Store the points in leaf order, so a leaf's points are read one after another.
        let leaf_order = tree.order.iter().flat_map(|&i| tree.point(i).iter().copied()).collect();
        tree.points = leaf_order;
        tree.firsts = tree.order.iter().map(|&u| (tree.copies_of(u)[0], tree.copies_of(u).len() as u32)).collect();
        tree
    }

    /// The point at position `i` of `points` (the input index while building, the leaf
    /// position after).
    fn point(&self, i: u32) -> &[f32] {
        &self.points[i as usize * self.dims..(i as usize + 1) * self.dims]
    }

    /// Build the subtree over `order[start..end]`; returns its node index.
    fn split(&mut self, start: usize, end: usize) -> u32 {
        let id = self.nodes.len() as u32;
        if end - start <= LEAF || self.dims == 0 {
            self.nodes.push(Node::Leaf { start: start as u32, end: end as u32 });
            return id;
        }
        let axis = self.widest_axis(start, end);
        let mid = (start + end) / 2;
        let (dims, points) = (self.dims, &self.points);
        let key = |i: &u32| points[*i as usize * dims + axis];
        self.order[start..end].select_nth_unstable_by(mid - start, |a, b| key(a).total_cmp(&key(b)).then(a.cmp(b)));
        let value = key(&self.order[mid]);
        self.nodes.push(Node::Leaf { start: 0, end: 0 });
        let left = self.split(start, mid);
        let right = self.split(mid, end);
        self.nodes[id as usize] = Node::Split { axis: axis as u32, value, left, right };
        id
    }

    fn widest_axis(&self, start: usize, end: usize) -> usize {
        (0..self.dims)
            .map(|a| {
                let values = self.order[start..end].iter().map(|i| self.points[*i as usize * self.dims + a]);
                let (lo, hi) = values.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
                (hi - lo, a)
            })
            .fold((f32::MIN, 0), |best, c| if c.0 > best.0 { c } else { best })
            .1
    }

    /// Dimensions.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// The `k` nearest points to `query`, nearest first.
    pub fn nearest(&self, query: &[f32], k: usize) -> Vec<Hit> {
        self.nearest_within(query, k, usize::MAX)
    }

    /// The `k` nearest points to `query` among about the first `budget` the search
    /// weighs, nearest first: the query's own cell first, then the cells beside it, so a
    /// budget of a few leaves finds most true neighbours in a fraction of the time (a tree
    /// over many dimensions otherwise weighs most of its points before it can prove the
    /// answer exact).
    pub fn nearest_within(&self, query: &[f32], k: usize, budget: usize) -> Vec<Hit> {
        let mut best: Vec<Hit> = Vec::with_capacity(k + 1);
        if !self.nodes.is_empty() && k > 0 {
            let mut offsets = vec![0.0; self.dims];
            let mut search = Search { query, k, best: &mut best, offsets: &mut offsets, left: budget };
            self.visit(0, &mut search, 0.0);
        }
        best
    }

    /// Search below `node`, whose cell lies at squared distance at least `reach` from the
    /// query; `search.offsets` holds the per-axis query-to-cell offsets that make up
    /// `reach` (Arya and Mount's incremental distance: a tighter bound than the split
    /// plane alone).
    fn visit(&self, node: u32, search: &mut Search, reach: f32) {
        match self.nodes[node as usize] {
            Node::Leaf { start, end } => {
                for at in start..end {
                    let d = squared(self.point(at), search.query);
                    let (first, count) = self.firsts[at as usize];
                    if count == 1 {
                        insert(search.best, search.k, (d, first));
                    } else {
                        // equal distances: the lower indices come first, the rest cannot get in
                        for &index in self.copies_of(self.order[at as usize]).iter().take(search.k) {
                            insert(search.best, search.k, (d, index));
                        }
                    }
                    search.left = search.left.saturating_sub(count as usize);
                }
            }
            Node::Split { axis, value, left, right } => {
                let axis = axis as usize;
                let diff = search.query[axis] - value;
                let (near, far) = if diff < 0.0 { (left, right) } else { (right, left) };
                self.visit(near, search, reach);
                let old = search.offsets[axis];
                let far_reach = reach - old * old + diff * diff;
                let full = search.best.len() == search.k;
                if search.left > 0 && (!full || far_reach <= search.best[search.k - 1].0) {
                    search.offsets[axis] = diff;
                    self.visit(far, search, far_reach);
                    search.offsets[axis] = old;
                }
            }
        }
    }
}

impl KdTree {
    /// The indices of distinct point `u`'s copies, ascending.
    fn copies_of(&self, u: u32) -> &[u32] {
        &self.copies[self.starts[u as usize] as usize..self.starts[u as usize + 1] as usize]
    }
}

/// The distinct points of row-major `points` in first-seen order, where each one's copies
/// start (one more entry than points, the last the end), and the copies' indices.
fn distinct(points: Vec<f32>, dims: usize) -> (Vec<f32>, Vec<u32>, Vec<u32>) {
    let count = points.len() / dims.max(1);
    if dims == 0 {
        return (points, (0..=count as u32).collect(), (0..count as u32).collect());
    }
    let mut first: HashMap<Vec<u32>, u32> = HashMap::with_capacity(count);
    let mut of_point = Vec::with_capacity(count);
    let mut unique = Vec::with_capacity(points.len());
    for p in points.chunks_exact(dims) {
        let next = first.len() as u32;
        let u = *first.entry(p.iter().map(|v| v.to_bits()).collect()).or_insert(next);
        if u == next {
            unique.extend_from_slice(p);
        }
        of_point.push(u);
    }
    let mut starts = vec![0u32; first.len() + 1];
    for &u in &of_point {
        starts[u as usize + 1] += 1;
    }
    for u in 0..first.len() {
        starts[u + 1] += starts[u];
    }
    let mut next = starts.clone();
    let mut copies = vec![0u32; count];
    for (i, &u) in of_point.iter().enumerate() {
        copies[next[u as usize] as usize] = i as u32;
        next[u as usize] += 1;
    }
    (unique, starts, copies)
}

/// One search's state: the query, how many it wants, the best so far, the offsets of the
/// current cell, and how many more points it may weigh.
struct Search<'a> {
    query: &'a [f32],
    k: usize,
    best: &'a mut Vec<Hit>,
    offsets: &'a mut [f32],
    left: usize,
}

/// Squared Euclidean distance, summed in eight independent lanes (the search's hottest
/// loop: one long chain of additions would wait on each one in turn). The lane order is
/// fixed, so the result is the same on every machine.
#[inline(always)]
pub fn squared(a: &[f32], b: &[f32]) -> f32 {
    lane_sum(a, b, |x, y| (x - y) * (x - y))
}

/// The sum of `term` over pairs of `a` and `b`, in eight lanes added in a fixed order.
#[inline(always)]
pub fn lane_sum(a: &[f32], b: &[f32], term: impl Fn(f32, f32) -> f32) -> f32 {
    const LANES: usize = 8;
    let mut acc = [0.0f32; LANES];
    let (xs, ys) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (x_rest, y_rest) = (xs.remainder(), ys.remainder());
    for (x, y) in xs.zip(ys) {
        for l in 0..LANES {
            acc[l] += term(x[l], y[l]);
        }
    }
    for (l, (x, y)) in x_rest.iter().zip(y_rest).enumerate() {
        acc[l] += term(*x, *y);
    }
    let half = [acc[0] + acc[4], acc[1] + acc[5], acc[2] + acc[6], acc[3] + acc[7]];
    (half[0] + half[2]) + (half[1] + half[3])
}

/// Insert into a sorted list kept at most `k` long; ties go to the lower index.
fn insert(best: &mut Vec<Hit>, k: usize, hit: Hit) {
    let before = |a: &Hit, b: &Hit| a.0 < b.0 || (a.0 == b.0 && a.1 < b.1);
    if best.len() == k && !before(&hit, &best[k - 1]) {
        return;
    }
    let at = best.iter().position(|b| before(&hit, b)).unwrap_or(best.len());
    best.insert(at, hit);
    best.truncate(k);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let dims = 5;
        let points: Vec<f32> = (0..900).map(|i| ((i * 7919) % 1000) as f32 / 1000.0).collect();
        let tree = KdTree::build(points.clone(), dims);
        for q in 0..20 {
            let query: Vec<f32> = (0..dims).map(|j| ((q * 31 + j * 17) % 100) as f32 / 100.0).collect();
            let got = tree.nearest(&query, 4);
            let mut all: Vec<Hit> =
                (0..180).map(|i| (squared(&points[i * dims..(i + 1) * dims], &query), i as u32)).collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(got, all[..4].to_vec());
        }
    }

    /// Points with many copies give the answers of a brute-force search (lower indices
    /// first among equal distances), and a search weighs each copy against its budget.
    #[test]
    fn copies_of_a_point_answer_as_every_copy_would() {
        let dims = 3;
        let point = |i: usize| -> [f32; 3] {
            match i % 5 {
                0..=2 => [0.5, 0.5, 0.5],
                3 => [0.25, 0.5, 0.75],
                _ => [(i % 7) as f32 / 7.0, (i % 11) as f32 / 11.0, 0.1],
            }
        };
        let points: Vec<f32> = (0..600).flat_map(point).collect();
        let tree = KdTree::build(points.clone(), dims);
        for query in [[0.5, 0.5, 0.5], [0.3, 0.5, 0.7], [0.0, 0.0, 0.1], [0.9, 0.2, 0.4]] {
            let mut all: Vec<Hit> = (0..600).map(|i| (squared(&point(i), &query), i as u32)).collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(tree.nearest(&query, 5), all[..5].to_vec(), "{query:?}");
        }
        // a budget of one point still answers, from the first leaf's first point
        assert_eq!(tree.nearest_within(&[0.5, 0.5, 0.5], 4, 1).len(), 4);
    }

    /// Within a budget of eight leaves, a search over 4,000 uniform points in 6 dimensions
    /// (no structure to help it: 146 of 200 measured) finds the exact nearest point for
    /// most queries and always as many points as asked, nearest first; a budget of every
    /// point is the exact search.
    #[test]
    fn a_budget_of_a_few_leaves_finds_most_nearest_points() {
        let dims = 6;
        let value = |i: usize| (crate::noise::mix64(i as u64) % 10_000) as f32 / 10_000.0;
        let points: Vec<f32> = (0..4000 * dims).map(value).collect();
        let tree = KdTree::build(points.clone(), dims);
        let mut right = 0;
        for q in 0..200 {
            let query: Vec<f32> = (0..dims).map(|j| value(1_000_000 + q * dims + j)).collect();
            let exact = tree.nearest(&query, 8);
            let within = tree.nearest_within(&query, 8, 8 * LEAF);
            assert_eq!(within.len(), 8);
            assert!(within.windows(2).all(|w| w[0].0 <= w[1].0), "nearest first");
            right += usize::from(within[0] == exact[0]);
            assert_eq!(tree.nearest_within(&query, 8, usize::MAX), exact);
        }
        assert!(right >= 130, "{right} of 200 queries found the nearest point");
    }
}
