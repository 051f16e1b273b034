//! A cut-away corner view: the solid seen from its (+x, +y, +z) corner with that
//! octant removed, so three outer faces and three inner cuts show at once.
//!
//! ```text
//!        z
//!        |   ____
//!        |  /   /|        the octant x > cx, y > cy, z > cz is cut away;
//!        | /___/ |__      the ray from each pixel stops at the first face of
//!        | |   | / /|     the remaining solid (exact: two box intersections)
//!        | |___|/_/ |
//!        |/________/
//! ```

use super::{BACKGROUND, ColourMap, Rgb8};
use crate::volume::Volume;
use glam::Vec3;

/// Render the cut-away view into a `size` x `size` picture.
pub fn cutaway(volume: &Volume, size: usize) -> Rgb8 {
    let d = volume.dims();
    let hi = Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32);
    let centre = hi / 2.0;
    let longest = hi.max_element();
    let dir = Vec3::new(-1.0, -1.0, -0.8).normalize();
    let right = dir.cross(Vec3::Z).normalize();
    let up = right.cross(dir);
    let step = 1.75 * longest / size as f32;
    let map = ColourMap::for_channels(volume.channels());
    let mut out = Rgb8::new(size, size, BACKGROUND);
    for j in 0..size {
        for i in 0..size {
            let a = (i as f32 + 0.5 - size as f32 / 2.0) * step;
            let b = (size as f32 / 2.0 - j as f32 - 0.5) * step;
            let origin = centre + a * right + b * up - 4.0 * longest * dir;
            if let Some((p, axis)) = first_hit(origin, dir, hi, centre) {
                out.put(i, j, shade(volume, map, p + dir * 1e-3, axis));
            }
        }
    }
    out
}

/// Where the ray first meets the solid (box minus the far octant), and the face axis.
fn first_hit(origin: Vec3, dir: Vec3, hi: Vec3, cut: Vec3) -> Option<(Vec3, usize)> {
    let (t0, _, enter, _) = slab(origin, dir, Vec3::ZERO, hi)?;
    let p = origin + t0 * dir;
    let in_octant = (p - cut).min_element() > 1e-4;
    if !in_octant {
        return Some((p, enter));
    }
    let (_, t1, _, exit) = slab(origin, dir, cut, hi)?;
    let q = origin + t1 * dir;
    let inside = q.cmpge(Vec3::splat(-1e-3)).all() && q.cmple(hi + 1e-3).all();
    inside.then_some((q, exit))
}

/// Ray-box intersection: (t enter, t exit, axis entered through, axis left through).
fn slab(origin: Vec3, dir: Vec3, lo: Vec3, hi: Vec3) -> Option<(f32, f32, usize, usize)> {
    let (mut t0, mut t1, mut enter, mut exit) = (f32::NEG_INFINITY, f32::INFINITY, 0, 0);
    for axis in 0..3 {
        let (o, d) = (origin[axis], dir[axis]);
        if d.abs() < 1e-9 {
            if o < lo[axis] || o > hi[axis] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
        let (near, far) = if a < b { (a, b) } else { (b, a) };
        if near > t0 {
            (t0, enter) = (near, axis);
        }
        if far < t1 {
            (t1, exit) = (far, axis);
        }
    }
    (t0 <= t1).then_some((t0, t1, enter, exit))
}

/// The voxel colour at `p`, darkened by which way the face looks.
fn shade(volume: &Volume, map: ColourMap, p: Vec3, axis: usize) -> [u8; 3] {
    let d = volume.dims();
    let idx = |k: usize| (p[k].floor().max(0.0) as usize).min(d[k] - 1);
    let rgb = map.colour(volume.voxel(idx(0), idx(1), idx(2)));
    let light = [0.80, 0.66, 1.0][axis];
    rgb.map(|c| (c as f32 * light).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    #[test]
    fn the_inner_cut_shows_the_core_colour() {
        // Outer shell red, core (the central 50 %) green: the cut reveals green.
        let v = Volume::from_fn([16, 16, 16], Channel::rgb(), |x, y, z, o| {
            let core = [x, y, z].iter().all(|c| (4..12).contains(c));
            o.copy_from_slice(if core { &[0.0, 1.0, 0.0] } else { &[1.0, 0.0, 0.0] });
        })
        .unwrap();
        let pic = cutaway(&v, 96);
        let count = |pred: fn([u8; 3]) -> bool| (0..96 * 96).filter(|i| pred(pic.at(i % 96, i / 96))).count();
        let green = count(|c| c[1] > 100 && c[0] == 0);
        let red = count(|c| c[0] > 100 && c[1] == 0);
        let empty = count(|c| c == BACKGROUND);
        assert!(green > 200, "green {green}");
        assert!(red > 1000, "red {red}");
        assert!(empty > 1000 && empty < 96 * 96 - 2000, "background {empty}");
        assert_eq!(pic.at(0, 0), BACKGROUND);
    }
}
