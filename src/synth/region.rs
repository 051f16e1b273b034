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

/// A set of voxels of a grid, one flag per voxel, x fastest.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mask {
    /// Grid size.
    pub dims: [usize; 3],
    /// One flag per voxel.
    pub on: Vec<bool>,
}

impl Mask {
    /// No voxel.
    pub fn empty(dims: [usize; 3]) -> Mask {
        Mask { dims, on: vec![false; dims.iter().product()] }
    }

    /// Every voxel.
    pub fn full(dims: [usize; 3]) -> Mask {
        Mask { dims, on: vec![true; dims.iter().product()] }
    }

    /// The index of voxel `v`.
    pub fn index(&self, v: [usize; 3]) -> usize {
        v[0] + self.dims[0] * (v[1] + self.dims[1] * v[2])
    }

    /// How many voxels are in the set.
    pub fn count(&self) -> usize {
        self.on.iter().filter(|b| **b).count()
    }

    /// The set grown by a cube of `reach` voxels each way (clipped to the grid): one 1D
    /// running window per axis.
    pub fn grown(&self, reach: usize) -> Mask {
        let mut out = self.clone();
        for axis in 0..3 {
            out = out.grown_along(axis, reach);
        }
        out
    }

    /// Grown along one axis: the grid seen as blocks of `len` layers of `inner` voxels
    /// (`inner`: the axis' stride), a window of counts sliding over the layers of each block.
    fn grown_along(&self, axis: usize, reach: usize) -> Mask {
        let len = self.dims[axis];
        let inner: usize = self.dims[..axis].iter().product();
        let mut out = Mask::empty(self.dims);
        out.on.par_chunks_mut(len * inner).zip(self.on.par_chunks(len * inner)).for_each(|(out, block)| {
            let layer = |k: usize| &block[k * inner..(k + 1) * inner];
            let mut counts = vec![0u32; inner];
            let add = |counts: &mut [u32], k: usize, sign: i32| {
                for (c, on) in counts.iter_mut().zip(layer(k)) {
                    *c = c.wrapping_add_signed(sign * i32::from(*on));
                }
            };
            // the window [k - reach, k + reach], counted as it slides
            for k in 0..reach.min(len) {
                add(&mut counts, k, 1);
            }
            for k in 0..len {
                if k + reach < len {
                    add(&mut counts, k + reach, 1);
                }
                if k > reach {
                    add(&mut counts, k - reach - 1, -1);
                }
                for (o, c) in out[k * inner..(k + 1) * inner].iter_mut().zip(&counts) {
                    *o = *c > 0;
                }
            }
        });
        out
    }

    /// The parents (voxel `v / 2`) of the voxels in the set, on a grid of `coarse` voxels.
    pub fn parents(&self, coarse: [usize; 3]) -> Mask {
        let mut out = Mask::empty(coarse);
        for (i, _) in self.on.iter().enumerate().filter(|(_, b)| **b) {
            let v = self.voxel(i);
            let p = [0, 1, 2].map(|a| (v[a] / 2).min(coarse[a] - 1));
            let at = out.index(p);
            out.on[at] = true;
        }
        out
    }

    /// The voxel of index `i`.
    pub fn voxel(&self, i: usize) -> [usize; 3] {
        [i % self.dims[0], (i / self.dims[0]) % self.dims[1], i / (self.dims[0] * self.dims[1])]
    }
}

/// Side of the store's bricks.
const BRICK: usize = 8;

/// Values on the voxels of a mask, stored in 8³ bricks allocated only where the mask has
/// a voxel: a cut's thin slab costs memory in proportion to its own size.
#[derive(Debug, Clone)]
pub struct Sparse<T> {
    /// Grid size.
    pub dims: [usize; 3],
    /// Bricks per axis.
    bricks: [usize; 3],
    /// Per brick, its slot in `values` (`u32::MAX`: not stored).
    table: Vec<u32>,
    /// `BRICK³` values per stored brick.
    values: Vec<T>,
    /// Per stored brick, its brick coordinates.
    stored: Vec<[usize; 3]>,
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
        let bricks = mask.dims.map(|d| d.div_ceil(BRICK));
        let mut table = vec![u32::MAX; bricks.iter().product()];
        let mut stored = Vec::new();
        for (i, _) in mask.on.iter().enumerate().filter(|(_, b)| **b) {
            let v = mask.voxel(i);
            let b = v.map(|c| c / BRICK);
            let at = b[0] + bricks[0] * (b[1] + bricks[1] * b[2]);
            if table[at] == u32::MAX {
                table[at] = stored.len() as u32;
                stored.push(b);
            }
        }
        let cube = BRICK * BRICK * BRICK;
        let mut values = vec![T::default(); stored.len() * cube];
        values.par_chunks_mut(cube).zip(&stored).for_each(|(chunk, b)| {
            if stop() {
                return;
            }
            for (k, out) in chunk.iter_mut().enumerate() {
                let v =
                    [b[0] * BRICK + k % BRICK, b[1] * BRICK + (k / BRICK) % BRICK, b[2] * BRICK + k / (BRICK * BRICK)];
                if v.iter().zip(&mask.dims).all(|(c, d)| c < d) && mask.on[mask.index(v)] {
                    *out = value(v);
                }
            }
        });
        Sparse { dims: mask.dims, bricks, table, values, stored }
    }

    /// The value at voxel `v` clamped into the grid; `T::default()` where nothing is stored.
    #[inline(always)]
    pub fn at(&self, v: [i64; 3]) -> T {
        let clamped = |a: usize| v[a].clamp(0, self.dims[a] as i64 - 1) as usize;
        let c = [clamped(0), clamped(1), clamped(2)];
        let b = [c[0] / BRICK, c[1] / BRICK, c[2] / BRICK];
        let slot = self.table[b[0] + self.bricks[0] * (b[1] + self.bricks[1] * b[2])];
        if slot == u32::MAX {
            return T::default();
        }
        let k = c[0] % BRICK + BRICK * (c[1] % BRICK + BRICK * (c[2] % BRICK));
        self.values[slot as usize * BRICK * BRICK * BRICK + k]
    }

    /// Bytes the values take.
    pub fn bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<T>() + self.table.len() * 4
    }

    /// How many bricks are stored.
    pub fn brick_count(&self) -> usize {
        self.stored.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Growing a single voxel by 2 gives the 5³ cube around it, clipped at the grid's edge.
    #[test]
    fn growing_gives_the_cube_of_the_reach() {
        let mut m = Mask::empty([9, 7, 6]);
        let at = m.index([1, 3, 3]);
        m.on[at] = true;
        let g = m.grown(2);
        for i in 0..g.on.len() {
            let v = g.voxel(i);
            let want = v[0] <= 3 && (1..=5).contains(&v[1]) && (1..=5).contains(&v[2]);
            assert_eq!(g.on[i], want, "voxel {v:?}");
        }
        assert_eq!(g.count(), 4 * 5 * 5);
    }

    /// Parents halve each coordinate; a store reads back what it computed and clamps.
    #[test]
    fn parents_and_store() {
        let mut m = Mask::empty([10, 4, 3]);
        for v in [[9, 3, 2], [0, 0, 0]] {
            let at = m.index(v);
            m.on[at] = true;
        }
        let p = m.parents([5, 2, 2]);
        assert_eq!(p.count(), 2);
        assert!(p.on[p.index([4, 1, 1])] && p.on[0]);
        let s = Sparse::compute(&m, |v| v[0] as u32 + 100 * v[1] as u32 + 1000 * v[2] as u32);
        assert_eq!(s.at([9, 3, 2]), 2309);
        assert_eq!(s.at([40, 9, 7]), 2309, "clamped into the grid");
        assert_eq!(s.at([0, 0, 0]), 0);
        assert_eq!(s.brick_count(), 2);
    }
}
