//! The frame field of sketch-guided solid texturing (Zhang et al. 2011, §4): the designer's
//! strokes and depth give local frames; a smooth frame at every point of the model comes
//! from **harmonic interpolation of quaternions** — the four components solved as four
//! Laplace problems on the tet mesh with the sketched frames as (soft) constraints, then
//! renormalized where they are read.
//!
//! ```text
//!  frame convention (exemplar axis -> model direction):
//!    z  the depth gradient (0 outside, 1 inside: the exemplar's rows from the outside in)
//!    x  the stroke's direction, made orthogonal to z
//!    y  z x x
//!  without depth constraints, or where the gradient runs along the stroke (on a depth
//!  axis), z is the world axis least along the stroke, made orthogonal
//! ```
//!
//! q and -q are the same rotation: each constraint's quaternion is flipped into the
//! hemisphere of the one before it (samples along a stroke, strokes in the spec's order),
//! and the four corners of a tet are flipped towards the first before blending.

use crate::error::{Error, Result};
use crate::fill::field::{Rbf, locate, smooth_at_vertices};
use crate::fill::render::{View, field_cut};
use crate::fill::tets::TetMesh;
use crate::noise::mix64;
use crate::render::{Rgb8, to_u8};
use glam::{Mat3, Quat, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// A frame constraint: at `point`, the rotation taking the exemplar's axes to the model's.
pub type FrameAt = (Vec3, Quat);

/// The frames the strokes give: one per stroke sample `(point, tangent)`, with z along the
/// gradient of the depth through `depth` (when there are depth constraints and the
/// gradient there is clear: not on a depth axis, where it vanishes, nor along the stroke).
/// Each is flipped into the hemisphere of the one before it.
pub fn sketched_frames(directions: &[(Vec3, Vec3)], depth: &[(Vec3, f32)]) -> Result<Vec<FrameAt>> {
    if directions.is_empty() {
        return Err(Error::invalid("the frame field needs at least one direction stroke ([[direction]])"));
    }
    let rbf = if depth.iter().any(|d| d.1 > 0.0) { Some(Rbf::fit(depth)?) } else { None };
    let (lo, hi) = depth.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), (p, _)| (a.min(*p), b.max(*p)));
    // the depth rises from 0 to 1 over about half the model: a gradient far below that is
    // a maximum's (an axis), whose direction means nothing
    let clear = 0.5 / lo.distance(hi).max(1e-6);
    let mut frames: Vec<FrameAt> = Vec::with_capacity(directions.len());
    for &(p, t) in directions {
        let gradient = rbf.as_ref().map(|f| f.gradient(p)).filter(|g| g.length() > clear);
        let z = gradient
            .and_then(Vec3::try_normalize)
            .filter(|g| g.dot(t.normalize_or_zero()).abs() < 0.9)
            .unwrap_or_else(|| least_along(t));
        let mut q = frame(t, z);
        if let Some(&(_, before)) = frames.last()
            && q.dot(before) < 0.0
        {
            q = -q;
        }
        frames.push((p, q));
    }
    Ok(frames)
}

/// The world axis least along `t`.
fn least_along(t: Vec3) -> Vec3 {
    let a = t.abs();
    if a.x <= a.y && a.x <= a.z {
        Vec3::X
    } else if a.y <= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

/// The rotation whose x axis is `x` made orthogonal to `z`, and whose z axis is `z`.
pub fn frame(x: Vec3, z: Vec3) -> Quat {
    let z = z.try_normalize().unwrap_or(Vec3::Z);
    let x = (x - z * z.dot(x)).try_normalize().unwrap_or_else(|| z.any_orthonormal_vector());
    Quat::from_mat3(&Mat3::from_cols(x, z.cross(x), z)).normalize()
}

/// The harmonic quaternion field: four components per vertex (not normalized; read them
/// with [`FrameField::at`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameField {
    /// Per vertex, the solved (x, y, z, w).
    pub components: Vec<[f32; 4]>,
}

/// Solves the four Laplace problems on `mesh` with `frames` as constraints. As in Zhang et
/// al., a frame whose sign disagrees with the field the others make (a later stroke
/// flipped against an earlier one) is flipped to agree with it, and the field solved again.
pub fn solve(mesh: &TetMesh, frames: &[FrameAt]) -> Result<FrameField> {
    if frames.is_empty() {
        return Err(Error::invalid("the frame field needs at least one sketched frame"));
    }
    let first = harmonic(mesh, frames)?;
    let signed: Vec<FrameAt> = frames
        .iter()
        .map(|&(p, q)| {
            let (t, b) = locate(mesh, p);
            let here = first.blend(mesh.tets[t], b);
            (p, if Vec4::from(q).dot(here) < 0.0 { -q } else { q })
        })
        .collect();
    if signed == frames {
        return Ok(first);
    }
    harmonic(mesh, &signed)
}

fn harmonic(mesh: &TetMesh, frames: &[FrameAt]) -> Result<FrameField> {
    let points: Vec<(Vec3, [f32; 4])> = frames.iter().map(|(p, q)| (*p, q.to_array())).collect();
    let solved = smooth_at_vertices(mesh, &points)?;
    let components = solved.chunks_exact(4).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32]).collect();
    Ok(FrameField { components })
}

impl FrameField {
    /// The rotation at barycentric point `b` of `tet`: its corners' quaternions flipped
    /// towards the first, blended, normalized.
    pub fn at(&self, tet: [u32; 4], b: [f32; 4]) -> Quat {
        self.blend(tet, b).try_normalize().map_or(Quat::IDENTITY, Quat::from_vec4)
    }

    /// The corners' four-vectors flipped towards the first and blended (not normalized).
    fn blend(&self, tet: [u32; 4], b: [f32; 4]) -> Vec4 {
        let first = Vec4::from_array(self.components[tet[0] as usize]);
        let mut sum = Vec4::ZERO;
        for (v, w) in tet.iter().zip(b) {
            let q = Vec4::from_array(self.components[*v as usize]);
            sum += if q.dot(first) < 0.0 { -q } else { q } * w;
        }
        sum
    }
}

/// Steps of the line integral along the field, each way.
const LIC_STEPS: usize = 14;

/// The field on a cut: line integral convolution of white noise along each pixel's frame x
/// axis projected onto the cut (streaks follow the strokes' direction), coloured by that
/// axis in model space (|x|, |y|, |z| as red, green, blue); black outside the mesh.
pub fn streamlines(mesh: &TetMesh, field: &FrameField, view: &View) -> Rgb8 {
    let (w, h) = (view.width, view.height);
    let parts: Vec<Vec<Option<f32>>> =
        (0..4).map(|k| field_cut(mesh, &field.components.iter().map(|c| c[k]).collect::<Vec<f32>>(), view)).collect();
    let axes: Vec<Option<Vec3>> = (0..w * h)
        .map(|i| {
            let c = Vec4::new(parts[0][i]?, parts[1][i]?, parts[2][i]?, parts[3][i]?);
            Some(Quat::from_vec4(c.try_normalize()?) * Vec3::X)
        })
        .collect();
    let (right, down) = (view.right.normalize(), view.down.normalize());
    let flow: Vec<Option<Vec2>> =
        axes.iter().map(|a| a.and_then(|a| Vec2::new(a.dot(right), a.dot(down)).try_normalize())).collect();
    let noise: Vec<f32> = (0..w * h).map(|i| (mix64(i as u64) >> 40) as f32 / (1u64 << 24) as f32).collect();
    let pixels: Vec<[u8; 3]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let Some(axis) = axes[i] else { return [0, 0, 0] };
            let streak = integrate(&flow, &noise, (w, h), i);
            let tone = 0.35 + 0.65 * streak;
            axis.abs().to_array().map(|c| to_u8((0.25 + 0.75 * c) * tone))
        })
        .collect();
    let mut out = Rgb8::new(w, h, [0, 0, 0]);
    for (i, c) in pixels.into_iter().enumerate() {
        out.put(i % w, i / w, c);
    }
    out
}

/// The mean noise along the streamline through pixel `start`, both ways.
fn integrate(flow: &[Option<Vec2>], noise: &[f32], (w, h): (usize, usize), start: usize) -> f32 {
    let mut sum = noise[start];
    let mut count = 1.0;
    for sign in [1.0f32, -1.0] {
        let mut p = Vec2::new((start % w) as f32 + 0.5, (start / w) as f32 + 0.5);
        let mut heading = flow[start].unwrap_or(Vec2::ZERO) * sign;
        for _ in 0..LIC_STEPS {
            p += heading;
            if p.x < 0.0 || p.y < 0.0 || p.x >= w as f32 || p.y >= h as f32 {
                break;
            }
            let i = p.y as usize * w + p.x as usize;
            let Some(d) = flow[i] else { break };
            heading = if d.dot(heading) < 0.0 { -d } else { d };
            sum += noise[i];
            count += 1.0;
        }
    }
    sum / count
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    #[test]
    fn the_frame_convention_puts_x_on_the_stroke_and_z_on_the_depth_gradient() {
        let q = frame(Vec3::new(1.0, 0.2, 0.0), Vec3::Y);
        assert!((q * Vec3::Z).distance(Vec3::Y) < 1e-5);
        assert!((q * Vec3::X).distance(Vec3::X) < 1e-5);
        assert!((q * Vec3::Y).distance(-Vec3::Z) < 1e-5, "right-handed: y = z x x");
        let depth =
            [(Vec3::ZERO, 0.0), (Vec3::new(0.0, 1.0, 0.0), 1.0), (Vec3::new(1.0, 0.0, 0.0), 0.0), (Vec3::Z, 0.0)];
        let frames = sketched_frames(&[(Vec3::new(0.3, 0.6, 0.3), Vec3::X)], &depth).unwrap();
        assert!((frames[0].1 * Vec3::Z).dot(Vec3::Y) > 0.99, "z follows the depth gradient");
    }

    /// Frames twisting about x from one face of a cube to the other: the harmonic field
    /// turns smoothly between them, and meets each where it was sketched.
    #[test]
    fn the_harmonic_field_meets_the_sketched_frames_and_turns_smoothly_between() {
        let mesh = cube_lattice([6, 6, 6], 1.0 / 6.0);
        let turned = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let mut frames = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let (y, z) = (0.1 + 0.2 * i as f32, 0.1 + 0.2 * j as f32);
                frames.push((Vec3::new(0.02, y, z), Quat::IDENTITY));
                // one frame given with the other sign: the same rotation, re-signed by the field
                frames.push((Vec3::new(0.98, y, z), if i == 2 && j == 2 { -turned } else { turned }));
            }
        }
        let field = solve(&mesh, &frames).unwrap();
        let at = |p: Vec3| {
            let (t, b) = crate::fill::field::locate(&mesh, p);
            field.at(mesh.tets[t], b)
        };
        assert!(at(Vec3::new(0.02, 0.5, 0.5)).angle_between(Quat::IDENTITY) < 0.1);
        assert!(at(Vec3::new(0.98, 0.5, 0.5)).angle_between(turned) < 0.1);
        let middle = at(Vec3::new(0.5, 0.5, 0.5));
        let half = Quat::from_rotation_x(std::f32::consts::FRAC_PI_4);
        assert!(middle.angle_between(half) < 0.15, "halfway: {middle:?}");
        assert!((middle * Vec3::X).distance(Vec3::X) < 1e-3, "the twist keeps x");
    }

    #[test]
    fn a_picture_of_the_field_streaks_along_the_stroke() {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let frames = vec![(Vec3::splat(0.5), frame(Vec3::X, Vec3::Z))];
        let field = solve(&mesh, &frames).unwrap();
        let view = View::framing((Vec3::ZERO, Vec3::ONE), Vec3::splat(0.5), Vec3::Z, 96).unwrap();
        let picture = streamlines(&mesh, &field, &view);
        // streaks along x: neighbours along a row differ less than along a column
        let (mut along, mut across) = (0.0, 0.0);
        for y in 20..76 {
            for x in 20..76 {
                let v = |x: usize, y: usize| picture.at(x, y)[0] as f32;
                along += (v(x + 1, y) - v(x, y)).abs();
                across += (v(x, y + 1) - v(x, y)).abs();
            }
        }
        assert!(along * 2.0 < across, "along {along} across {across}");
        assert_eq!(picture.at(0, 0), [0, 0, 0], "outside the mesh is black");
        assert!(picture.at(48, 48)[0] > picture.at(48, 48)[1], "x axis shows red");
    }
}
