//! An exact k-nearest-neighbour kd-tree over points of any (runtime) dimension.
//! Ties are broken by the lower point index, so answers never depend on build order.

/// A kd-tree over `count` points of `dims` f32 values each.
#[derive(Debug, Clone)]
pub struct KdTree {
    dims: usize,
    points: Vec<f32>,
    order: Vec<u32>,
    nodes: Vec<Node>,
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
        let count = points.len() / dims.max(1);
        let mut tree = KdTree { dims, points, order: (0..count as u32).collect(), nodes: Vec::new() };
        tree.split(0, count);
        // Store the points in leaf order, so a leaf's points are read one after another.
        let leaf_order = tree.order.iter().flat_map(|&i| tree.point(i).iter().copied()).collect();
        tree.points = leaf_order;
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
        let mut best: Vec<Hit> = Vec::with_capacity(k + 1);
        if !self.nodes.is_empty() && k > 0 {
            let mut offsets = vec![0.0; self.dims];
            self.visit(0, query, k, &mut best, 0.0, &mut offsets);
        }
        best
    }

    /// Search below `node`, whose cell lies at squared distance at least `reach` from the
    /// query; `offsets` holds the per-axis query-to-cell offsets that make up `reach`
    /// (Arya and Mount's incremental distance: a tighter bound than the split plane alone).
    fn visit(&self, node: u32, query: &[f32], k: usize, best: &mut Vec<Hit>, reach: f32, offsets: &mut [f32]) {
        match self.nodes[node as usize] {
            Node::Leaf { start, end } => {
                for at in start..end {
                    let d = squared(self.point(at), query);
                    insert(best, k, (d, self.order[at as usize]));
                }
            }
            Node::Split { axis, value, left, right } => {
                let axis = axis as usize;
                let diff = query[axis] - value;
                let (near, far) = if diff < 0.0 { (left, right) } else { (right, left) };
                self.visit(near, query, k, best, reach, offsets);
                let old = offsets[axis];
                let far_reach = reach - old * old + diff * diff;
                if best.len() < k || far_reach <= best[best.len() - 1].0 {
                    offsets[axis] = diff;
                    self.visit(far, query, k, best, far_reach, offsets);
                    offsets[axis] = old;
                }
            }
        }
    }
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
}
