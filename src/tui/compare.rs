//! Comparing: two exemplars side by side (`v` marks one, `v` on another opens both), or an
//! entry's previous build beside its new one (`V`), accepted with `a` or discarded with
//! `d`. Pure: the volumes arrive as messages.

use super::message::Effect;
use super::model::{BuildState, CompareView, Model, Screen, Side};
use crate::volume::Axis;

fn side(label: String) -> Side {
    Side { label, volume: None, quality: None }
}

fn open(model: &mut Model, labels: [String; 2], before_after: Option<String>) {
    let [a, b] = labels;
    model.screen =
        Screen::Compare(CompareView { sides: [side(a), side(b)], axis: Axis::Z, position: 0.5, before_after });
}

/// `v` on the library: mark the selected built entry, or compare it with the marked one
/// (`v` on the marked one clears the mark).
pub fn compare(model: &mut Model) -> Vec<Effect> {
    let Some(item) = model.items.get(model.selected) else { return Vec::new() };
    if !matches!(item.state, BuildState::Built(_) | BuildState::Changed(..)) {
        model.status = format!("{} is not built: b builds it, then v compares it", item.name);
        return Vec::new();
    }
    let name = item.name.clone();
    match model.mark.take() {
        Some(marked) if marked != name => {
            model.status = format!("{marked} beside {name}: x/y/z and arrows move both slices");
            open(model, [marked.clone(), name.clone()], None);
            vec![Effect::LoadSide(0, marked.clone(), marked, false), Effect::LoadSide(1, name.clone(), name, false)]
        }
        Some(_) => {
            model.status = format!("{name} is no longer marked");
            Vec::new()
        }
        None => {
            model.status = format!("{name} marked: choose another built entry and press v to see both");
            model.mark = Some(name);
            Vec::new()
        }
    }
}

/// `V` on the library: the selected entry's previous build beside its new one.
pub fn before_after(model: &mut Model) -> Vec<Effect> {
    let Some(item) = model.items.get(model.selected) else { return Vec::new() };
    let name = item.name.clone();
    if !item.previous {
        model.status = format!(
            "{name} has no previous build kept: rebuilding a built entry here keeps the one before it until you \
             accept or discard the new one"
        );
        return Vec::new();
    }
    let (before, after) = (format!("{name} before"), format!("{name} after"));
    model.status = format!("{name}: a keeps the new build, d discards it (the previous comes back)");
    open(model, [before.clone(), after.clone()], Some(name.clone()));
    vec![Effect::LoadSide(0, before, name.clone(), true), Effect::LoadSide(1, after, name, false)]
}

fn view(model: &mut Model) -> Option<&mut CompareView> {
    match &mut model.screen {
        Screen::Compare(v) => Some(v),
        _ => None,
    }
}

/// A side arrived; dropped when the screen moved on.
pub fn loaded(model: &mut Model, index: usize, label: &str, result: super::message::SideResult) {
    let Some(v) = view(model) else { return };
    let Some(side) = v.sides.get_mut(index).filter(|s| s.label == label) else { return };
    match result {
        Ok((volume, quality)) => {
            side.volume = Some(Ok(volume));
            side.quality = quality;
        }
        Err(e) => {
            model.status = format!("cannot read {label}: {e}");
            if let Some(side) = view(model).and_then(|v| v.sides.get_mut(index)) {
                side.volume = Some(Err(e));
            }
        }
    }
}

/// x, y, z: the axis of both slices.
pub fn axis(model: &mut Model, axis: Axis) -> bool {
    let Some(v) = view(model) else { return false };
    v.axis = axis;
    true
}

/// Arrows: both slices move by `step` voxels of the left volume.
pub fn move_slice(model: &mut Model, step: i64) -> bool {
    let Some(v) = view(model) else { return false };
    let voxels = v.sides[0].volume.as_ref().and_then(|r| r.as_ref().ok()).map_or(64, |vol| vol.dims()[v.axis.index()]);
    let step = step as f32 / voxels.saturating_sub(1).max(1) as f32;
    v.position = (v.position + step).clamp(0.0, 1.0);
    true
}

/// `a` / `d` in a before-and-after comparison: keep or discard the new build.
pub fn settle(model: &mut Model, accept: bool) -> Vec<Effect> {
    let Some(name) = view(model).and_then(|v| v.before_after.clone()) else {
        model.status = "a and d keep or discard a new build: open one with V on the library".into();
        return Vec::new();
    };
    model.screen = Screen::Library;
    model.status =
        if accept { format!("keeping the new build of {name}") } else { format!("discarding the new build of {name}") };
    vec![Effect::Settle(name, accept)]
}

/// The slice index `position` (0 to 1) gives along an axis of `voxels`.
pub fn index(position: f32, voxels: usize) -> usize {
    (position * voxels.saturating_sub(1) as f32).round() as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::model::Item;
    use crate::tui::{Message, update};
    use crate::volume::{Channel, Volume};
    use std::path::PathBuf;
    use std::sync::Arc;

    fn model() -> Model {
        let item = |n: &str, state, previous| Item {
            name: n.into(),
            declared: None,
            size: None,
            state,
            quality: None,
            previous,
        };
        let items = vec![
            item("a", BuildState::Built("0".into()), true),
            item("b", BuildState::NotBuilt, false),
            item("c", BuildState::Built("0".into()), false),
        ];
        Model::new(PathBuf::from("lib.toml"), PathBuf::from("out"), items, Vec::new())
    }

    #[test]
    fn v_marks_one_entry_and_opens_both_on_another() {
        let mut m = model();
        assert!(update(&mut m, Message::Compare).is_empty());
        assert_eq!(m.mark.as_deref(), Some("a"));
        m.selected = 1;
        assert!(update(&mut m, Message::Compare).is_empty() && m.status.contains("b is not built"));
        m.selected = 2;
        let effects = update(&mut m, Message::Compare);
        let expected = vec![
            Effect::LoadSide(0, "a".into(), "a".into(), false),
            Effect::LoadSide(1, "c".into(), "c".into(), false),
        ];
        assert_eq!(effects, expected);
        assert!(m.mark.is_none() && matches!(m.screen, Screen::Compare(_)));
        let volume = Arc::new(Volume::new([4, 4, 9], Channel::rgb()).unwrap());
        update(&mut m, Message::SideLoaded(1, "someone else".into(), Ok((volume.clone(), None))));
        update(&mut m, Message::SideLoaded(0, "a".into(), Ok((volume, None))));
        let Screen::Compare(v) = &m.screen else { panic!("compare") };
        assert!(v.sides[0].volume.is_some() && v.sides[1].volume.is_none(), "a late side of another label is dropped");
        // both slices move together, by the left volume's voxels
        update(&mut m, Message::MoveSlice(2));
        let Screen::Compare(v) = &m.screen else { panic!("compare") };
        assert!((v.position - 0.75).abs() < 1e-6 && index(v.position, 9) == 6, "{}", v.position);
        update(&mut m, Message::SelectAxis(Axis::X));
        assert!(update(&mut m, Message::Accept).is_empty() && m.status.contains("open one with V"), "{}", m.status);
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Library));
    }

    #[test]
    fn v_upper_shows_the_previous_build_beside_the_new_and_a_or_d_settles_it() {
        let mut m = model();
        m.selected = 2;
        assert!(update(&mut m, Message::BeforeAfter).is_empty() && m.status.contains("no previous build"));
        m.selected = 0;
        let effects = update(&mut m, Message::BeforeAfter);
        let expected = vec![
            Effect::LoadSide(0, "a before".into(), "a".into(), true),
            Effect::LoadSide(1, "a after".into(), "a".into(), false),
        ];
        assert_eq!(effects, expected);
        assert_eq!(update(&mut m, Message::Discard), vec![Effect::Settle("a".into(), false)]);
        assert!(matches!(m.screen, Screen::Library));
        update(&mut m, Message::BeforeAfter);
        assert_eq!(update(&mut m, Message::Accept), vec![Effect::Settle("a".into(), true)]);
    }
}
