//! Cross-sections: axis-aligned slices and slices on an arbitrary plane.
//!
//! ```text
//! axis Z at index k:  image(x, y) = volume(x, y, k)
//! axis Y at index j:  image(x, z) = volume(x, j, z)
//! axis X at index i:  image(y, z) = volume(i, y, z)
//! ```

use super::{Edge, Image2d, Volume};
use crate::error::{Error, Result};
use glam::Vec3;
use std::fmt;
use std::str::FromStr;

/// A volume axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// The x axis (slices are y-z images).
    X,
    /// The y axis (slices are x-z images).
    Y,
    /// The z axis (slices are x-y images).
    Z,
}

impl Axis {
    /// All three axes.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// 0, 1 or 2.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The two in-plane axes of a slice across this axis, as (image x, image y).
    pub fn plane_axes(self) -> (usize, usize) {
        match self {
            Axis::X => (1, 2),
            Axis::Y => (0, 2),
            Axis::Z => (0, 1),
        }
    }
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(["x", "y", "z"][self.index()])
    }
}

impl FromStr for Axis {
    type Err = Error;

    fn from_str(text: &str) -> Result<Axis> {
        match text.to_ascii_lowercase().as_str() {
            "x" => Ok(Axis::X),
            "y" => Ok(Axis::Y),
            "z" => Ok(Axis::Z),
            _ => Err(Error::invalid(format!("unknown axis {text:?}; allowed: x, y, z"))),
        }
    }
}

/// A sampling plane: pixel (i, j) of the slice is at `origin + i * u + j * v` (voxel units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Position of pixel (0, 0).
    pub origin: Vec3,
    /// Step between neighbouring pixels along the image x direction.
    pub u: Vec3,
    /// Step between neighbouring pixels along the image y direction.
    pub v: Vec3,
}

impl Plane {
    /// A plane through `centre` with unit normal `normal`, one voxel per pixel,
    /// covering `size` x `size` pixels around `centre`, which pixel (size / 2, size / 2)
    /// samples: so a plane through voxel positions samples voxel positions in the plane
    /// too. Its image axes are those of the axis slice across the axis nearest the normal,
    /// turned into the plane, so a normal along an axis gives that axis' slice.
    pub fn through(centre: Vec3, normal: Vec3, size: usize) -> Result<Plane> {
        let n = normal
            .try_normalize()
            .ok_or_else(|| Error::invalid(format!("plane normal {normal} has zero length or is not finite")))?;
        let nearest = (0..3).max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap_or(2);
        let (pa, sa) = Axis::ALL[nearest].plane_axes();
        let unit = |k: usize| Vec3::AXES[k];
        let u = (unit(pa) - n * n.dot(unit(pa))).normalize();
        let v = (unit(sa) - n * n.dot(unit(sa)) - u * u.dot(unit(sa))).normalize();
        let half = (size / 2) as f32;
        Ok(Plane { origin: centre - half * (u + v), u, v })
    }
}

impl Volume {
    /// The slice across `axis` at `index`, with all channels.
    pub fn slice(&self, axis: Axis, index: usize) -> Result<Image2d> {
        let d = self.dims();
        if index >= d[axis.index()] {
            return Err(Error::invalid(format!(
                "slice index {index} is outside axis {axis}, which has {} voxels (allowed 0..={})",
                d[axis.index()],
                d[axis.index()] - 1
            )));
        }
        let (a, b) = axis.plane_axes();
        let mut image = Image2d::new(d[a], d[b], self.channels().to_vec())?;
        for j in 0..d[b] {
            for i in 0..d[a] {
                let mut p = [0; 3];
                p[axis.index()] = index;
                p[a] = i;
                p[b] = j;
                image.pixel_mut(i, j).copy_from_slice(self.voxel(p[0], p[1], p[2]));
            }
        }
        Ok(image)
    }

    /// The volume with its axes reordered: new axis k is the old axis `order[k]`
    /// (`[Axis::Z, Axis::X, Axis::Y]` makes the old z the new x). `order` must be a permutation.
    pub fn permuted(&self, order: [Axis; 3]) -> Result<Volume> {
        let idx = order.map(|a| a.index());
        if idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2] {
            return Err(Error::invalid(format!("axis order {}{}{} repeats an axis", order[0], order[1], order[2])));
        }
        let old = self.dims();
        let dims = idx.map(|k| old[k]);
        let out = Volume::from_fn(dims, self.channels().to_vec(), |x, y, z, o| {
            let mut p = [0; 3];
            for (k, v) in [x, y, z].into_iter().enumerate() {
                p[idx[k]] = v;
            }
            o.copy_from_slice(self.voxel(p[0], p[1], p[2]));
        })?;
        Ok(out.with_meta(self.meta.clone()))
    }

    /// A `width` x `height` slice on an arbitrary plane, trilinearly sampled.
    pub fn plane_slice(&self, plane: &Plane, width: usize, height: usize, edge: Edge) -> Result<Image2d> {
        let mut image = Image2d::new(width, height, self.channels().to_vec())?;
        for j in 0..height {
            for i in 0..width {
                let p = plane.origin + i as f32 * plane.u + j as f32 * plane.v;
                self.sample_trilinear(p, edge, image.pixel_mut(i, j));
            }
        }
        Ok(image)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    fn coords() -> Volume {
        Volume::from_fn([4, 5, 6], Channel::rgb(), |x, y, z, o| o.copy_from_slice(&[x as f32, y as f32, z as f32]))
            .unwrap()
    }

    #[test]
    fn axis_slices_have_the_right_plane() {
        let v = coords();
        let s = v.slice(Axis::Y, 3).unwrap();
        assert_eq!((s.width(), s.height()), (4, 6));
        assert_eq!(s.pixel(2, 5), &[2.0, 3.0, 5.0]);
        let s = v.slice(Axis::X, 1).unwrap();
        assert_eq!((s.width(), s.height()), (5, 6));
        assert_eq!(s.pixel(4, 2), &[1.0, 4.0, 2.0]);
        let err = v.slice(Axis::Z, 6).unwrap_err().to_string();
        assert!(err.contains("index 6") && err.contains("0..=5"), "{err}");
    }

    #[test]
    fn an_axis_aligned_plane_matches_the_axis_slice() {
        let v = coords();
        let plane = Plane { origin: Vec3::new(0.0, 0.0, 2.0), u: Vec3::X, v: Vec3::Y };
        let s = v.plane_slice(&plane, 4, 5, Edge::Clamp).unwrap();
        assert_eq!(s, v.slice(Axis::Z, 2).unwrap());
    }

    #[test]
    fn permuting_axes_moves_voxels() {
        let v = coords();
        let p = v.permuted([Axis::Z, Axis::X, Axis::Y]).unwrap();
        assert_eq!(p.dims(), [6, 4, 5]);
        assert_eq!(p.voxel(5, 3, 4), &[3.0, 4.0, 5.0]);
        assert!(v.permuted([Axis::X, Axis::X, Axis::Y]).is_err());
    }

    #[test]
    fn a_tilted_plane_stays_on_the_plane() {
        let v = coords();
        let centre = Vec3::new(2.0, 2.0, 3.0);
        let normal = Vec3::new(1.0, 1.0, 1.0);
        let plane = Plane::through(centre, normal, 3).unwrap();
        let s = v.plane_slice(&plane, 3, 3, Edge::Clamp).unwrap();
        for px in s.data().chunks(3) {
            let p = Vec3::new(px[0], px[1], px[2]);
            assert!((p - centre).dot(normal.normalize()).abs() < 1e-4);
        }
        assert!(Plane::through(centre, Vec3::ZERO, 3).is_err());
    }

    /// A normal along an axis (either way) gives that axis' slice, image axes and all.
    #[test]
    fn an_axis_normal_gives_the_axis_slice() {
        let v =
            Volume::from_fn([5; 3], Channel::rgb(), |x, y, z, o| o.copy_from_slice(&[x as f32, y as f32, z as f32]))
                .unwrap();
        for (axis, normal) in [(Axis::X, Vec3::X), (Axis::Y, Vec3::NEG_Y), (Axis::Z, Vec3::Z)] {
            let plane = Plane::through(Vec3::splat(2.0), normal, 5).unwrap();
            let s = v.plane_slice(&plane, 5, 5, Edge::Clamp).unwrap();
            assert_eq!(s, v.slice(axis, 2).unwrap(), "{axis}");
        }
    }

    /// On an even side too, a plane through a voxel's position samples voxel positions,
    /// not the points between them.
    #[test]
    fn an_axis_plane_of_an_even_side_samples_voxels() {
        let v =
            Volume::from_fn([6; 3], Channel::rgb(), |x, y, z, o| o.copy_from_slice(&[x as f32, y as f32, z as f32]))
                .unwrap();
        let plane = Plane::through(Vec3::splat(3.0), Vec3::Z, 6).unwrap();
        assert_eq!(v.plane_slice(&plane, 6, 6, Edge::Wrap).unwrap(), v.slice(Axis::Z, 3).unwrap());
    }
}
