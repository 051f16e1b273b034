//! `update` for stamp mode: a seed mesh placed over the exemplar's slices, moved, turned and
//! scaled with keys; Enter stamps it into the volume, `n` scatters ten, `u` undoes, `s`
//! saves what was stamped as manifest steps. Pure: the stamping is plain computation, the
//! mesh loading and the saving are effects.

use super::message::Effect;
use super::model::{ExemplarView, Model, Screen, StampMode, StampStep};
use crate::mesh::{Mesh, voxelize};
use crate::stamp::{self, Placement, Region, Scatter};
use glam::{Quat, Vec3};
use std::sync::Arc;

/// The colour stamped seeds get (a dark seed).
pub const SEED_COLOUR: [f32; 3] = [0.09, 0.067, 0.043];
/// Seeds per scatter.
pub const SCATTER_COUNT: usize = 10;

fn view(model: &mut Model) -> Option<&mut ExemplarView> {
    match &mut model.screen {
        Screen::Exemplar(v) if v.volume.is_some() => Some(v),
        _ => None,
    }
}

/// `m`: ask for the seed mesh, or leave stamp mode.
pub fn toggle(model: &mut Model) -> Vec<Effect> {
    let Some(v) = view(model) else { return Vec::new() };
    if v.stamp.take().is_some() {
        model.status = "stamp mode off".into();
        return Vec::new();
    }
    let name = v.name.clone();
    model.status = "loading the seed mesh...".into();
    vec![Effect::LoadSeed(name)]
}

/// The seed mesh arrived: place it at the volume's centre, a tenth of its size.
pub fn seed_loaded(model: &mut Model, result: Result<(Arc<Mesh>, Option<String>), String>) {
    let Some(v) = view(model) else { return };
    let (mesh, file) = match result {
        Ok(found) => found,
        Err(e) => {
            model.status = format!("no seed mesh: {e}");
            return;
        }
    };
    let dims = v.volume.as_ref().map(|vol| vol.dims()).unwrap_or([1; 3]);
    let (_, radius) = stamp::bounding_sphere(&mesh);
    let size = *dims.iter().min().unwrap_or(&1) as f32 / 10.0;
    let at = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) / 2.0;
    let placement = Placement { at, rotation: Quat::IDENTITY, scale: Vec3::splat(size / radius.max(1e-6)) };
    let outline = Arc::new(voxelize(&mesh.transformed(placement.matrix()), dims, 1));
    let source = file.clone().unwrap_or_else(|| "the built-in seed".into());
    v.stamp = Some(StampMode { mesh, file, placement, outline, undo: Vec::new(), steps: Vec::new(), next_seed: 1 });
    follow(v);
    model.status = format!(
        "stamp mode ({source}): arrows/pgup/pgdn move, r/R turn, +/- scale, enter stamps, n scatters, u undo, s saves"
    );
}

/// Keep the slices through the seed and its outline current.
fn follow(v: &mut ExemplarView) {
    let Some(s) = &mut v.stamp else { return };
    let dims = v.volume.as_ref().map(|vol| vol.dims()).unwrap_or([1; 3]);
    s.outline = Arc::new(voxelize(&s.mesh.transformed(s.placement.matrix()), dims, 1));
    for (k, (index, side)) in v.index.iter_mut().zip(dims).enumerate() {
        *index = (s.placement.at[k].round().max(0.0) as usize).min(side - 1);
    }
}

/// Move the seed: `step` is (right, up, along) the current slice axis, in voxels.
pub fn move_seed(model: &mut Model, step: [i32; 3]) {
    let Some(v) = view(model) else { return };
    let (a, b) = v.axis.plane_axes();
    let k = v.axis.index();
    if let Some(s) = &mut v.stamp {
        s.placement.at[a] += step[0] as f32;
        s.placement.at[b] += step[1] as f32;
        s.placement.at[k] += step[2] as f32;
        follow(v);
    }
}

/// Turn the seed about the current slice axis.
pub fn turn(model: &mut Model, degrees: f32) {
    let Some(v) = view(model) else { return };
    let mut axis = Vec3::ZERO;
    axis[v.axis.index()] = 1.0;
    if let Some(s) = &mut v.stamp {
        s.placement.rotation = Quat::from_axis_angle(axis, degrees.to_radians()) * s.placement.rotation;
        follow(v);
    }
}

/// Scale the seed, from a voxel across up to as wide as the volume's longest side.
pub fn scale(model: &mut Model, factor: f32) {
    let Some(v) = view(model) else { return };
    let longest = v.volume.as_ref().map_or(1, |vol| vol.dims().into_iter().max().unwrap_or(1)) as f32;
    let Some(s) = &mut v.stamp else { return };
    let (_, radius) = stamp::bounding_sphere(&s.mesh);
    let radius = radius.max(1e-6);
    let (smallest, largest) = (0.5 / radius, longest / (2.0 * radius));
    let wanted = s.placement.scale.x * factor;
    let scale = wanted.clamp(smallest, largest);
    s.placement.scale = Vec3::splat(scale);
    follow(v);
    let across = 2.0 * radius * scale;
    model.status = if wanted > largest {
        format!("the seed is {across:.0} voxels across, as wide as the volume: it grows no further")
    } else if wanted < smallest {
        "the seed is one voxel across: it shrinks no further".to_string()
    } else {
        format!("the seed is {across:.1} voxels across")
    };
}

/// Enter: stamp the seed into the volume.
pub fn stamp_seed(model: &mut Model) {
    let Some(v) = view(model) else { return };
    let (Some(s), Some(volume)) = (&mut v.stamp, &v.volume) else { return };
    let mut next = (**volume).clone();
    let result = stamp::stamp(&mut next, &s.mesh, &s.placement, SEED_COLOUR);
    model.status = match result {
        Ok(done) => {
            s.undo.push(volume.clone());
            s.steps.push(StampStep::Stamp(s.placement));
            v.volume = Some(Arc::new(next));
            format!("stamped {} voxels ({} step(s) to save with s)", done.voxels, s.steps.len())
        }
        Err(e) => format!("not stamped: {e}"),
    };
}

/// `n`: scatter ten seeds around the current scale.
pub fn scatter(model: &mut Model) {
    let Some(v) = view(model) else { return };
    let (Some(s), Some(volume)) = (&mut v.stamp, &v.volume) else { return };
    let mut next = (**volume).clone();
    let d = next.dims();
    let scale = s.placement.scale.x;
    let region = Region::Box(Vec3::ZERO, Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32));
    let params =
        Scatter { count: SCATTER_COUNT, region, scale: (scale * 0.8, scale * 1.2), colour: SEED_COLOUR, attempts: 200 };
    let seed = s.next_seed;
    model.status = match stamp::scatter(&mut next, &s.mesh, &params, seed) {
        Ok(done) => {
            s.undo.push(volume.clone());
            s.steps.push(StampStep::Scatter { count: SCATTER_COUNT, scale: params.scale, seed });
            s.next_seed += 1;
            v.volume = Some(Arc::new(next));
            let small = match done.too_small {
                0 => String::new(),
                n => format!("; {n} smaller than a voxel changed nothing (+ grows the seed)"),
            };
            format!("scattered {} seeds (seed {seed}){small}", done.placed.len())
        }
        Err(e) => format!("not scattered: {e}"),
    };
}

/// `u`: take back the last stamp or scatter.
pub fn undo(model: &mut Model) {
    let Some(v) = view(model) else { return };
    let Some(s) = &mut v.stamp else { return };
    match s.undo.pop() {
        Some(previous) => {
            s.steps.pop();
            v.volume = Some(previous);
            model.status = format!("undone ({} step(s) left)", s.steps.len());
        }
        None => model.status = "nothing to undo".into(),
    }
}

/// `s`: append the stamps and scatters to the manifest as steps.
pub fn save(model: &mut Model) -> Vec<Effect> {
    let Some(v) = view(model) else { return Vec::new() };
    let name = v.name.clone();
    let Some(s) = &v.stamp else { return Vec::new() };
    let (steps, file) = (s.steps.clone(), s.file.clone());
    match (steps.is_empty(), file) {
        (true, _) => model.status = "nothing stamped yet".into(),
        (false, None) => {
            model.status =
                "the built-in seed has no file: put a seed mesh (.obj) beside the manifest to save steps".into()
        }
        (false, Some(file)) => {
            model.status = format!("saving {} step(s) into the manifest", steps.len());
            return vec![Effect::SaveSteps(name, steps, file)];
        }
    }
    Vec::new()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::message::Message;
    use crate::tui::model::{BuildState, Item};
    use crate::tui::update;
    use crate::volume::{Axis, Channel, Volume};
    use std::path::PathBuf;

    fn stamping() -> Model {
        let item = Item {
            name: "a".into(),
            declared: None,
            size: None,
            state: BuildState::Built("0".into()),
            quality: None,
            previous: false,
        };
        let mut m = Model::new(PathBuf::from("lib.toml"), PathBuf::from("out"), vec![item], Vec::new());
        update(&mut m, Message::Open);
        let grey = Volume::from_fn([32; 3], Channel::rgb(), |_, _, _, o| o.fill(0.8)).unwrap();
        update(&mut m, Message::Loaded("a".into(), Ok(Arc::new(grey))));
        assert_eq!(update(&mut m, Message::StampMode), vec![Effect::LoadSeed("a".into())]);
        let ball = crate::mesh::shapes::ellipsoid(Vec3::ONE, 8, 16);
        update(&mut m, Message::SeedLoaded(Ok((Arc::new(ball), Some("seed.obj".into())))));
        m
    }

    fn view_of(m: &Model) -> &ExemplarView {
        let Screen::Exemplar(v) = &m.screen else { panic!("the exemplar view") };
        v
    }

    /// `o` opens a picker of meshes in the manifest's folder; a chosen mesh is read as the
    /// seed and the view comes back; esc keeps the seed; unsaved stamps refuse the picker.
    #[test]
    fn o_picks_another_seed_mesh() {
        use crate::tui::new_entry::{FileKind, FileRow};
        let mut m = stamping();
        assert_eq!(update(&mut m, Message::PickSeed), vec![Effect::List(PathBuf::from("."), FileKind::Mesh)]);
        update(&mut m, Message::Back);
        assert!(view_of(&m).stamp.is_some() && m.status == "the seed mesh stays", "{}", m.status);
        update(&mut m, Message::PickSeed);
        let rows = vec![FileRow { name: "..".into(), folder: true }, FileRow { name: "pip.stl".into(), folder: false }];
        update(&mut m, Message::Listed(PathBuf::from("."), Ok((PathBuf::from("/w"), rows))));
        update(&mut m, Message::Down);
        assert_eq!(update(&mut m, Message::Open), vec![Effect::LoadSeedFile(PathBuf::from("/w/pip.stl"))]);
        assert!(view_of(&m).stamp.is_some(), "back on the slices, still stamping");
        update(&mut m, Message::Stamp);
        assert!(update(&mut m, Message::PickSeed).is_empty() && m.status.contains("save (s) or undo (u)"));
    }

    #[test]
    fn the_seed_moves_with_the_slices_stamps_and_undoes() {
        let mut m = stamping();
        assert_eq!(view_of(&m).index, [16, 16, 16]);
        update(&mut m, Message::SelectAxis(Axis::Z));
        update(&mut m, Message::MoveSeed([3, -2, 1]));
        assert_eq!(view_of(&m).index, [19, 14, 17], "the slices follow the seed");
        assert!(!view_of(&m).stamp.as_ref().unwrap().outline.is_empty());
        update(&mut m, Message::Stamp);
        let dark = view_of(&m).volume.as_ref().unwrap().get(19, 14, 17, 0);
        assert!(dark < 0.2, "the seed's colour at its centre: {dark}");
        assert_eq!(update(&mut m, Message::SaveSteps).len(), 1);
        update(&mut m, Message::Undo);
        assert_eq!(view_of(&m).volume.as_ref().unwrap().get(19, 14, 17, 0), 0.8);
        assert!(update(&mut m, Message::SaveSteps).is_empty());
        update(&mut m, Message::Scatter);
        let s = view_of(&m).stamp.as_ref().unwrap();
        assert!(matches!(s.steps[..], [StampStep::Scatter { count: 10, seed: 1, .. }]), "{:?}", s.steps);
        update(&mut m, Message::StampMode);
        assert!(view_of(&m).stamp.is_some() && m.status.contains("unsaved stamps"), "{}", m.status);
        update(&mut m, Message::StampMode);
        assert!(view_of(&m).stamp.is_none(), "m again leaves stamp mode");
    }

    #[test]
    fn stamps_are_not_dropped_without_asking() {
        let mut m = stamping();
        update(&mut m, Message::Stamp);
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Exemplar(_)) && m.status.contains("unsaved stamps"), "{}", m.status);
        update(&mut m, Message::Quit);
        assert!(!m.quit, "q asks too");
        update(&mut m, Message::Saved(Ok(String::new())));
        assert!(matches!(&m.items[0].state, BuildState::Changed(t, _) if t == "0"));
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Library), "saved stamps leave without a question");
    }

    #[test]
    fn the_seed_grows_no_wider_than_the_volume() {
        let mut m = stamping();
        for _ in 0..40 {
            update(&mut m, Message::ScaleSeed(1.15));
        }
        let s = view_of(&m).stamp.as_ref().unwrap();
        let (_, radius) = stamp::bounding_sphere(&s.mesh);
        assert!(2.0 * radius * s.placement.scale.x <= 32.0 + 1e-3, "{}", s.placement.scale.x);
        assert!(m.status.contains("grows no further"), "{}", m.status);
        update(&mut m, Message::Stamp);
        let v = view_of(&m).volume.as_ref().unwrap();
        let dark = v.data().chunks_exact(3).filter(|p| p[0] < 0.2).count();
        assert!(dark < 32 * 32 * 32 * 6 / 10, "a ball as wide as the volume covers about half of it: {dark}");
    }
}
