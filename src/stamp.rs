//! Hand-made solids, part 2 (thesis §4.3): stamp seed meshes into a volume, scatter
//! many of them without overlaps, and blur locally.
//!
//! A seed is placed by [`Placement`]: the mesh's own origin goes to voxel position `at`,
//! after rotating it and scaling it so that one mesh unit becomes `scale` voxels.
//! Voxel (i, j, k) is the cube [i, i+1) x [j, j+1) x [k, k+1).

use crate::error::{Error, Result};
use crate::mesh::{Mesh, voxelize};
use crate::volume::{Channel, Volume, luminance};
use glam::{Affine3A, Quat, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// Supersamples per axis for anti-aliased edges.
pub const SUPERSAMPLE: usize = 4;
/// Allowed scales, in voxels per mesh unit.
pub const SCALE: (f32, f32) = (0.001, 10_000.0);
/// Most seeds one scatter places: each try is checked against every seed placed, so the
/// work grows with the square of the count.
pub const MAX_COUNT: usize = 2000;
/// Largest distance from the origin of a position, in voxels: far beyond any volume, small
/// enough that differences of positions stay finite.
pub const POSITION_LIMIT: f32 = 1.0e6;
/// Allowed blur radii, in voxels: the blur costs 125 samples per voxel of its sphere's box.
pub const RADIUS: (f32, f32) = (0.1, 64.0);

/// Where and how big a seed goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Voxel position of the mesh origin.
    pub at: Vec3,
    /// Rotation about the mesh origin.
    pub rotation: Quat,
    /// Voxels per mesh unit, per mesh axis.
    pub scale: Vec3,
}

impl Placement {
    /// Mesh coordinates to voxel coordinates.
    pub fn matrix(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.at)
    }
}

/// What was stamped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stamped {
    /// Voxels touched (coverage above 0).
    pub voxels: usize,
    /// Summed coverage: the seed's volume in voxels.
    pub volume: f64,
}

/// Stamp `mesh` placed by `placement` into `volume`, blending `colour` (R, G, B) into the
/// colour channels by coverage (anti-aliased edges). A seed wholly outside is an error.
pub fn stamp(volume: &mut Volume, mesh: &Mesh, placement: &Placement, colour: [f32; 3]) -> Result<Stamped> {
    let stamped = stamp_covered(volume, mesh, placement, colour)?;
    if stamped.voxels == 0 {
        let d = volume.dims();
        let placed = mesh.transformed(placement.matrix());
        let (lo, hi) = placed.bounds();
        let why = if !meets_volume(lo, hi, d) {
            format!("lies wholly outside the {}x{}x{} volume", d[0], d[1], d[2])
        } else if flat(mesh) {
            "encloses no volume (a flat or open mesh); a seed must be a closed surface".to_string()
        } else {
            "covers no voxel's centre: it is smaller than a voxel (raise --scale)".to_string()
        };
        return Err(Error::invalid(format!(
            "the seed placed at ({}, {}, {}) {why}",
            placement.at.x, placement.at.y, placement.at.z
        )));
    }
    Ok(stamped)
}

/// Whether `mesh` encloses no volume: open, or flat (its volume a negligible share of its
/// bounding box's), at whatever scale it is placed.
fn flat(mesh: &Mesh) -> bool {
    let (lo, hi) = mesh.bounds();
    mesh.boundary_edges() > 0 || mesh.signed_volume().abs() <= 1e-6 * (hi - lo).length().powi(3)
}

/// [`stamp`] without the check that the seed covers some voxel (a scattered seed may be
/// smaller than a sample spacing).
fn stamp_covered(volume: &mut Volume, mesh: &Mesh, placement: &Placement, colour: [f32; 3]) -> Result<Stamped> {
    check_placement(placement)?;
    let targets = colour_targets(volume, colour)?;
    let placed = mesh.transformed(placement.matrix());
    let cover = voxelize(&placed, volume.dims(), SUPERSAMPLE);
    let mut stamped = Stamped { voxels: 0, volume: 0.0 };
    for (i, &alpha) in cover.alpha.iter().enumerate().filter(|(_, a)| **a > 0.0) {
        let [x, y, z] = crate::volume::unindex(cover.dims, i);
        let voxel = volume.voxel_mut(cover.origin[0] + x, cover.origin[1] + y, cover.origin[2] + z);
        for &(c, value) in &targets {
            voxel[c] += alpha * (value - voxel[c]);
        }
        stamped.voxels += 1;
        stamped.volume += alpha as f64;
    }
    Ok(stamped)
}

/// Whether every coordinate of `p` lies within [`POSITION_LIMIT`] of 0 (NaN never does).
fn within_limit(p: Vec3) -> bool {
    p.abs().max_element() <= POSITION_LIMIT && !p.is_nan()
}

/// A placement within the allowed positions and scales.
fn check_placement(p: &Placement) -> Result<()> {
    let limit = POSITION_LIMIT;
    if !within_limit(p.at) {
        return Err(Error::invalid(format!(
            "seed position ({}, {}, {}) is out of range; allowed: each coordinate -{limit} to {limit}",
            p.at.x, p.at.y, p.at.z
        )));
    }
    let (lo, hi) = SCALE;
    if p.scale.is_nan() || !(p.scale.min_element() >= lo && p.scale.max_element() <= hi) {
        return Err(Error::invalid(format!(
            "seed scale ({}, {}, {}) is out of range; allowed: {lo} to {hi} voxels per mesh unit",
            p.scale.x, p.scale.y, p.scale.z
        )));
    }
    Ok(())
}

/// Each colour channel of the volume with the value `colour` gives it. A grey volume (one
/// colour channel, stored as R) takes the colour's luminance.
fn colour_targets(volume: &Volume, colour: [f32; 3]) -> Result<Vec<(usize, f32)>> {
    let rgb: Vec<(usize, f32)> = [Channel::R, Channel::G, Channel::B]
        .iter()
        .zip(colour)
        .filter_map(|(c, value)| Some((volume.channel_index(c)?, value)))
        .collect();
    match rgb.as_slice() {
        [] => Err(Error::invalid("the volume has no R, G or B channel to stamp a colour into")),
        [(grey, _)] => Ok(vec![(*grey, luminance(colour))]),
        _ => Ok(rgb),
    }
}

/// Where scattered seeds may go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Region {
    /// A box of voxel positions, min and max corners.
    Box(Vec3, Vec3),
    /// Wherever the volume's Depth channel lies between the two values (kiwi seeds sit in
    /// a ring between two depths).
    Depth(f32, f32),
}

/// How to scatter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scatter {
    /// How many seeds to place.
    pub count: usize,
    /// Where they may go.
    pub region: Region,
    /// Smallest and largest scale (voxels per mesh unit), drawn uniformly.
    pub scale: (f32, f32),
    /// Seed colour.
    pub colour: [f32; 3],
    /// Tries per seed before giving up on it.
    pub attempts: usize,
}

/// What a scatter did.
#[derive(Debug, Clone, PartialEq)]
pub struct Scattered {
    /// Placements of the seeds stamped (each changed some voxels), in order.
    pub placed: Vec<Placement>,
    /// Candidate positions rejected (overlap, outside, or out of the region).
    pub rejected: usize,
    /// Seeds that found room but were drawn smaller than a voxel, so they changed no voxel
    /// (a larger scale places them).
    pub too_small: usize,
}

/// Scatter up to `params.count` seeds with random orientation and scale, never overlapping
/// (their bounding capsules stay apart) and wholly inside the volume. A seed that covers no
/// voxel (smaller than one) is counted in `too_small`, not placed, and takes no room.
/// Reproducible from `seed`.
pub fn scatter(volume: &mut Volume, mesh: &Mesh, params: &Scatter, seed: u64) -> Result<Scattered> {
    check_scatter(volume, params)?;
    if flat(mesh) {
        return Err(Error::invalid(
            "the seed mesh encloses no volume (a flat or open mesh); a seed must be a closed surface",
        ));
    }
    let capsule = bounding_capsule(mesh);
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut out = Scattered { placed: Vec::new(), rejected: 0, too_small: 0 };
    let mut taken: Vec<Capsule> = Vec::new();
    for _ in 0..params.count {
        for _ in 0..params.attempts.max(1) {
            let scale = rng.random_range(params.scale.0..=params.scale.1);
            let rotation = random_rotation(&mut rng);
            let at = random_point(volume, params.region, &mut rng);
            let placement = Placement { at, rotation, scale: Vec3::splat(scale) };
            let moved = capsule.placed(&placement);
            if moved.inside(volume.dims()) && taken.iter().all(|c| !c.overlaps(&moved)) {
                if stamp_covered(volume, mesh, &placement, params.colour)?.voxels == 0 {
                    out.too_small += 1;
                } else {
                    taken.push(moved);
                    out.placed.push(placement);
                }
                break;
            }
            out.rejected += 1;
        }
    }
    Ok(out)
}

/// A segment with a radius: every point within `radius` of the segment `a`-`b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// One end of the segment.
    pub a: Vec3,
    /// The other end.
    pub b: Vec3,
    /// Distance from the segment that the shape stays within.
    pub radius: f32,
}

impl Capsule {
    /// The capsule moved, turned and scaled as a placement moves the mesh.
    pub fn placed(&self, p: &Placement) -> Capsule {
        let s = p.scale.x;
        Capsule { a: p.at + p.rotation * (self.a * s), b: p.at + p.rotation * (self.b * s), radius: self.radius * s }
    }

    /// Whether the whole capsule lies inside a volume of these dims.
    pub fn inside(&self, dims: [usize; 3]) -> bool {
        (0..3).all(|k| {
            let (lo, hi) = (self.a[k].min(self.b[k]), self.a[k].max(self.b[k]));
            lo - self.radius >= 0.0 && hi + self.radius <= dims[k] as f32
        })
    }

    /// Whether two capsules share a point.
    pub fn overlaps(&self, other: &Capsule) -> bool {
        segment_distance(self.a, self.b, other.a, other.b) < self.radius + other.radius
    }
}

/// The capsule around a mesh: its segment runs along the bounding box's longest side
/// through the box's centre, its radius is the farthest vertex's distance from that
/// segment. Elongated seeds (a kiwi's) get a capsule far tighter than their bounding
/// sphere, so scattered seeds can lie as close as their shapes allow.
pub fn bounding_capsule(mesh: &Mesh) -> Capsule {
    let (lo, hi) = mesh.bounds();
    let centre = (lo + hi) / 2.0;
    let size = hi - lo;
    let long = if size.x >= size.y && size.x >= size.z {
        Vec3::X
    } else if size.y >= size.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let half = long * (size.dot(long) / 2.0);
    let (a, b) = (centre - half, centre + half);
    let radius = mesh.vertices.iter().map(|v| segment_distance(*v, *v, a, b)).fold(0.0, f32::max);
    Capsule { a, b, radius }
}

/// The shortest distance between segments `p1`-`q1` and `p2`-`q2`; a segment may be a point.
fn segment_distance(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f32 {
    let (on_first, on_second) = crate::mesh::closest_between_segments([p1, q1], [p2, q2]);
    on_first.distance(on_second)
}

fn check_scatter(volume: &Volume, p: &Scatter) -> Result<()> {
    if !(1..=MAX_COUNT).contains(&p.count) {
        return Err(Error::invalid(format!("scatter count {} is out of range; allowed: 1 to {MAX_COUNT}", p.count)));
    }
    let (lo, hi) = SCALE;
    if !(p.scale.0 >= lo && p.scale.0 <= p.scale.1 && p.scale.1 <= hi) {
        return Err(Error::invalid(format!(
            "scatter scale {}..{} is out of range; allowed: {lo} to {hi}, the smaller first",
            p.scale.0, p.scale.1
        )));
    }
    check_region(p.region)?;
    check_region_fits(volume, p.region)
}

/// A region's own values: a box within the allowed positions, its first corner nowhere past
/// its second; a depth band with 0 <= from <= to <= 1.
pub fn check_region(region: Region) -> Result<()> {
    match region {
        Region::Box(a, b) => {
            let limit = POSITION_LIMIT;
            if !(within_limit(a) && within_limit(b)) {
                return Err(Error::invalid(format!(
                    "scatter region box {a}..{b} is out of range; allowed: each coordinate -{limit} to {limit}"
                )));
            }
            if let Some(why) = reversed_corners(a, b) {
                return Err(Error::invalid(format!("scatter region box {a}..{b} {why}")));
            }
        }
        Region::Depth(lo, hi) => {
            if !(0.0..=1.0).contains(&lo) || !(lo..=1.0).contains(&hi) {
                return Err(Error::invalid(format!("depth band {lo}..{hi} must satisfy 0 <= from <= to <= 1")));
            }
        }
    }
    Ok(())
}

/// What is wrong with a box from corner `a` to corner `b` whose corners are reversed (the
/// first axis on which `a` lies past `b`), in the words of a manifest's `box:X0,Y0,Z0,X1,Y1,Z1`;
/// `None` for a box in order.
pub fn reversed_corners(a: Vec3, b: Vec3) -> Option<String> {
    (0..3).find(|&k| a[k] > b[k]).map(|k| {
        let axis = ["X", "Y", "Z"][k];
        format!(
            "has its corners reversed: {axis}0 {} is past {axis}1 {}; allowed: X0 <= X1, Y0 <= Y1, Z0 <= Z1",
            a[k], b[k]
        )
    })
}

/// Whether the box `lo..hi` (voxel coordinates) reaches into a volume of `dims` voxels.
fn meets_volume(lo: Vec3, hi: Vec3, dims: [usize; 3]) -> bool {
    let top = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
    lo.cmplt(top).all() && hi.cmpgt(Vec3::ZERO).all()
}

/// Whether `volume` has what `region` reads: a box must reach into it, a depth band needs
/// a Depth channel.
pub fn check_region_fits(volume: &Volume, region: Region) -> Result<()> {
    let d = volume.dims();
    if let Region::Box(lo, hi) = region
        && !meets_volume(lo, hi, d)
    {
        return Err(Error::invalid(format!(
            "the box ({}, {}, {}) to ({}, {}, {}) lies wholly outside the {}x{}x{} volume; seeds are placed inside \
             it (voxel coordinates 0 to the size)",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, d[0], d[1], d[2]
        )));
    }
    if matches!(region, Region::Depth(..)) && volume.channel_index(&Channel::Depth).is_none() {
        let names = crate::volume::channel_names(volume.channels());
        return Err(Error::invalid(format!(
            "the volume has no Depth channel (its channels: {names}), so it has no depth band to scatter \
             in; a sweep with a depth axis makes one (sweep --depth-axis, or depth_axis in a manifest), or \
             scatter in a box"
        )));
    }
    Ok(())
}

/// Centre and radius of a sphere around the mesh (bounding-box centre, farthest vertex).
pub fn bounding_sphere(mesh: &Mesh) -> (Vec3, f32) {
    let (lo, hi) = mesh.bounds();
    let centre = (lo + hi) / 2.0;
    let radius = mesh.vertices.iter().map(|v| v.distance(centre)).fold(0.0, f32::max);
    (centre, radius)
}

/// A uniformly random rotation (Shoemake's method).
fn random_rotation(rng: &mut Pcg64) -> Quat {
    let (u1, u2, u3): (f32, f32, f32) = (rng.random(), rng.random(), rng.random());
    let tau = std::f32::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    Quat::from_xyzw(a * (tau * u2).sin(), a * (tau * u2).cos(), b * (tau * u3).sin(), b * (tau * u3).cos()).normalize()
}

/// A random point of the region (for a depth band: a random voxel, kept only if its depth fits).
fn random_point(volume: &Volume, region: Region, rng: &mut Pcg64) -> Vec3 {
    let d = volume.dims();
    match region {
        Region::Box(lo, hi) => Vec3::new(
            rng.random_range(lo.x..=hi.x.max(lo.x)),
            rng.random_range(lo.y..=hi.y.max(lo.y)),
            rng.random_range(lo.z..=hi.z.max(lo.z)),
        ),
        Region::Depth(lo, hi) => {
            let depth = volume.channel_index(&Channel::Depth).expect("checked up front");
            let p = [0, 1, 2].map(|k| rng.random_range(0..d[k]));
            let value = volume.get(p[0], p[1], p[2], depth);
            let inside = (lo..=hi).contains(&value);
            let at = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) + 0.5;
            if inside { at } else { Vec3::splat(f32::NAN) }
        }
    }
}

/// A local blur: Gaussian-blurred values blended in inside a sphere, fully (times
/// `strength`) at the centre and fading to nothing at the radius. Returns how many voxels
/// it blended: those whose centre lies inside the sphere, none at strength 0.
pub fn blur(volume: &mut Volume, at: Vec3, radius: f32, strength: f32) -> Result<usize> {
    let (lo, hi) = RADIUS;
    if !((lo..=hi).contains(&radius) && (0.0..=1.0).contains(&strength)) {
        return Err(Error::invalid(format!(
            "blur radius {radius} or strength {strength} is out of range; allowed: radius {lo} to {hi} voxels, \
             strength 0 to 1"
        )));
    }
    let limit = POSITION_LIMIT;
    if !within_limit(at) {
        return Err(Error::invalid(format!(
            "blur centre ({}, {}, {}) is out of range; allowed: each coordinate -{limit} to {limit}",
            at.x, at.y, at.z
        )));
    }
    let d = volume.dims();
    let lo = [0, 1, 2].map(|k| (at[k] - radius).floor().max(0.0) as usize);
    let hi = [0, 1, 2].map(|k| ((at[k] + radius).ceil().max(0.0) as usize).min(d[k]));
    if (0..3).any(|k| lo[k] >= hi[k]) {
        return Err(Error::invalid(format!(
            "the blur sphere at ({}, {}, {}) with radius {radius} misses the {}x{}x{} volume",
            at.x, at.y, at.z, d[0], d[1], d[2]
        )));
    }
    let blurred = box_gaussian(volume, lo, hi);
    let n = volume.channel_count();
    // Depth is where a voxel lies between the skin and the core, not a colour: it stays
    let blurs: Vec<usize> = (0..n).filter(|&c| volume.channels()[c] != Channel::Depth).collect();
    let mut changed = 0;
    for z in lo[2]..hi[2] {
        for y in lo[1]..hi[1] {
            for x in lo[0]..hi[0] {
                let r = (Vec3::new(x as f32, y as f32, z as f32) + 0.5).distance(at) / radius;
                if r >= 1.0 {
                    continue;
                }
                let w = strength * (1.0 - r * r).powi(2);
                if w <= 0.0 {
                    continue;
                }
                let i = ((z - lo[2]) * (hi[1] - lo[1]) + (y - lo[1])) * (hi[0] - lo[0]) + (x - lo[0]);
                let voxel = volume.voxel_mut(x, y, z);
                for &c in &blurs {
                    voxel[c] += w * (blurred[i * n + c] - voxel[c]);
                }
                changed += 1;
            }
        }
    }
    if changed == 0 && strength > 0.0 {
        return Err(Error::invalid(format!(
            "the blur sphere at ({}, {}, {}) with radius {radius} holds no voxel's centre (voxel i's centre is at \
             i + 0.5): a larger radius, or a centre such as ({}, {}, {}), blurs some",
            at.x,
            at.y,
            at.z,
            at.x.floor() + 0.5,
            at.y.floor() + 0.5,
            at.z.floor() + 0.5
        )));
    }
    Ok(changed)
}

/// The 3x3x3 binomial blur (applied twice) of the box `lo..hi`, reading neighbours
/// outside the box from the volume (clamped at its border).
fn box_gaussian(volume: &Volume, lo: [usize; 3], hi: [usize; 3]) -> Vec<f32> {
    let n = volume.channel_count();
    let d = volume.dims();
    let size = [0, 1, 2].map(|k| hi[k] - lo[k]);
    let mut out = vec![0.0f32; size.iter().product::<usize>() * n];
    let w1 = [0.0625f32, 0.25, 0.375, 0.25, 0.0625];
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let at = ((z * size[1] + y) * size[0] + x) * n;
                for (k, wz) in w1.iter().enumerate() {
                    let zz = (lo[2] + z + k).saturating_sub(2).min(d[2] - 1);
                    for (j, wy) in w1.iter().enumerate() {
                        let yy = (lo[1] + y + j).saturating_sub(2).min(d[1] - 1);
                        for (i, wx) in w1.iter().enumerate() {
                            let xx = (lo[0] + x + i).saturating_sub(2).min(d[0] - 1);
                            let w = wx * wy * wz;
                            for (o, v) in out[at..at + n].iter_mut().zip(volume.voxel(xx, yy, zz)) {
                                *o += w * v;
                            }
                        }
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey() -> Volume {
        Volume::from_fn([8; 3], Channel::rgb(), |_, _, _, o| o.fill(0.5)).unwrap()
    }

    fn placed(at: Vec3, scale: f32) -> Placement {
        Placement { at, rotation: Quat::IDENTITY, scale: Vec3::splat(scale) }
    }

    #[test]
    fn values_out_of_range_are_refused_and_change_nothing() {
        let seed = crate::sections::seed_mesh(8, 8).unwrap();
        let mut v = grey();
        let error = |r: Result<Stamped>| r.unwrap_err().to_string();
        assert!(
            error(stamp(&mut v, &seed, &placed(Vec3::new(f32::NAN, 1.0, 1.0), 1.0), [0.0; 3])).contains("position")
        );
        assert!(error(stamp(&mut v, &seed, &placed(Vec3::splat(4.0), 1.0e9), [0.0; 3])).contains("0.001 to 10000"));
        let whole = Region::Box(Vec3::ZERO, Vec3::splat(8.0));
        let many = Scatter { count: 10_000_000, region: whole, scale: (1.0, 1.0), colour: [0.0; 3], attempts: 200 };
        assert!(scatter(&mut v, &seed, &many, 1).unwrap_err().to_string().contains("1 to 2000"));
        let wide = Scatter { count: 1, region: Region::Box(Vec3::splat(-3.0e38), Vec3::splat(3.0e38)), ..many };
        assert!(scatter(&mut v, &seed, &wide, 1).unwrap_err().to_string().contains("region box"));
        assert!(blur(&mut v, Vec3::splat(4.0), 1.0e9, 1.0).unwrap_err().to_string().contains("0.1 to 64"));
        assert!(blur(&mut v, Vec3::new(f32::NAN, 0.0, 0.0), 2.0, 1.0).unwrap_err().to_string().contains("centre"));
        let between = blur(&mut v, Vec3::splat(4.0), 0.5, 1.0).unwrap_err().to_string();
        assert!(between.contains("holds no voxel's centre") && between.contains("(4.5, 4.5, 4.5)"), "{between}");
        assert_eq!(v, grey());
    }

    #[test]
    fn a_scattered_seed_smaller_than_a_voxel_is_counted_as_too_small_not_placed() {
        let seed = crate::sections::seed_mesh(8, 8).unwrap();
        let mut v = grey();
        let tiny = Scatter {
            count: 3,
            region: Region::Box(Vec3::ZERO, Vec3::splat(8.0)),
            scale: (0.001, 0.001),
            colour: [0.0; 3],
            attempts: 200,
        };
        let done = scatter(&mut v, &seed, &tiny, 1).unwrap();
        assert_eq!((done.placed.len(), done.too_small), (0, 3));
        assert_eq!(v, grey(), "no voxel changed");
        let outside = stamp(&mut v, &seed, &placed(Vec3::splat(500.0), 1.0), [0.0; 3]).unwrap_err();
        assert!(outside.to_string().contains("wholly outside"), "{outside}");
        let flat = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).unwrap();
        let none = stamp(&mut v, &flat, &placed(Vec3::splat(4.0), 3.0), [0.0; 3]).unwrap_err();
        assert!(none.to_string().contains("encloses no volume"), "{none}");
        let none = scatter(&mut v, &flat, &Scatter { scale: (3.0, 3.0), ..tiny }, 1).unwrap_err();
        assert!(none.to_string().contains("encloses no volume"), "scattered: {none}");
        let small = stamp(&mut v, &seed, &placed(Vec3::splat(4.0), 0.001), [0.0; 3]).unwrap_err();
        assert!(small.to_string().contains("smaller than a voxel"), "a closed seed at the least scale: {small}");
    }

    /// A blur softens the colours and leaves Depth (where a voxel lies between skin and
    /// core) as it was.
    #[test]
    fn a_blur_keeps_depth() {
        let channels = vec![Channel::R, Channel::G, Channel::B, Channel::Depth];
        let ramp = |_: usize, _: usize, z: usize, o: &mut [f32]| {
            let d = z as f32 / 7.0;
            o.copy_from_slice(&[if z.is_multiple_of(2) { 1.0 } else { 0.0 }, 0.5, 0.5, d]);
        };
        let before = Volume::from_fn([8; 3], channels.clone(), ramp).unwrap();
        let mut v = before.clone();
        blur(&mut v, Vec3::splat(4.0), 8.0, 1.0).unwrap();
        let (d, r) = (v.channel_index(&Channel::Depth).unwrap(), v.channel_index(&Channel::R).unwrap());
        let (b, a) = (before.data(), v.data());
        assert!((0..512).all(|i| a[i * 4 + d] == b[i * 4 + d]), "depth as it was");
        assert!((0..512).any(|i| (a[i * 4 + r] - b[i * 4 + r]).abs() > 0.1), "the stripes are softened");
    }
}
