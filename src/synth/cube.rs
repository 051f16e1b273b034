//! A solid exemplar for guided synthesis: a cube of colours that tiles (made from the 2D
//! exemplars by the project's synthesis, [`crate::synth::synthesize`]), kept at every
//! pyramid level. A voxel then holds one place in the cube and shows the cube's colour
//! there: its neighbourhoods in the three planes of its frame come from one consistent
//! solid, so cuts keep the cube's sharpness, where a triple of 2D pixels shows the mean
//! of three pixels that seldom agree (docs/guided.md, "Two exemplars").

use crate::error::{Error, Result};
use crate::volume::{Axis, Edge, Image2d, Volume, downsample};

/// Side of the cube synthesized from 2D exemplars: 64 voxels tile without visible repeats
/// at the resolutions guided synthesis runs at, in about a second.
pub const SIDE: usize = 64;

/// Side of the cube's coarsest level at least.
pub const SMALLEST: usize = 16;

/// Channels a cube may hold.
const MAX_CHANNELS: usize = super::coords::MAX_CHANNELS;

/// One level of the cube.
#[derive(Debug, Clone)]
pub struct CubeLevel {
    /// Voxels per side.
    pub side: usize,
    /// Colours, interleaved, x fastest.
    pub colours: Vec<f32>,
}

/// The cube at every level, coarsest first.
#[derive(Debug, Clone)]
pub struct Cube {
    /// Levels, coarsest first.
    pub levels: Vec<CubeLevel>,
    /// Channels per voxel.
    pub channels: usize,
}

impl Cube {
    /// The cube of `volume`'s channels `keep` at `levels` levels: a cube whose side halves
    /// evenly down to the coarsest level, which holds at least `smallest` voxels a side.
    pub fn new(volume: &Volume, keep: &[usize], levels: usize, smallest: usize) -> Result<Cube> {
        let [w, h, d] = volume.dims();
        let shrink = 1usize << (levels - 1);
        if w != h || h != d || w % shrink != 0 || w / shrink < smallest {
            return Err(Error::invalid(format!(
                "a solid exemplar must be a cube whose side divides by {shrink} with at least {smallest} voxels a side \
                 at its coarsest level ({levels} levels): {w}x{h}x{d} is not"
            )));
        }
        if keep.is_empty() || keep.len() > MAX_CHANNELS || keep.iter().any(|&k| k >= volume.channel_count()) {
            return Err(Error::invalid(format!(
                "a solid exemplar shows 1 to {MAX_CHANNELS} of the volume's {} channels, not {keep:?}",
                volume.channel_count()
            )));
        }
        // the given volume is the finest level; only the coarser ones are made (no copy of it)
        let mut shrunk: Option<Volume> = None;
        let mut out = Vec::with_capacity(levels);
        for level in 0..levels {
            if level > 0 {
                shrunk = Some(downsample(shrunk.as_ref().unwrap_or(volume), Edge::Wrap)?);
            }
            let v = shrunk.as_ref().unwrap_or(volume);
            let c = v.channel_count();
            let data = v.data().chunks_exact(c).flat_map(|px| keep.iter().map(move |&k| px[k])).collect();
            out.push(CubeLevel { side: v.dims()[0], colours: data });
        }
        out.reverse();
        Ok(Cube { levels: out, channels: keep.len() })
    }

    /// The colour at place `p` of `level` (wrapped into the cube).
    #[inline]
    pub fn at(&self, level: usize, p: [i64; 3]) -> &[f32] {
        let l = &self.levels[level];
        let s = l.side as i64;
        let [x, y, z] = p.map(|c| c.rem_euclid(s) as usize);
        let i = x + l.side * (y + l.side * z);
        &l.colours[i * self.channels..(i + 1) * self.channels]
    }

    /// The summed squared distance from `query` (an n x n neighbourhood, rows along the
    /// plane's second axis, channels interleaved) to the cube's neighbourhood in the plane
    /// orthogonal to `axis` around place `t` of `level` (`n` at most 11, and below the side).
    pub fn plane_distance(&self, level: usize, t: [u32; 3], axis: usize, n: usize, query: &[f32]) -> f32 {
        let l = &self.levels[level];
        let (side, ch, h) = (l.side, self.channels, n / 2);
        let (pa, sa) = Axis::ALL[axis].plane_axes();
        let stride = [1, side, side * side];
        // t + d - h lifted by a side, back into [0, side)
        let wrapped = |c: usize| {
            if c >= 2 * side {
                c - 2 * side
            } else if c >= side {
                c - side
            } else {
                c
            }
        };
        let mut columns = [0usize; 11];
        for (d, column) in columns.iter_mut().enumerate().take(n) {
            *column = wrapped(t[pa] as usize + d + side - h) * stride[pa];
        }
        let base = t[axis] as usize * stride[axis];
        let mut sum = 0.0;
        for dy in 0..n {
            let row = base + wrapped(t[sa] as usize + dy + side - h) * stride[sa];
            for (dx, column) in columns.iter().enumerate().take(n) {
                let at = (row + column) * ch;
                let q = &query[(dy * n + dx) * ch..(dy * n + dx + 1) * ch];
                for (a, b) in q.iter().zip(&l.colours[at..at + ch]) {
                    sum += (a - b) * (a - b);
                }
            }
        }
        sum
    }

    /// `p` wrapped into the cube of `level`.
    #[inline]
    pub fn wrapped(&self, level: usize, p: [i64; 3]) -> [u32; 3] {
        let s = self.levels[level].side as i64;
        p.map(|c| c.rem_euclid(s) as u32)
    }
}

/// The tiling volume of [`SIDE`]³ voxels synthesized from `images` (orthogonal to x, y,
/// z; alpha-free) that becomes the cube.
pub fn synthesize(images: &[Image2d; 3], seed: u64) -> Result<Volume> {
    let mut params = crate::synth::SynthParams { core: core_for(images), size: [SIDE; 3], ..Default::default() };
    // as many levels (at most the default's) as a small exemplar holds neighbourhoods at
    let side = images.iter().map(|e| e.width().min(e.height())).min().unwrap_or(0);
    while params.levels > 1 && (side >> (params.levels - 1)) < params.neighbourhood + 2 {
        params.levels -= 1;
    }
    let ex = crate::synth::Exemplars { x: &images[0], y: Some(&images[1]), z: Some(&images[2]) };
    crate::synth::synthesize(ex, &params, seed, &crate::progress::NoProgress)
}

/// The colours a cube synthesized from `images` can hold, generously: the exemplars' range
/// (taken to cover 0 to 1 at least) widened by its span on either side, as synthesis mixes
/// exemplar pixels and matches their spectrum, which may overshoot a little. A cached cube
/// with a colour outside is damaged.
pub fn colour_range(images: &[Image2d; 3]) -> (f32, f32) {
    let all = images.iter().flat_map(|image| image.data().iter().copied());
    let (lo, hi) = all.fold((0.0f32, 1.0f32), |(lo, hi), c| (lo.min(c), hi.max(c)));
    let span = hi - lo;
    (lo - span, hi + span)
}

/// The core that synthesizes the cube: the coordinate core for label images, the blend
/// core for photos.
fn core_for(images: &[Image2d; 3]) -> crate::synth::Core {
    crate::synth::Core::for_exemplars(&[&images[0], &images[1], &images[2]], false)
}

/// A key of everything [`synthesize`] depends on: the images, the seed, the cube's side
/// and its core (which the images decide; named in the key for label images, so that a
/// cube the blend core made of the same images is never read as theirs).
pub fn key(images: &[Image2d; 3], seed: u64) -> u64 {
    let mut h = crate::noise::mix64(0xc0be_5eed);
    let mut add = |x: u64| h = crate::noise::mix64(h ^ x);
    for image in images {
        add(image.width() as u64);
        add(image.height() as u64);
        image.channels().iter().for_each(|c| c.to_string().bytes().for_each(|b| add(u64::from(b))));
        image.data().iter().for_each(|c| add(u64::from(c.to_bits())));
    }
    add(SIDE as u64);
    add(seed);
    if core_for(images) == crate::synth::Core::Coordinates {
        add(u64::from(b'c'));
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    /// Levels halve the side, wrap around, and keep the channels asked for.
    #[test]
    fn levels_halve_and_places_wrap() {
        let v = Volume::from_fn([16, 16, 16], vec![Channel::R, Channel::A], |x, y, z, o| {
            o[0] = (x + 2 * y + 3 * z) as f32 / 100.0;
            o[1] = 1.0;
        })
        .unwrap();
        let cube = Cube::new(&v, &[0], 3, 4).unwrap();
        assert_eq!(cube.levels.iter().map(|l| l.side).collect::<Vec<_>>(), [4, 8, 16]);
        assert_eq!(cube.channels, 1);
        assert_eq!(cube.at(2, [1, 2, 3]), [0.14]);
        assert_eq!(cube.at(2, [17, -14, 19]), [0.14], "wrapped");
        assert_eq!(cube.wrapped(2, [-1, 16, 5]), [15, 0, 5]);
        let err = Cube::new(&v, &[0], 3, 5).unwrap_err().to_string();
        assert!(err.contains("at least 5 voxels") && err.contains("16x16x16"), "{err}");
        assert!(Cube::new(&v, &[2], 3, 4).unwrap_err().to_string().contains("[2]"));
        let flat = Volume::from_fn([12, 12, 10], Channel::grey(), |_, _, _, o| o[0] = 0.5).unwrap();
        assert!(Cube::new(&flat, &[0], 1, 4).unwrap_err().to_string().contains("12x12x10"));
    }

    /// A plane's distance equals the sum over the neighbourhood read place by place with
    /// `at`, across the cube's wrap too, for each of the three planes.
    #[test]
    fn a_plane_distance_reads_the_wrapped_neighbourhood() {
        let v = Volume::from_fn([16, 16, 16], Channel::rgb(), |x, y, z, o| {
            o[0] = (x * 7 % 5) as f32 / 4.0;
            o[1] = (y * 3 % 7) as f32 / 6.0;
            o[2] = ((x + z) % 3) as f32 / 2.0;
        })
        .unwrap();
        let cube = Cube::new(&v, &[0, 1, 2], 1, 4).unwrap();
        let n = 5;
        let query: Vec<f32> = (0..n * n * 3).map(|i| (i % 11) as f32 / 10.0).collect();
        for t in [[0u32, 15, 7], [14, 1, 0], [8, 8, 15]] {
            for axis in 0..3 {
                let (pa, sa) = Axis::ALL[axis].plane_axes();
                let mut want = 0.0;
                for dy in 0..n {
                    for dx in 0..n {
                        let mut p = t.map(i64::from);
                        p[pa] += dx as i64 - 2;
                        p[sa] += dy as i64 - 2;
                        let q = &query[(dy * n + dx) * 3..][..3];
                        want += q.iter().zip(cube.at(0, p)).map(|(a, b)| (a - b) * (a - b)).sum::<f32>();
                    }
                }
                let got = cube.plane_distance(0, t, axis, n, &query);
                assert!((got - want).abs() < 1e-4, "place {t:?}, axis {axis}: {got} against {want}");
            }
        }
    }
}
