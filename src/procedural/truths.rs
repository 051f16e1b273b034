//! Label volumes with long features, made to be the 3D truth that synthesis from their
//! central slices is compared with (`quality --labels --truth`):
//!
//! - **foam**: a 3D Voronoi foam of stones in twelve greys with thin dark joints (cells on
//!   a jittered grid about 16 voxels apart; a voxel is joint where its second-nearest site
//!   is less than [`JOINT`] voxels farther than its nearest). Isotropic, tileable in 3D.
//! - **channels**: long sinuous channels running along x in a dark mud, a facies-like
//!   volume of three labels: mud, the channel's sand, and the levee around it. Each channel
//!   meanders in y, undulates gently in z and varies in width along its course; its section
//!   is an ellipse about three times wider than tall; the channels are spread evenly over
//!   the height, so every horizontal cut crosses some. Tileable in 3D.
//!
//! Both hold exact label values in all three channels (grey), so `--labels` reads them;
//! the values are whole multiples of 1/255, so slices saved as 8-bit PNGs keep them exactly.

use crate::noise::{hash3, unit};
use glam::Vec3;

/// How much farther the second-nearest site may be for a voxel to be joint (voxels).
pub const JOINT: f32 = 1.2;
/// Foam: the joints' grey level.
pub const JOINT_GREY: f32 = 31.0 / 255.0;
/// Foam: how many stone greys there are, evenly spaced from 115/255 to 225/255 (many
/// levels, so that the line yardstick's percentile never splits a large class of equal
/// values; few enough for a label volume).
pub const STONE_GREYS: usize = 12;
/// Channels: mud, levee and sand.
pub const CHANNEL_LABELS: [f32; 3] = [64.0 / 255.0, 140.0 / 255.0, 217.0 / 255.0];
/// Foam cell spacing in voxels.
const CELL: usize = 16;

/// Where the grid of cells starts, in cells: not at 0, so that no central slice of a
/// volume whose side is a multiple of the cell lies where the cells meet (joint faces
/// gather near cell walls, and that slice would hold more joint than the volume).
const GRID_SHIFT: f32 = 0.37;

/// The foam's sites: one per cell of a grid, jittered within it.
pub struct Foam {
    dims: [usize; 3],
    cells: [usize; 3],
    seed: u64,
}

impl Foam {
    /// The foam for a volume of `dims` voxels.
    pub fn new(dims: [usize; 3], seed: u64) -> Foam {
        Foam { dims, cells: dims.map(|d| (d as f32 / CELL as f32).round().max(1.0) as usize), seed }
    }

    /// The site of cell `c` (wrapped) in cell units, shifted by the whole periods wrapped.
    fn site(&self, c: [i64; 3]) -> (Vec3, u64) {
        let n = self.cells.map(|k| k as i64);
        let w = [0, 1, 2].map(|k| c[k].rem_euclid(n[k]));
        let h = hash3(self.seed, w[0], w[1], w[2]);
        let jitter = Vec3::new(unit(h), unit(h.rotate_left(21)), unit(h.rotate_left(42)));
        (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + 0.05 + 0.9 * jitter, h)
    }

    /// The label at voxel `(x, y, z)`.
    pub fn label(&self, x: usize, y: usize, z: usize) -> f32 {
        let dims = self.dims;
        let scale = Vec3::new(
            dims[0] as f32 / self.cells[0] as f32,
            dims[1] as f32 / self.cells[1] as f32,
            dims[2] as f32 / self.cells[2] as f32,
        );
        let p = Vec3::new(x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5) / scale + GRID_SHIFT;
        let home = [p.x.floor() as i64, p.y.floor() as i64, p.z.floor() as i64];
        let (mut first, mut second, mut stone) = (f32::MAX, f32::MAX, 0u64);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (site, h) = self.site([home[0] + dx, home[1] + dy, home[2] + dz]);
                    let d = ((site - p) * scale).length();
                    if d < first {
                        (second, first, stone) = (first, d, h);
                    } else if d < second {
                        second = d;
                    }
                }
            }
        }
        if second - first < JOINT { JOINT_GREY } else { stone_grey(stone) }
    }
}

/// The grey of the stone whose site hash is `h`.
fn stone_grey(h: u64) -> f32 {
    let level = (h % STONE_GREYS as u64) as f32;
    (115.0 + (level * 110.0 / (STONE_GREYS - 1) as f32).round()) / 255.0
}

/// One channel's course.
struct Course {
    y: f32,
    z: f32,
    meander: (f32, f32, f32),
    undulation: (f32, f32),
    width: (f32, f32, f32),
}

/// The channels of a volume, with each course's centre and half width at every x, and
/// per z the courses that can reach it.
pub struct Channels {
    dims: [usize; 3],
    /// Per course, its centre line's y and z at the meander's and undulation's zero.
    places: Vec<(f32, f32)>,
    /// Per course, per x: the meander, the undulation and the half width there.
    along: Vec<[f32; 3]>,
    /// Per z, the courses whose levee can reach it.
    near: Vec<Vec<usize>>,
}

/// The levee's outer edge, in half widths.
const LEVEE: f32 = 1.45;
/// A section's height over its width.
const FLATNESS: f32 = 0.35;

impl Channels {
    /// The channels for a volume of `dims` voxels: about one per 200 voxels of its x-section.
    pub fn new(dims: [usize; 3], seed: u64) -> Channels {
        let count = (dims[1] * dims[2] / 200).max(1);
        let side = |k: usize| dims[k] as f32;
        let courses: Vec<Course> = (0..count as i64)
            .map(|i| {
                let r = |k: i64| unit(hash3(seed, i, k, 7));
                let cycles = |k: i64, most: f32| (1.0 + (r(k) * most).floor()) / side(0);
                Course {
                    y: r(0) * side(1),
                    z: (i as f32 + 0.2 + 0.6 * r(1)) * side(2) / count as f32,
                    meander: (0.08 * side(1) * (0.5 + r(2)), std::f32::consts::TAU * cycles(3, 2.0), r(4) * 6.3),
                    undulation: (0.02 * side(2) * (0.5 + r(5)), r(6) * 6.3),
                    width: (
                        0.06 * side(1).min(side(0)) * (0.8 + 0.4 * r(7)),
                        std::f32::consts::TAU * cycles(8, 3.0),
                        r(9) * 6.3,
                    ),
                }
            })
            .collect();
        let along = courses
            .iter()
            .flat_map(|c| {
                (0..dims[0]).map(move |x| {
                    let px = x as f32 + 0.5;
                    let wave = c.meander.0 * (c.meander.1 * px + c.meander.2).sin();
                    let rise = c.undulation.0 * (std::f32::consts::TAU * px / side(0) + c.undulation.1).sin();
                    let half_width = c.width.0 * (1.0 + 0.35 * (c.width.1 * px + c.width.2).sin());
                    [wave, rise, half_width]
                })
            })
            .collect();
        let near = (0..dims[2])
            .map(|z| {
                let pz = z as f32 + 0.5;
                let reach = |c: &Course| c.undulation.0 + LEVEE * FLATNESS * 1.35 * c.width.0 + 1.0;
                (0..courses.len())
                    .filter(|&i| wrapped(pz - courses[i].z, side(2)).abs() <= reach(&courses[i]))
                    .collect()
            })
            .collect();
        let places = courses.iter().map(|c| (c.y, c.z)).collect();
        Channels { dims, places, along, near }
    }

    /// The label at voxel `(x, y, z)`.
    pub fn label(&self, x: usize, y: usize, z: usize) -> f32 {
        let (py, pz) = (y as f32 + 0.5, z as f32 + 0.5);
        let mut inner = f32::MAX;
        for &c in &self.near[z] {
            let [wave, rise, half_width] = self.along[c * self.dims[0] + x];
            let (cy, cz) = self.places[c];
            let dy = wrapped(py - cy - wave, self.dims[1] as f32) / half_width;
            let dz = wrapped(pz - cz - rise, self.dims[2] as f32) / (FLATNESS * half_width);
            inner = inner.min(dy.hypot(dz));
        }
        match inner {
            r if r < 1.0 => CHANNEL_LABELS[2],
            r if r < LEVEE => CHANNEL_LABELS[1],
            _ => CHANNEL_LABELS[0],
        }
    }
}

/// `d` wrapped into (-period / 2, period / 2].
fn wrapped(d: f32, period: f32) -> f32 {
    d - period * (d / period).round()
}
