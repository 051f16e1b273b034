//! Hand-made solids, part 1 (thesis §4.3): sweep a 2D cross-section along an axis,
//! perturb it with noise, and add a thin skin at the depth-0 face.
//!
//! ```text
//!   image (w x h)               volume: image x -> first plane axis, image y -> second,
//!   +---------+                 repeated `length` times along the sweep axis
//!   | skin    |  <- row 0       with a Depth channel, depth runs along one plane axis:
//!   | flesh   |                 0 at its first face (the skin), 1 at the far face
//!   | core    |
//!   +---------+
//! ```

use crate::error::{Error, Result};
use crate::noise::{Fbm, fbm};
use crate::volume::{Axis, Channel, Image2d, Meta, Volume, luminance};
use glam::Vec3;

/// Allowed displacement amplitudes, in voxels.
pub const AMPLITUDE: (f32, f32) = (0.0, 64.0);
/// Allowed noise frequencies, in cells across the longest side.
pub const FREQUENCY: (f32, f32) = (0.0, 64.0);
/// Allowed colour jitter amplitudes.
pub const JITTER: (f32, f32) = (0.0, 1.0);
/// Allowed skin widths and width noises, in voxels.
pub const SKIN_WIDTH: (f32, f32) = (0.0, 64.0);

/// Noise that displaces where the cross-section is sampled, plus colour jitter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Largest displacement, in voxels.
    pub amplitude: f32,
    /// Noise cells across the volume's longest side (whole numbers tile seamlessly).
    pub frequency: f32,
    /// Colour jitter amplitude (added to every colour channel), 0 for none.
    pub jitter: f32,
}

/// What covers the depth-0 face.
#[derive(Debug, Clone, PartialEq)]
pub enum SkinLook {
    /// A flat colour (R, G, B).
    Colour([f32; 3]),
    /// An image mapped over the face: image x along the first other axis, y along the other.
    Image(Image2d),
}

/// A thin exterior layer at the depth-0 face.
#[derive(Debug, Clone, PartialEq)]
pub struct Skin {
    /// What it looks like.
    pub look: SkinLook,
    /// Thickness in voxels (fractions are blended).
    pub width: f32,
    /// How much the thickness varies, in voxels.
    pub width_noise: f32,
}

/// A sweep: the cross-section, how far it is swept, and what is added.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// Voxels along the sweep axis.
    pub length: usize,
    /// The axis the cross-section is extruded along.
    pub axis: Axis,
    /// The in-plane axis depth runs along (adds a Depth channel), if any.
    pub depth_axis: Option<Axis>,
    /// Sampling noise, if any.
    pub noise: Option<Noise>,
    /// Exterior skin at depth 0, if any (needs `depth_axis`).
    pub skin: Option<Skin>,
    /// A grey relief the size of the cross-section, swept like it into a Displacement
    /// channel (its first channel; 0.5 leaves a surface in place), if any.
    pub displacement: Option<Image2d>,
}

/// The dims and channels of the volume [`sweep`] makes of `image`.
pub fn swept_shape(image: &Image2d, params: &Sweep) -> ([usize; 3], Vec<Channel>) {
    let (a, b) = params.axis.plane_axes();
    let mut dims = [0; 3];
    dims[params.axis.index()] = params.length;
    dims[a] = image.width();
    dims[b] = image.height();
    let mut channels = image.channels().to_vec();
    if params.depth_axis.is_some() {
        channels.push(Channel::Depth);
    }
    if params.displacement.is_some() {
        channels.push(Channel::Displacement);
    }
    (dims, channels)
}

/// Sweep `image` into a volume; `seed` drives the noise.
pub fn sweep(image: &Image2d, params: &Sweep, seed: u64) -> Result<Volume> {
    check(image, params)?;
    let (a, b) = params.axis.plane_axes();
    let (dims, channels) = swept_shape(image, params);
    let colour = colour_positions(image)?;
    let n_in = image.channel_count();
    let relief_at = n_in + usize::from(params.depth_axis.is_some());
    let fields = params.noise.map(|n| NoiseFields::new(n, seed));
    let volume = Volume::from_fn_par(dims, channels, |x, y, z, out| {
        let p = [x, y, z];
        let q = displaced(params, fields.as_ref(), dims, p);
        sample_bilinear(image, q[a], q[b], &mut out[..n_in]);
        if let (Some(noise), Some(f)) = (params.noise.filter(|n| n.jitter > 0.0), &fields) {
            let j = noise.jitter * f.jitter.sample(cell(p, dims, noise.frequency * 2.0));
            for &c in &colour {
                out[c] = (out[c] + j).clamp(0.0, 1.0);
            }
        }
        if let Some(d) = params.depth_axis {
            out[n_in] = if dims[d.index()] > 1 { p[d.index()] as f32 / (dims[d.index()] - 1) as f32 } else { 0.0 };
        }
        if let Some(relief) = &params.displacement {
            let mut grey = [0.0];
            sample_bilinear(relief, q[a], q[b], &mut grey);
            out[relief_at] = grey[0];
        }
    })?;
    let mut volume = volume;
    if let (Some(skin), Some(d)) = (&params.skin, params.depth_axis) {
        add_skin(&mut volume, skin, d, &colour, seed);
    }
    let mut meta = Meta::default();
    meta.set("recipe", "sweep");
    meta.set("seed", seed.to_string());
    Ok(volume.with_meta(meta))
}

fn check(image: &Image2d, params: &Sweep) -> Result<()> {
    if params.length == 0 {
        return Err(Error::invalid("sweep length 0: it must be at least 1 voxel"));
    }
    if let Some(d) = params.depth_axis.filter(|d| *d == params.axis) {
        return Err(Error::invalid(format!(
            "the depth axis {d} is the sweep axis; depth must run along one of the cross-section's axes"
        )));
    }
    if let Some(relief) = &params.displacement {
        check_relief(image, relief)?;
    }
    if params.skin.is_some() && params.depth_axis.is_none() {
        return Err(Error::invalid("a skin needs a depth axis: it covers the depth-0 face"));
    }
    if let Some(noise) = &params.noise {
        within("noise amplitude", noise.amplitude, AMPLITUDE)?;
        within("noise frequency", noise.frequency, FREQUENCY)?;
        within("noise jitter", noise.jitter, JITTER)?;
        check_frequency("noise", noise)?;
    }
    if let Some(skin) = &params.skin {
        within("skin width", skin.width, SKIN_WIDTH)?;
        within("skin width noise", skin.width_noise, SKIN_WIDTH)?;
        check_skin(image, skin)?;
    }
    if let Some([x, y, c]) = image.first_non_finite() {
        return Err(Error::invalid(format!("cross-section pixel ({x}, {y}) channel {c} is not finite")));
    }
    Ok(())
}

/// Whether a displacement image `relief` suits the cross-section `image` (the same size).
/// The error is about the displacement image, so a caller can name its file.
pub fn check_relief(image: &Image2d, relief: &Image2d) -> Result<()> {
    if (relief.width(), relief.height()) != (image.width(), image.height()) {
        return Err(Error::invalid(format!(
            "the displacement image is {}x{} but the cross-section is {}x{}; they must be the same size",
            relief.width(),
            relief.height(),
            image.width(),
            image.height()
        )));
    }
    Ok(())
}

/// A noise that moves or jitters anything needs a frequency above 0: at 0 every voxel
/// reads the same point of the noise, which is 0 there.
pub fn check_frequency(label: &str, noise: &Noise) -> Result<()> {
    if noise.frequency == 0.0 && (noise.amplitude > 0.0 || noise.jitter > 0.0) {
        return Err(Error::invalid(format!(
            "{label} frequency 0 gives every voxel the same noise, which moves and jitters nothing; allowed: above 0 \
             to {} (cells across the longest side), or amplitude and jitter 0",
            FREQUENCY.1
        )));
    }
    Ok(())
}

/// Whether `skin` can cover a volume swept from `image`: a skin image needs R, G and B when
/// the cross-section has them (a grey skin image suits only a grey cross-section). The
/// error is about the skin image, so a caller can name its file.
pub fn check_skin(image: &Image2d, skin: &Skin) -> Result<()> {
    if let SkinLook::Image(look) = &skin.look
        && look.channel_count() < 3
        && colour_positions(image).is_ok_and(|c| c.len() == 3)
    {
        return Err(Error::invalid(format!(
            "the skin image has {} channel(s) ({}) but the cross-section has R, G and B; a skin image must \
             have R, G and B channels for a colour volume",
            look.channel_count(),
            crate::volume::channel_names(look.channels())
        )));
    }
    Ok(())
}

/// An error unless `value` lies in `min..=max` (NaN never does).
fn within(name: &str, value: f32, (min, max): (f32, f32)) -> Result<()> {
    if value >= min && value <= max {
        Ok(())
    } else {
        Err(Error::invalid(format!("{name} {value} is out of range; allowed: {min} to {max}")))
    }
}

/// Positions of the R, G, B roles (all channels for a grey image).
fn colour_positions(image: &Image2d) -> Result<Vec<usize>> {
    let list: Vec<usize> = [Channel::R, Channel::G, Channel::B]
        .iter()
        .filter_map(|c| image.channels().iter().position(|x| x == c))
        .collect();
    if list.is_empty() {
        return Err(Error::invalid("the cross-section has no R, G or B channel to colour"));
    }
    Ok(list)
}

/// A shift of the noise lattice against the voxels: gradient noise is 0 at its lattice
/// points, and a frequency with as many cells (or half as many) as the longest side has
/// voxels would put every voxel centre on one and move nothing. A whole number of cells
/// still tiles (the shift moves the whole periodic field).
const LATTICE_SHIFT: Vec3 = Vec3::new(0.37, 0.61, 0.13);

/// Noise lattice coordinates of voxel `p`'s centre: `frequency` cells across the longest side.
fn cell(p: [usize; 3], dims: [usize; 3], frequency: f32) -> Vec3 {
    let longest = *dims.iter().max().unwrap_or(&1) as f32;
    (Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) + 0.5) * (frequency / longest) + LATTICE_SHIFT
}

fn period(frequency: f32) -> [i64; 3] {
    [(frequency.round() as i64).max(1); 3]
}

/// The three noise fields of a sweep, precomputed once.
struct NoiseFields {
    along_a: Fbm,
    along_b: Fbm,
    jitter: Fbm,
}

impl NoiseFields {
    fn new(noise: Noise, seed: u64) -> NoiseFields {
        NoiseFields {
            along_a: Fbm::new(seed, period(noise.frequency), 2),
            along_b: Fbm::new(seed ^ 0x5eed, period(noise.frequency), 2),
            jitter: Fbm::new(seed ^ 0x71, period(noise.frequency * 2.0), 2),
        }
    }
}

/// Where voxel `p` samples the cross-section (in voxel units along each axis).
fn displaced(params: &Sweep, fields: Option<&NoiseFields>, dims: [usize; 3], p: [usize; 3]) -> [f32; 3] {
    let mut q = [p[0] as f32, p[1] as f32, p[2] as f32];
    if let (Some(noise), Some(f)) = (params.noise.filter(|n| n.amplitude > 0.0), fields) {
        let c = cell(p, dims, noise.frequency);
        let (a, b) = params.axis.plane_axes();
        let [da, db] = f.along_a.sample_many([&f.along_a, &f.along_b], c);
        q[a] += noise.amplitude * da;
        q[b] += noise.amplitude * db;
    }
    q
}

/// Bilinear sample of `image` at (x, y): wraps across x, clamps along y (depth).
fn sample_bilinear(image: &Image2d, x: f32, y: f32, out: &mut [f32]) {
    let (w, h) = (image.width() as i64, image.height() as i64);
    let (x0, y0) = (x.floor(), y.floor());
    let (tx, ty) = (x - x0, y - y0);
    out.fill(0.0);
    for (dx, dy, wt) in
        [(0, 0, (1.0 - tx) * (1.0 - ty)), (1, 0, tx * (1.0 - ty)), (0, 1, (1.0 - tx) * ty), (1, 1, tx * ty)]
    {
        let px = (x0 as i64 + dx).rem_euclid(w) as usize;
        let py = (y0 as i64 + dy).clamp(0, h - 1) as usize;
        for (o, v) in out.iter_mut().zip(image.pixel(px, py)) {
            *o += wt * v;
        }
    }
}

/// Paint the skin over the first `width (+ noise)` voxels along `depth`, blending the last one.
fn add_skin(volume: &mut Volume, skin: &Skin, depth: Axis, colour: &[usize], seed: u64) {
    let dims = volume.dims();
    let d = depth.index();
    let (u, v) = depth.plane_axes();
    let grey = colour.len() == 1;
    for j in 0..dims[v] {
        for i in 0..dims[u] {
            let mut p = [0; 3];
            p[u] = i;
            p[v] = j;
            let wobble = skin.width_noise * fbm(seed ^ 0x5c1, cell(p, dims, 6.0), period(6.0), 2);
            let width = (skin.width + wobble).max(0.0);
            let rgb = skin_colour(&skin.look, i, j, dims[u], dims[v], grey);
            for k in 0..(width.ceil() as usize).min(dims[d]) {
                p[d] = k;
                let share = (width - k as f32).clamp(0.0, 1.0);
                let voxel = volume.voxel_mut(p[0], p[1], p[2]);
                for (n, &c) in colour.iter().enumerate() {
                    voxel[c] += share * (rgb[n.min(2)] - voxel[c]);
                }
            }
        }
    }
}

/// The skin at face position (i, j) of a `w` x `h` face: R, G, B, or for a `grey` volume its
/// luminance three times (a grey skin image's own value).
fn skin_colour(look: &SkinLook, i: usize, j: usize, w: usize, h: usize, grey: bool) -> [f32; 3] {
    let rgb = match look {
        SkinLook::Colour(c) => *c,
        SkinLook::Image(img) => {
            let x = (i * img.width() / w.max(1)).min(img.width() - 1);
            let y = (j * img.height() / h.max(1)).min(img.height() - 1);
            match img.pixel(x, y) {
                [r, g, b, ..] => [*r, *g, *b],
                px => return [px[0]; 3],
            }
        }
    };
    if grey { [luminance(rgb); 3] } else { rgb }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows() -> Image2d {
        // 6 wide, 10 tall; value = row / 9 in every channel.
        let data = (0..60).flat_map(|i| [(i / 6) as f32 / 9.0; 3]).collect();
        Image2d::from_data(6, 10, Channel::rgb(), data).unwrap()
    }

    fn plain(length: usize) -> Sweep {
        Sweep { length, axis: Axis::X, depth_axis: Some(Axis::Z), noise: None, skin: None, displacement: None }
    }

    #[test]
    fn a_relief_image_becomes_the_displacement_channel() {
        let relief =
            Image2d::from_data(6, 10, Channel::grey(), (0..60).map(|i| (i % 6) as f32 / 5.0).collect()).unwrap();
        let v = sweep(&rows(), &Sweep { displacement: Some(relief), ..plain(3) }, 1).unwrap();
        let names: Vec<&str> = v.channels().iter().map(Channel::name).collect();
        assert_eq!(names, ["R", "G", "B", "Depth", "Displacement"]);
        // the relief's column i is the volume's y = i on every slice along the sweep
        for (x, y, z) in [(0, 0, 0), (2, 3, 7), (1, 5, 9)] {
            assert!((v.get(x, y, z, 4) - y as f32 / 5.0).abs() < 1e-6, "{x} {y} {z}");
        }
        let small = Image2d::from_data(3, 10, Channel::grey(), vec![0.5; 30]).unwrap();
        let err = sweep(&rows(), &Sweep { displacement: Some(small), ..plain(3) }, 1).unwrap_err().to_string();
        assert!(err.contains("3x10") && err.contains("6x10"), "{err}");
    }

    #[test]
    fn sweeping_copies_the_section_along_the_axis() {
        let v = sweep(&rows(), &plain(4), 1).unwrap();
        assert_eq!(v.dims(), [4, 6, 10]);
        assert_eq!(v.channels(), &[Channel::R, Channel::G, Channel::B, Channel::Depth]);
        for x in 0..4 {
            assert_eq!(v.voxel(x, 2, 9)[0], 1.0);
            assert_eq!(v.voxel(x, 5, 3)[1], 3.0 / 9.0);
        }
        assert_eq!(v.get(0, 0, 0, 3), 0.0);
        assert_eq!(v.get(0, 0, 9, 3), 1.0);
    }

    #[test]
    fn skin_has_the_asked_thickness() {
        let skin = Skin { look: SkinLook::Colour([1.0, 0.0, 0.0]), width: 2.0, width_noise: 0.0 };
        let v = sweep(&rows(), &Sweep { skin: Some(skin), ..plain(3) }, 1).unwrap();
        for z in 0..10 {
            let red = v.voxel(1, 1, z)[1] == 0.0 && v.voxel(1, 1, z)[0] == 1.0;
            assert_eq!(red, z < 2, "z = {z}");
        }
        let half = Skin { look: SkinLook::Colour([1.0, 1.0, 1.0]), width: 1.5, width_noise: 0.0 };
        let v = sweep(&rows(), &Sweep { skin: Some(half), ..plain(3) }, 1).unwrap();
        assert_eq!(v.voxel(0, 0, 1)[0], 0.5 * (1.0 / 9.0) + 0.5);
    }

    #[test]
    fn noise_moves_samples_and_is_seeded() {
        let noisy = Sweep { noise: Some(Noise { amplitude: 2.0, frequency: 2.0, jitter: 0.0 }), ..plain(8) };
        let a = sweep(&rows(), &noisy, 1).unwrap();
        let b = sweep(&rows(), &noisy, 1).unwrap();
        let c = sweep(&rows(), &noisy, 2).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.data(), c.data());
        assert_ne!(a.data(), sweep(&rows(), &plain(8), 1).unwrap().data());
    }

    /// As many noise cells as the longest side has voxels (10 here), or half as many for the
    /// jitter (which runs at twice the frequency), still move and jitter every sweep:
    /// sampled on the lattice, gradient noise would be 0 at every voxel.
    #[test]
    fn noise_at_the_voxels_own_frequency_moves_and_jitters() {
        let plain_volume = sweep(&rows(), &plain(8), 1).unwrap();
        let moved = Sweep { noise: Some(Noise { amplitude: 2.0, frequency: 10.0, jitter: 0.0 }), ..plain(8) };
        assert_ne!(sweep(&rows(), &moved, 1).unwrap().data(), plain_volume.data());
        let jittered = Sweep { noise: Some(Noise { amplitude: 0.0, frequency: 5.0, jitter: 0.2 }), ..plain(8) };
        assert_ne!(sweep(&rows(), &jittered, 1).unwrap().data(), plain_volume.data());
        let still = Sweep { noise: Some(Noise { amplitude: 2.0, frequency: 0.0, jitter: 0.0 }), ..plain(8) };
        let e = sweep(&rows(), &still, 1).unwrap_err().to_string();
        assert!(e.contains("noise frequency 0") && e.contains("above 0"), "{e}");
    }

    #[test]
    fn bad_sweeps_are_refused() {
        assert!(sweep(&rows(), &plain(0), 1).unwrap_err().to_string().contains("length 0"));
        let same = Sweep { depth_axis: Some(Axis::X), ..plain(2) };
        assert!(sweep(&rows(), &same, 1).unwrap_err().to_string().contains("sweep axis"));
        let skin = Skin { look: SkinLook::Colour([0.0; 3]), width: 1.0, width_noise: 0.0 };
        let no_depth = Sweep { depth_axis: None, skin: Some(skin), ..plain(2) };
        assert!(sweep(&rows(), &no_depth, 1).unwrap_err().to_string().contains("needs a depth axis"));
        for (amplitude, frequency, jitter, name) in
            [(1.0, 2.0e6, 0.0, "noise frequency"), (f32::NAN, 1.0, 0.0, "noise amplitude"), (1.0, 1.0, 2.0, "jitter")]
        {
            let noisy = Sweep { noise: Some(Noise { amplitude, frequency, jitter }), ..plain(2) };
            let e = sweep(&rows(), &noisy, 1).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("out of range"), "{e}");
        }
    }
}
