//! The voxels on-demand synthesis touches: a mask per pyramid level and version, and a
//! store that holds values only where a mask says so.
//!
//! ```text
//!  finest level, last version:  the voxels asked for (a cut, a surface, the whole solid)
//!  version i - 1:               version i grown by the reach of one correction
//!  coarser level, last version: the parents of the finer level's version 0
//! ```
//!
//! Every voxel of a version is computed from voxels of the version before that lie in a
//! cube of the reach around it, so a region synthesized alone equals the same region of
//! a full run, whatever else is asked for.

use rayon::prelude::*;

/// Side of the bricks masks and stores are kept in.
pub const BRICK: usize = 8;

/// One brick's flags: 64 rows (`y + 8 z`) of 8 bits (bit `x`).
pub type Bits = [u8; BRICK * BRICK];

/// The voxel of index `i` of a grid of `dims` voxels, x fastest.
pub fn grid_voxel(dims: [usize; 3], i: usize) -> [usize; 3] {
    [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])]
}

/// The index of voxel `v` of a grid of `dims` voxels, x fastest.
pub fn grid_index(dims: [usize; 3], v: [usize; 3]) -> usize {
    v[0] + dims[0] * (v[1] + dims[1] * v[2])
}

/// A set of voxels of a grid, kept as flags in 8³ bricks stored only where the set has a
/// voxel: a cut's thin slab through a grid of 1024 voxels a side costs memory in proportion
/// to the slab, not the grid.
#[derive(Debug, Clone)]
pub struct Mask {
    /// Grid size.
    pub dims: [usize; 3],
    /// Bricks per axis.
    bricks: [usize; 3],
    /// Per brick, its slot in `bits` (`u32::MAX`: no voxel there).
    table: Vec<u32>,
    /// Per stored brick, its flags.
    bits: Vec<Bits>,
    /// Per stored brick, its brick coordinates.
    stored: Vec<[usize; 3]>,
}

impl Mask {
    /// No voxel.
    pub fn empty(dims: [usize; 3]) -> Mask {
        let bricks = dims.map(|d| d.div_ceil(BRICK));
        Mask { dims, bricks, table: vec![u32::MAX; bricks.iter().product()], bits: Vec::new(), stored: Vec::new() }
    }

    /// Every voxel.
    pub fn full(dims: [usize; 3]) -> Mask {
        let mut out = Mask::empty(dims);
        for z in 0..out.bricks[2] {
            for y in 0..out.bricks[1] {
                for x in 0..out.bricks[0] {
                    let b = [x, y, z];
                    out.store(b, out.inside(b));
                }
            }
        }
        out
    }

    /// Whether voxel `v` (inside the grid) is in the set.
    pub fn contains(&self, v: [usize; 3]) -> bool {
        let slot = self.table[self.brick_index(v.map(|c| c / BRICK))];
        slot != u32::MAX && {
            let [x, y, z] = v.map(|c| c % BRICK);
            self.bits[slot as usize][y + BRICK * z] >> x & 1 == 1
        }
    }

    /// Put voxel `v` (inside the grid) in the set.
    pub fn insert(&mut self, v: [usize; 3]) {
        let b = v.map(|c| c / BRICK);
        let slot = match self.table[self.brick_index(b)] {
            u32::MAX => self.store(b, [0; BRICK * BRICK]),
            s => s as usize,
        };
        let [x, y, z] = v.map(|c| c % BRICK);
        self.bits[slot][y + BRICK * z] |= 1 << x;
    }

    /// How many voxels are in the set.
    pub fn count(&self) -> usize {
        self.bits.iter().flatten().map(|row| row.count_ones() as usize).sum()
    }

    /// Whether every voxel of the grid is in the set.
    pub fn is_full(&self) -> bool {
        self.count() == self.dims.iter().product::<usize>()
    }

    /// The stored bricks: their brick coordinates and flags.
    pub fn bricks(&self) -> impl Iterator<Item = ([usize; 3], &Bits)> {
        self.stored.iter().copied().zip(&self.bits)
    }

    /// The voxels in the set, brick by brick.
    pub fn voxels(&self) -> impl Iterator<Item = [usize; 3]> + '_ {
        self.bricks().flat_map(|(b, bits)| {
            (0..BRICK * BRICK * BRICK).filter(|k| bits[k / BRICK] >> (k % BRICK) & 1 == 1).map(move |k| in_brick(b, k))
        })
    }

    /// The set grown by a cube of `reach` voxels each way (clipped to the grid).
    pub fn grown(&self, reach: usize) -> Mask {
        self.grown_box([reach; 3])
    }

    /// The set grown by every voxel a point within `radius` of a voxel's centre falls in:
    /// the offsets whose voxel cube comes within `radius` of the centre (clipped to the
    /// grid). A rounded cube: for a neighbourhood of 5 (radius 2√2) the 5³ cube and a 3 x 3
    /// patch on each face, 179 offsets against the 343 of the 7³ cube that holds them.
    pub fn grown_round(&self, radius: f32) -> Mask {
        let grown = round_boxes(radius).into_iter().map(|b| self.grown_box(b));
        grown.reduce(|a, b| a.union(&b)).unwrap_or_else(|| self.clone())
    }

    /// The set grown by `reach[a]` voxels each way along axis `a` (clipped to the grid):
    /// per axis, each brick's rows widened by at most one brick's side at a time.
    fn grown_box(&self, reach: [usize; 3]) -> Mask {
        let mut out = self.clone();
        for (axis, &reach) in reach.iter().enumerate() {
            let mut left = reach;
            while left > 0 {
                let step = left.min(BRICK);
                out = out.grown_along(axis, step);
                left -= step;
            }
        }
        out
    }

    /// Grown along `axis` by `reach` ≤ [`BRICK`]: every stored brick and its two
    /// neighbours along the axis take the flags within `reach` of theirs.
    fn grown_along(&self, axis: usize, reach: usize) -> Mask {
        let mut candidates = Mask::empty(self.dims);
        for &b in &self.stored {
            for step in [-1i64, 0, 1] {
                let mut n = b.map(|c| c as i64);
                n[axis] += step;
                if (0..3).all(|a| n[a] >= 0 && (n[a] as usize) < self.bricks[a]) {
                    let n = n.map(|c| c as usize);
                    if candidates.table[candidates.brick_index(n)] == u32::MAX {
                        candidates.store(n, [0; BRICK * BRICK]);
                    }
                }
            }
        }
        let empty = [0u8; BRICK * BRICK];
        let neighbour = |b: [usize; 3], step: i64| -> &Bits {
            let c = b[axis] as i64 + step;
            if c < 0 || c as usize >= self.bricks[axis] {
                return &empty;
            }
            let mut n = b;
            n[axis] = c as usize;
            match self.table[self.brick_index(n)] {
                u32::MAX => &empty,
                s => &self.bits[s as usize],
            }
        };
        let grown: Vec<Bits> = candidates
            .stored
            .par_iter()
            .map(|&b| {
                let rows = [neighbour(b, -1), neighbour(b, 0), neighbour(b, 1)];
                let inside = self.inside(b);
                let mut out = widened(rows, axis, reach);
                for (o, keep) in out.iter_mut().zip(&inside) {
                    *o &= keep;
                }
                out
            })
            .collect();
        let mut out = Mask::empty(self.dims);
        for (b, bits) in candidates.stored.iter().zip(grown) {
            if bits.iter().any(|r| *r != 0) {
                out.store(*b, bits);
            }
        }
        out
    }

    /// The voxels of the set or of `other` (a mask of the same grid).
    pub fn union(&self, other: &Mask) -> Mask {
        let mut out = self.clone();
        for (b, bits) in other.bricks() {
            match out.table[out.brick_index(b)] {
                u32::MAX => _ = out.store(b, *bits),
                s => out.bits[s as usize].iter_mut().zip(bits).for_each(|(row, t)| *row |= t),
            }
        }
        out
    }

    /// The voxels of the set that `other` (a mask of the same grid) does not hold.
    pub fn without(&self, other: &Mask) -> Mask {
        let mut out = Mask::empty(self.dims);
        for (b, bits) in self.bricks() {
            let mut left = *bits;
            if let Some(theirs) = other.brick(b) {
                left.iter_mut().zip(theirs).for_each(|(row, t)| *row &= !t);
            }
            if left.iter().any(|r| *r != 0) {
                out.store(b, left);
            }
        }
        out
    }

    /// The flags of brick `b`, if it is stored.
    pub fn brick(&self, b: [usize; 3]) -> Option<&Bits> {
        match self.table[self.brick_index(b)] {
            u32::MAX => None,
            s => Some(&self.bits[s as usize]),
        }
    }

    /// The parents (voxel `v / 2`) of the voxels in the set, on a grid of `coarse` voxels.
    pub fn parents(&self, coarse: [usize; 3]) -> Mask {
        let mut out = Mask::empty(coarse);
        for v in self.voxels() {
            out.insert([0, 1, 2].map(|a| (v[a] / 2).min(coarse[a] - 1)));
        }
        out
    }

    fn brick_index(&self, b: [usize; 3]) -> usize {
        b[0] + self.bricks[0] * (b[1] + self.bricks[1] * b[2])
    }

    /// Store brick `b` with `bits`; its slot.
    fn store(&mut self, b: [usize; 3], bits: Bits) -> usize {
        let at = self.brick_index(b);
        self.table[at] = self.bits.len() as u32;
        self.bits.push(bits);
        self.stored.push(b);
        self.bits.len() - 1
    }

    /// The flags of brick `b`'s voxels that lie inside the grid.
    fn inside(&self, b: [usize; 3]) -> Bits {
        let within = |a: usize, k: usize| b[a] * BRICK + k < self.dims[a];
        let row: u8 = (0..BRICK).filter(|&x| within(0, x)).map(|x| 1u8 << x).sum();
        std::array::from_fn(|k| if within(1, k % BRICK) && within(2, k / BRICK) { row } else { 0 })
    }
}

/// Brick `b`'s voxel of in-brick index `k` (x fastest).
fn in_brick(b: [usize; 3], k: usize) -> [usize; 3] {
    [b[0] * BRICK + k % BRICK, b[1] * BRICK + (k / BRICK) % BRICK, b[2] * BRICK + k / (BRICK * BRICK)]
}

/// The middle brick of `rows` (the bricks before, at and after it along `axis`) with every
/// flag spread `reach` ≤ [`BRICK`] voxels each way along the axis.
/// The largest voxel offsets (one octant, per axis) whose voxel cube comes within
/// `radius` of the centre: the corners of the boxes whose union holds every such offset
/// (the set is the same in every octant and shrinks as any coordinate grows).
fn round_boxes(radius: f32) -> Vec<[usize; 3]> {
    let most = (radius + 0.5).ceil() as usize;
    let gap = |c: usize| (c as f32 - 0.5).max(0.0);
    let within = |o: [usize; 3]| o.iter().map(|&c| gap(c) * gap(c)).sum::<f32>() <= radius * radius;
    let all: Vec<[usize; 3]> = (0..=most)
        .flat_map(|x| (0..=most).flat_map(move |y| (0..=most).map(move |z| [x, y, z])))
        .filter(|o| within(*o))
        .collect();
    let covered = |o: &[usize; 3], by: &[usize; 3]| o != by && (0..3).all(|a| o[a] <= by[a]);
    all.iter().filter(|o| !all.iter().any(|by| covered(o, by))).copied().collect()
}

fn widened(rows: [&Bits; 3], axis: usize, reach: usize) -> Bits {
    let mut out = [0u8; BRICK * BRICK];
    if axis == 0 {
        for (k, o) in out.iter_mut().enumerate() {
            let w = rows[0][k] as u32 | (rows[1][k] as u32) << BRICK | (rows[2][k] as u32) << (2 * BRICK);
            let spread = (0..=reach).fold(0, |acc, s| acc | w << s | w >> s);
            *o = (spread >> BRICK) as u8;
        }
        return out;
    }
    // rows along y (axis 1) or z (axis 2): the other of the two is the row's fixed coordinate
    let at = |c: usize, other: usize| if axis == 1 { c + BRICK * other } else { other + BRICK * c };
    for other in 0..BRICK {
        for c in 0..BRICK {
            let mut row = 0u8;
            for s in c as i64 - reach as i64..=c as i64 + reach as i64 {
                let (brick, k) = (s.div_euclid(BRICK as i64) + 1, s.rem_euclid(BRICK as i64) as usize);
                row |= rows[brick as usize][at(k, other)];
            }
            out[at(c, other)] = row;
        }
    }
    out
}

/// Values on the voxels of a mask, stored in the mask's 8³ bricks: a cut's thin slab costs
/// memory in proportion to its own size.
#[derive(Debug, Clone)]
pub struct Sparse<T> {
    /// Grid size.
    pub dims: [usize; 3],
    /// The voxels that hold a value.
    mask: Mask,
    /// `BRICK³` values per stored brick of the mask.
    values: Vec<T>,
}

impl<T: Copy + Default + Send + Sync> Sparse<T> {
    /// A store for the voxels of `mask`, each computed by `value` (in parallel, by brick).
    pub fn compute(mask: &Mask, value: impl Fn([usize; 3]) -> T + Sync) -> Sparse<T> {
        Sparse::compute_unless(mask, &|| false, value)
    }

    /// [`Sparse::compute`], asking `stop` before each brick: once it says yes, the bricks
    /// not yet begun keep `T::default()` (the caller throws the store away).
    pub fn compute_unless(
        mask: &Mask,
        stop: &(dyn Fn() -> bool + Sync),
        value: impl Fn([usize; 3]) -> T + Sync,
    ) -> Sparse<T> {
        let cube = BRICK * BRICK * BRICK;
        let mut values = vec![T::default(); mask.stored.len() * cube];
        values.par_chunks_mut(cube).zip(mask.stored.par_iter().zip(&mask.bits)).for_each(|(chunk, (b, bits))| {
            if stop() {
                return;
            }
            for (k, out) in chunk.iter_mut().enumerate() {
                if bits[k / BRICK] >> (k % BRICK) & 1 == 1 {
                    *out = value(in_brick(*b, k));
                }
            }
        });
        Sparse { dims: mask.dims, mask: mask.clone(), values }
    }

    /// The value at voxel `v` clamped into the grid; `T::default()` where nothing is stored.
    #[inline(always)]
    pub fn at(&self, v: [i64; 3]) -> T {
        let clamped = |a: usize| v[a].clamp(0, self.dims[a] as i64 - 1) as usize;
        let c = [clamped(0), clamped(1), clamped(2)];
        let b = [c[0] / BRICK, c[1] / BRICK, c[2] / BRICK];
        let slot = self.mask.table[self.mask.brick_index(b)];
        if slot == u32::MAX {
            return T::default();
        }
        let k = c[0] % BRICK + BRICK * (c[1] % BRICK + BRICK * (c[2] % BRICK));
        self.values[slot as usize * BRICK * BRICK * BRICK + k]
    }

    /// A store of whole bricks: each its brick coordinates, the flags of the voxels it
    /// holds (those outside the grid dropped) and `BRICK³` values (x fastest); a brick
    /// given twice keeps its first.
    pub fn from_bricks(dims: [usize; 3], bricks: impl IntoIterator<Item = ([usize; 3], Bits, Vec<T>)>) -> Sparse<T> {
        let mut mask = Mask::empty(dims);
        let mut values = Vec::new();
        for (b, bits, brick) in bricks {
            let inside = (0..3).all(|a| b[a] < mask.bricks[a]) && brick.len() == BRICK * BRICK * BRICK;
            if !inside || mask.brick(b).is_some() {
                continue;
            }
            let within = mask.inside(b);
            mask.store(b, std::array::from_fn(|k| bits[k] & within[k]));
            values.extend(brick);
        }
        Sparse { dims, mask, values }
    }

    /// The same voxels, each value turned by `f`.
    pub fn map<U: Copy + Default + Send + Sync>(&self, f: impl Fn(T) -> U + Sync) -> Sparse<U> {
        use rayon::prelude::*;
        Sparse { dims: self.dims, mask: self.mask.clone(), values: self.values.par_iter().map(|v| f(*v)).collect() }
    }

    /// This store's values over `older`'s (a store of the same grid) where this one holds
    /// none: this store's bricks first, then `older`'s others, at most `most` bricks.
    pub fn over(&self, older: &Sparse<T>, most: usize) -> Sparse<T> {
        let cube = BRICK * BRICK * BRICK;
        let brick_of = |s: &Sparse<T>, slot: usize| s.values[slot * cube..(slot + 1) * cube].to_vec();
        let newer = self.mask.bricks().enumerate().map(|(slot, (b, bits))| {
            let mut values = brick_of(self, slot);
            let mut bits = *bits;
            if let Some(old) = older.mask.table.get(older.mask.brick_index(b)).filter(|s| **s != u32::MAX) {
                let theirs = brick_of(older, *old as usize);
                for k in 0..cube {
                    let (row, bit) = (k / BRICK, 1u8 << (k % BRICK));
                    if bits[row] & bit == 0 && older.mask.bits[*old as usize][row] & bit != 0 {
                        values[k] = theirs[k];
                        bits[row] |= bit;
                    }
                }
            }
            (b, bits, values)
        });
        let rest = older
            .mask
            .bricks()
            .enumerate()
            .filter(|(_, (b, _))| self.mask.brick(*b).is_none())
            .map(|(slot, (b, bits))| (b, *bits, brick_of(older, slot)));
        Sparse::from_bricks(self.dims, newer.chain(rest).take(most))
    }

    /// The stored bricks: their brick coordinates, flags and `BRICK³` values.
    pub fn bricks(&self) -> impl Iterator<Item = ([usize; 3], &Bits, &[T])> {
        let cube = BRICK * BRICK * BRICK;
        self.mask.bricks().zip(self.values.chunks_exact(cube)).map(|((b, bits), values)| (b, bits, values))
    }

    /// The voxels that hold a value.
    pub fn mask(&self) -> &Mask {
        &self.mask
    }

    /// Whether voxel `v` (inside the grid) holds a value.
    pub fn holds(&self, v: [usize; 3]) -> bool {
        self.mask.contains(v)
    }

    /// Bytes the values take.
    pub fn bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<T>() + self.mask.table.len() * 4
    }

    /// How many bricks are stored.
    pub fn brick_count(&self) -> usize {
        self.mask.stored.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Growing a single voxel by 2 gives the 5³ cube around it, clipped at the grid's edge.
    #[test]
    fn growing_gives_the_cube_of_the_reach() {
        let dims = [9, 7, 6];
        let mut m = Mask::empty(dims);
        m.insert([1, 3, 3]);
        let g = m.grown(2);
        for i in 0..dims.iter().product() {
            let v = grid_voxel(dims, i);
            let want = v[0] <= 3 && (1..=5).contains(&v[1]) && (1..=5).contains(&v[2]);
            assert_eq!(g.contains(v), want, "voxel {v:?}");
        }
        assert_eq!(g.count(), 4 * 5 * 5);
    }

    /// Grown by reaches within, at and beyond a brick's side, scattered voxels give what
    /// checking every voxel's distance to them gives, and a full mask holds every voxel.
    #[test]
    fn growing_across_bricks_equals_the_distance_test() {
        let dims = [37, 21, 30];
        let seeds = [[0, 0, 0], [36, 20, 29], [8, 7, 15], [17, 0, 23], [30, 12, 1]];
        let mut m = Mask::empty(dims);
        seeds.iter().for_each(|v| m.insert(*v));
        for reach in [1, 3, 8, 11] {
            let g = m.grown(reach);
            let mut count = 0;
            for i in 0..dims.iter().product() {
                let v = grid_voxel(dims, i);
                let near = seeds.iter().any(|s| (0..3).all(|a| s[a].abs_diff(v[a]) <= reach));
                assert_eq!(g.contains(v), near, "reach {reach}, voxel {v:?}");
                count += usize::from(near);
            }
            assert_eq!(g.count(), count);
        }
        let full = Mask::full(dims);
        assert!(full.is_full() && !m.is_full());
        assert_eq!(full.voxels().count(), dims.iter().product::<usize>());
        assert!(full.grown(3).is_full());
    }

    /// Grown round by a radius, a voxel gives the voxels whose cubes come within the
    /// radius of its centre: for 2√2 (a neighbourhood of 5) the 5³ cube and a 3 x 3 patch
    /// on each face; the union of two masks holds what either holds.
    #[test]
    fn growing_round_gives_the_voxels_within_the_radius() {
        let dims = [20, 19, 21];
        let seeds = [[10, 9, 10], [1, 1, 18]];
        let mut m = Mask::empty(dims);
        seeds.iter().for_each(|v| m.insert(*v));
        let radius = 2.0 * std::f32::consts::SQRT_2;
        let g = m.grown_round(radius);
        let gap = |d: usize| (d as f32 - 0.5).max(0.0);
        for i in 0..dims.iter().product() {
            let v = grid_voxel(dims, i);
            let near =
                seeds.iter().any(|s| (0..3).map(|a| gap(s[a].abs_diff(v[a])).powi(2)).sum::<f32>() <= radius * radius);
            assert_eq!(g.contains(v), near, "voxel {v:?}");
        }
        let mut one = Mask::empty(dims);
        one.insert(seeds[0]);
        assert_eq!(one.grown_round(radius).count(), 125 + 6 * 9);
        assert_eq!(round_boxes(radius).len(), 4);
        let (mut a, mut b) = (Mask::empty(dims), Mask::empty(dims));
        a.insert([0, 0, 0]);
        b.insert([19, 18, 20]);
        let both = a.union(&b);
        assert!(both.contains([0, 0, 0]) && both.contains([19, 18, 20]) && both.count() == 2);
    }

    /// Parents halve each coordinate; a store reads back what it computed and clamps.
    #[test]
    fn parents_and_store() {
        let mut m = Mask::empty([10, 4, 3]);
        for v in [[9, 3, 2], [0, 0, 0]] {
            m.insert(v);
        }
        let p = m.parents([5, 2, 2]);
        assert_eq!(p.count(), 2);
        assert!(p.contains([4, 1, 1]) && p.contains([0, 0, 0]));
        let s = Sparse::compute(&m, |v| v[0] as u32 + 100 * v[1] as u32 + 1000 * v[2] as u32);
        assert_eq!(s.at([9, 3, 2]), 2309);
        assert_eq!(s.at([40, 9, 7]), 2309, "clamped into the grid");
        assert_eq!(s.at([0, 0, 0]), 0);
        assert_eq!(s.brick_count(), 2);
    }
}
