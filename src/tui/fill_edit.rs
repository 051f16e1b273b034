//! Placing the constraints of thesis ch. 5 on the fill preview's cut: a cursor on the cut
//! (keys or mouse), direction strokes, depth points, face groups given a depth, manual
//! pastes turned and scaled, the depth field as a colour map, a refill with them, and the
//! fill spec they make written out. Pure: the refill and the writing are effects.

use super::message::Effect;
use super::model::{FillEdit, FillView, Model, OverlayKey, Screen};
use crate::fill::render::{self, View};
use crate::fill::spec::{FaceGroup, FillSpec, PasteSpec};
use crate::library::guided::{Overlay, Picture};
use glam::{Quat, Vec3};
use std::sync::Arc;

/// How far the cursor keys move it: a share of the cut.
pub const CURSOR_STEP: f32 = 1.0 / 32.0;
/// How much `[` and `]` change the depth of new points.
pub const DEPTH_STEP: f32 = 0.25;

/// The plane of the cut on screen as a `size`-pixel square view of the model.
pub fn plane_view(filled: &super::model::FillPreview, axis: crate::volume::Axis, offset: f32, size: usize) -> View {
    let models = [(&filled.model, &filled.textures)];
    let (lo, hi) = render::bounds(&models);
    let mut normal = Vec3::ZERO;
    normal[axis.index()] = 1.0;
    let point = (lo + hi) / 2.0 + normal * (hi - lo) / 2.0 * offset;
    View::framing((lo, hi), point, normal, size).expect("a finite plane and a size in range")
}

/// The model point under the cursor.
pub fn cursor_point(view: &FillView) -> Option<Vec3> {
    let (filled, edit) = (view.filled.as_ref()?, view.edit.as_ref()?);
    let plane = plane_view(filled, view.axis, view.offset, 512);
    Some(plane.origin + plane.right * (edit.cursor[0] * 512.0) + plane.down * (edit.cursor[1] * 512.0))
}

fn editing(model: &mut Model) -> Option<(&mut FillView, Vec3)> {
    let Screen::Fill(view) = &mut model.screen else { return None };
    let at = cursor_point(view)?;
    Some((view, at))
}

/// Move the cursor by (right, down) steps.
pub fn move_cursor(model: &mut Model, right: f32, down: f32) {
    if let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen {
        e.cursor =
            [(e.cursor[0] + right * CURSOR_STEP).clamp(0.0, 1.0), (e.cursor[1] + down * CURSOR_STEP).clamp(0.0, 1.0)];
    }
}

/// Put the cursor at (across, down), 0 to 1 (a click).
pub fn cursor_at(model: &mut Model, across: f32, down: f32) {
    if let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen {
        e.cursor = [across.clamp(0.0, 1.0), down.clamp(0.0, 1.0)];
    }
}

/// Change the spec (kept for undo) and say what changed, and what of it the fill's
/// texture type does not use.
fn change(model: &mut Model, what: impl FnOnce(&mut FillEdit, Vec3) -> Result<String, String>) {
    let Some((view, at)) = editing(model) else {
        model.status = "the fill is still running".into();
        return;
    };
    let filled = view.filled.clone().expect("editing has a fill");
    let edit = view.edit.as_mut().expect("editing has an edit");
    let before = edit.spec.clone();
    model.status = match what(edit, at) {
        Ok(done) => {
            if edit.spec != before {
                edit.undo.push(before.clone());
            }
            match newly_ignored(&filled, &before, &edit.spec).as_slice() {
                [] => format!("{done}; r refills with it, w writes the fill spec"),
                notes => format!("{}; {done}", notes.join("; ")),
            }
        }
        Err(why) => why,
    };
}

/// What `after` asks that the fill's texture type does not use and `before` did not ask.
fn newly_ignored(filled: &super::model::FillPreview, before: &FillSpec, after: &FillSpec) -> Vec<String> {
    let sources = &filled.model.sources;
    let known = crate::fill::spec::ignored(before, filled.kind, sources);
    let notes = crate::fill::spec::ignored(after, filled.kind, sources);
    notes.into_iter().filter(|n| !known.contains(n)).collect()
}

/// The spec was written by `w`: leaving no longer asks, unless it changes again.
pub fn written(model: &mut Model, spec: &FillSpec) {
    if let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen {
        *e.saved = spec.clone();
    }
}

/// A fill spec chosen with `o` arrived: its constraints (strokes, depth, scale points,
/// pastes) replace the preview's (`u` gives them back), for `r` to refill with.
pub fn spec_loaded(model: &mut Model, path: &std::path::Path, result: Result<Box<FillSpec>, String>) {
    let Screen::Fill(FillView { edit: Some(e), name, filled, .. }) = &mut model.screen else { return };
    let loaded = match result {
        Ok(loaded) => loaded,
        Err(why) => {
            model.status = format!("no constraints loaded: {why}");
            return;
        }
    };
    let before = e.spec.clone();
    e.spec.directions = loaded.directions.clone();
    e.spec.depth = loaded.depth.clone();
    e.spec.scales = loaded.scales.clone();
    e.spec.pastes = loaded.pastes.clone();
    e.undo.push(before.clone());
    e.stroke.clear();
    *e.saved = e.spec.clone();
    let other = if loaded.exemplar != *name { format!(" (written for {})", loaded.exemplar) } else { String::new() };
    model.status = format!(
        "loaded {} stroke(s), {} depth point(s), {} face group(s), {} paste(s) from {}{other}; r refills with them",
        e.spec.directions.len(),
        e.spec.depth.points.len(),
        e.spec.depth.faces.len(),
        e.spec.pastes.len(),
        path.display()
    );
    if let Some(filled) = filled {
        let notes = crate::fill::spec::ignored(&e.spec, filled.kind, &filled.model.sources);
        if !notes.is_empty() {
            model.status += &format!("; {}", notes.join("; "));
        }
    }
}

fn show(p: Vec3) -> String {
    format!("{:.2},{:.2},{:.2}", p.x, p.y, p.z)
}

/// `s`: the cursor's point joins the stroke being drawn.
pub fn stroke_point(model: &mut Model) {
    change(model, |e, at| {
        e.stroke.push(at);
        Ok(format!("stroke point {} at {}; S ends the stroke", e.stroke.len(), show(at)))
    });
}

/// A drag on the cut: the cursor follows, and every step of the cursor's size adds a
/// point to the stroke being drawn (the first where the drag started).
pub fn drag(model: &mut Model, across: f32, down: f32) {
    let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen else { return };
    let moved = (e.cursor[0] - across).abs().max((e.cursor[1] - down).abs());
    if e.stroke.is_empty() {
        stroke_point(model);
    }
    if moved < CURSOR_STEP {
        return;
    }
    cursor_at(model, across, down);
    stroke_point(model);
    if let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen {
        e.dragging = true;
    }
}

/// The button went up: a dragged stroke of two points or more becomes a direction stroke.
pub fn end_drag(model: &mut Model) {
    let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen else { return };
    if std::mem::take(&mut e.dragging) && e.stroke.len() >= 2 {
        finish_stroke(model);
    }
}

/// `S`: the stroke drawn becomes a direction stroke of the spec.
pub fn finish_stroke(model: &mut Model) {
    change(model, |e, _| {
        let length: f32 = e.stroke.windows(2).map(|w| w[0].distance(w[1])).sum();
        if e.stroke.len() < 2 || length <= 0.0 {
            return Err("a stroke needs two different points: s adds the cursor's point".into());
        }
        e.spec.directions.push(std::mem::take(&mut e.stroke));
        Ok(format!("direction stroke {} added", e.spec.directions.len()))
    });
}

/// `d`: a depth point at the cursor with the current depth.
pub fn depth_point(model: &mut Model) {
    change(model, |e, at| {
        e.spec.depth.points.push((at, e.depth));
        Ok(format!("depth {:.2} at {}", e.depth, show(at)))
    });
}

/// `[` / `]`: the depth new points and face groups get.
pub fn depth_value(model: &mut Model, step: f32) {
    if let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen {
        e.depth = (e.depth + step).clamp(0.0, 1.0);
        model.status = format!("new depth points and face groups get depth {:.2} (0 surface, 1 innermost)", e.depth);
    }
}

/// `g`: the surface faces connected to the face nearest the cursor whose normals lie within
/// [`SINGLE_FACE_ANGLE`] of its normal get the current depth (the thesis' single-face fill,
/// widened to the faces that continue the clicked one: a lattice of small triangles has no
/// single face worth filling).
pub fn face_group(model: &mut Model) {
    change(model, |e, at| {
        e.spec.depth.faces.push(FaceGroup { at, crease: 30.0, angle: SINGLE_FACE_ANGLE, value: e.depth });
        Ok(format!("the faces within {SINGLE_FACE_ANGLE}° of the face nearest {} get depth {:.2}", show(at), e.depth))
    });
}

/// How far (degrees) the normals of the faces `g` fills may turn from the clicked face's.
pub const SINGLE_FACE_ANGLE: f32 = 20.0;

/// `p`: a manual paste of the exemplar at the cursor, a quarter of the model across.
pub fn paste(model: &mut Model, size: f32) {
    change(model, |e, at| {
        let scale = e.spec.scale.unwrap_or(size / 4.0);
        e.spec.pastes.push(PasteSpec { exemplar: e.spec.exemplar.clone(), at, rotation: Quat::IDENTITY, scale });
        Ok(format!("paste {} at {}; t turns it, +/- scale it", e.spec.pastes.len(), show(at)))
    });
}

/// `t` and `+`/`-`: turn the last paste 15° about the cut's normal, or scale it.
pub fn warp_paste(model: &mut Model, degrees: f32, factor: f32) {
    let normal = match &model.screen {
        Screen::Fill(v) => {
            let mut n = Vec3::ZERO;
            n[v.axis.index()] = 1.0;
            n
        }
        _ => return,
    };
    change(model, |e, _| {
        let count = e.spec.pastes.len();
        let Some(p) = e.spec.pastes.last_mut() else { return Err("no paste to warp: p places one".into()) };
        p.rotation = (Quat::from_axis_angle(normal, degrees.to_radians()) * p.rotation).normalize();
        p.scale *= factor;
        let (_, angle) = p.rotation.to_axis_angle();
        Ok(format!("paste {count} turned {:.0}°, {:.3} across", angle.to_degrees(), p.scale))
    });
}

/// `u`: the last constraint goes (a stroke being drawn first).
pub fn undo(model: &mut Model) {
    let Screen::Fill(FillView { edit: Some(e), .. }) = &mut model.screen else { return };
    model.status = if e.stroke.pop().is_some() {
        "stroke point removed".into()
    } else if let Some(spec) = e.undo.pop() {
        e.spec = spec;
        "undone".into()
    } else {
        "nothing to undo".into()
    };
}

/// `c`: the depth field as a colour map, or the texture again.
pub fn toggle_depth(model: &mut Model) {
    let Screen::Fill(view) = &mut model.screen else { return };
    let has_depth = view.filled.as_ref().is_some_and(|f| f.depth.is_some());
    let Some(e) = &mut view.edit else { return };
    if !has_depth {
        model.status = "this fill has no depth field (its type does not vary with depth)".into();
        return;
    }
    e.show_depth = !e.show_depth;
    model.status =
        if e.show_depth { "the depth field: dark blue 0 (surface) to yellow 1 (innermost)" } else { "the texture" }
            .into();
}

/// Side of the overlay pictures in pixels (drawn scaled to the cut on screen).
pub const OVERLAY_SIZE: usize = 128;

/// `v`: the cut shows the texture, the frame field of the spec as placed (strokes and
/// depth; it follows each finished stroke), or a cut synthesized along that field.
pub fn next_overlay(model: &mut Model) {
    let Screen::Fill(FillView { edit: Some(e), filled: Some(_), .. }) = &mut model.screen else {
        model.status = "the fill is still running".into();
        return;
    };
    e.overlay = match e.overlay {
        None => Some(Overlay::Field),
        Some(Overlay::Field) => Some(Overlay::Guided),
        Some(Overlay::Guided) => None,
    };
    model.status = match e.overlay {
        Some(Overlay::Field) => {
            "the frame field of the strokes and depth (x red, y green, z blue), made after each stroke"
        }
        Some(Overlay::Guided) => "a cut synthesized along the field from the exemplar's central slices (sketch-guided)",
        None => "the texture",
    }
    .into();
}

/// The overlay picture the cut on screen needs, if it is not there and none is being made.
pub fn overlay_due(model: &mut Model) -> Vec<Effect> {
    let Screen::Fill(view) = &mut model.screen else { return Vec::new() };
    let (Some(filled), Some(e)) = (&view.filled, &mut view.edit) else { return Vec::new() };
    let Some(overlay) = e.overlay else { return Vec::new() };
    if e.pending {
        return Vec::new();
    }
    let key = OverlayKey { overlay, axis: view.axis, offset: view.offset, spec: e.spec.clone() };
    if e.picture.as_ref().is_some_and(|(made, _)| **made == key) {
        return Vec::new();
    }
    e.pending = true;
    let shared = super::message::SharedFill(filled.clone());
    vec![Effect::Overlay(view.name.clone(), shared, Box::new(key))]
}

/// An overlay picture arrived: kept with what it shows (the cut shows it while that is
/// still the cut and the spec on screen); a failure turns the overlay off and says why.
pub fn overlay_made(model: &mut Model, name: &str, key: OverlayKey, result: Result<Arc<Picture>, String>) {
    let Screen::Fill(FillView { edit: Some(e), name: shown, .. }) = &mut model.screen else { return };
    if shown != name {
        return;
    }
    e.pending = false;
    match result {
        Ok(picture) => e.picture = Some((Box::new(key), picture)),
        Err(why) => {
            e.overlay = None;
            model.status = match key.overlay {
                Overlay::Field => format!("no frame field: {why}"),
                Overlay::Guided => format!("no guided cut: {why}"),
            };
        }
    }
}

/// The overlay picture to draw on the cut on screen, if it shows that cut and spec.
pub fn overlay_shown(view: &FillView) -> Option<&Picture> {
    let e = view.edit.as_ref()?;
    let (made, picture) = e.picture.as_ref()?;
    let current = e.overlay.is_some_and(|o| o == made.overlay)
        && made.axis == view.axis
        && made.offset == view.offset
        && made.spec == e.spec;
    current.then_some(&**picture)
}

/// `r`: fill again with the constraints placed.
pub fn refill(model: &mut Model) -> Vec<Effect> {
    let Screen::Fill(view) = &mut model.screen else { return Vec::new() };
    let Some(e) = &mut view.edit else { return Vec::new() };
    if view.filled.is_none() || e.refilling {
        model.status = "the fill is still running".into();
        return Vec::new();
    }
    // the fill on screen stays until the new one arrives (or fails: then it is kept)
    e.refilling = true;
    model.status = format!(
        "filling again with {} stroke(s), {} depth point(s), {} face group(s), {} paste(s)",
        e.spec.directions.len(),
        e.spec.depth.points.len(),
        e.spec.depth.faces.len(),
        e.spec.pastes.len()
    );
    vec![Effect::Refill(view.name.clone(), Box::new(e.spec.clone()), e.shape.clone())]
}

/// `w`: write the fill spec (and the shape it fills) for `solidtex fill`.
pub fn write(model: &mut Model) -> Vec<Effect> {
    let Screen::Fill(view) = &model.screen else { return Vec::new() };
    let Some(e) = &view.edit else { return Vec::new() };
    model.status = format!("writing the fill spec of {}", view.name);
    vec![Effect::WriteSpec(view.name.clone(), Box::new(e.spec.clone()), e.shape.clone())]
}

/// The model's size (the diagonal of its bounds), for the size of a new paste.
pub fn model_size(view: &FillView) -> f32 {
    view.filled.as_ref().map_or(1.0, |f| {
        let (lo, hi) = render::bounds(&[(&f.model, &f.textures)]);
        (hi - lo).length()
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::tui::model::{FillPreview, Item};
    use crate::tui::{Message, update};
    use std::path::PathBuf;
    use std::sync::Arc;

    /// A unit cube of marble, filled, its depth field x, on the fill preview's screen.
    pub fn filled_cube(depth: Option<Vec<f32>>) -> FillPreview {
        use crate::fill::render::Textures;
        let marble = crate::procedural::generate(crate::procedural::Recipe::Marble, [16; 3], 1).unwrap();
        let mask = crate::mask::splotch(16, 0.1, 1).unwrap();
        let mesh = crate::fill::tets::cube_lattice([4, 4, 4], 0.25);
        let patch = crate::fill::paste::Patch {
            source: 0,
            vertices: (0..mesh.vertices.len() as u32).collect(),
            coords: mesh.vertices.iter().map(|v| *v * 0.5 + 0.25).collect(),
        };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let sources = vec![crate::fill::Source {
            exemplar: "marble".into(),
            volume: "marble.exr".into(),
            mask: crate::fill::MaskRef::Splotch { size: 16, falloff: 0.1, seed: 1 },
        }];
        let depth = depth.map(|_| mesh.vertices.iter().map(|v| v.x).collect());
        let surface = crate::fill::LstModel::boundary_of(&mesh).unwrap();
        let model = crate::fill::LstModel::new(mesh, surface, sources, vec![patch], tet_patches);
        FillPreview {
            model,
            textures: Textures::new(&[marble], &[mask]),
            summary: "marble in a cube".into(),
            depth,
            spec: crate::fill::spec::FillSpec::new("marble"),
            shape: "block".into(),
            kind: crate::texture_type::TextureType::T0,
        }
    }

    pub fn filling(preview: FillPreview) -> Model {
        let item = Item {
            name: "marble".into(),
            declared: None,
            size: None,
            state: crate::tui::BuildState::Built("0".into()),
            quality: None,
            previous: false,
        };
        let mut m = Model::new(PathBuf::from("lib.toml"), PathBuf::from("out"), vec![item], Vec::new());
        m.screen = Screen::Fill(FillView {
            name: "marble".into(),
            filled: None,
            axis: crate::volume::Axis::Z,
            offset: 0.0,
            from: None,
            edit: None,
        });
        update(&mut m, Message::Filled("marble".into(), Ok(Arc::new(preview))));
        m
    }

    fn edit(m: &Model) -> &FillEdit {
        let Screen::Fill(FillView { edit: Some(e), .. }) = &m.screen else { panic!("the fill preview") };
        e
    }

    /// The overlay effect an update asked for, made at once as the runner makes it.
    fn make_overlay(m: &mut Model, effects: Vec<Effect>) -> OverlayKey {
        let Some(Effect::Overlay(name, filled, key)) = effects.into_iter().next() else { panic!("an overlay effect") };
        let view = plane_view(&filled.0, key.axis, key.offset, OVERLAY_SIZE);
        let made =
            crate::library::guided::picture(&filled.0, &key.spec, key.overlay, &view, &crate::progress::NoProgress);
        update(m, Message::OverlayMade(name, key.clone(), made.map(Arc::new).map_err(|e| e.to_string())));
        *key
    }

    fn shown(m: &Model) -> Option<Picture> {
        let Screen::Fill(view) = &m.screen else { panic!("the fill preview") };
        overlay_shown(view).cloned()
    }

    /// `v` shows the frame field of the strokes placed: along a stroke on x the cut is red
    /// (x); a new stroke across makes the field again (the old picture is not shown for the
    /// new spec). `v` again shows a cut synthesized along the field from the built
    /// exemplar; without a built exemplar it says why and turns the overlay off.
    #[test]
    fn the_field_follows_each_stroke_and_a_guided_cut_is_shown() {
        let dir = tempfile::tempdir().unwrap();
        let mut cube = filled_cube(None);
        // the cube made the drawn block's size, so the spec's strokes lie inside the block
        let model = &mut cube.model;
        for v in model.mesh.vertices.iter_mut().chain(&mut model.surface.vertices) {
            *v = (*v * 2.0 - Vec3::ONE) * Vec3::new(1.0, 0.5, 0.5);
        }
        cube.spec.built = dir.path().to_path_buf();
        let mut m = filling(cube);
        let stroke = |m: &mut Model, (right, down): (f32, f32)| {
            update(m, Message::StrokePoint);
            (0..8).for_each(|_| _ = update(m, Message::MoveCursor(right, down)));
            update(m, Message::StrokePoint);
            update(m, Message::FinishStroke)
        };
        (0..4).for_each(|_| _ = update(&mut m, Message::MoveCursor(-1.0, 0.0)));
        assert!(stroke(&mut m, (1.0, 0.0)).is_empty(), "no overlay asked for yet");
        let effects = update(&mut m, Message::NextOverlay);
        assert!(shown(&m).is_none());
        let key = make_overlay(&mut m, effects);
        assert_eq!(key.overlay, Overlay::Field);
        let along = shown(&m).expect("the field on the cut");
        let inside: Vec<[u8; 3]> = along.pixels.iter().flatten().copied().collect();
        let red = inside.iter().filter(|[r, g, b]| r > g && r > b).count();
        assert!(red * 10 > inside.len() * 8, "{red} of {} pixels show x as red", inside.len());

        (0..3).for_each(|_| _ = update(&mut m, Message::MoveCursor(0.0, -1.0)));
        let effects = stroke(&mut m, (0.0, 1.0));
        assert!(shown(&m).is_none(), "the picture of the old spec is not shown for the new one");
        assert_eq!(make_overlay(&mut m, effects).spec.directions.len(), 2);
        assert_ne!(shown(&m).expect("the new field").pixels, along.pixels, "the field follows the stroke");

        let effects = update(&mut m, Message::NextOverlay);
        make_overlay(&mut m, effects);
        assert!(edit(&m).overlay.is_none() && m.status.contains("no guided cut"), "{}", m.status);
        let marble = crate::procedural::generate(crate::procedural::Recipe::Marble, [32; 3], 1).unwrap();
        crate::io::write_volume(&crate::library::files::volume(dir.path(), "marble"), &marble).unwrap();
        update(&mut m, Message::NextOverlay);
        let effects = update(&mut m, Message::NextOverlay);
        assert_eq!(make_overlay(&mut m, effects).overlay, Overlay::Guided);
        let guided = shown(&m).expect("the guided cut");
        let greys: Vec<u8> = guided.pixels.iter().flatten().map(|p| p[0]).collect();
        let (lo, hi) = greys.iter().fold((255, 0), |(lo, hi), g| (lo.min(*g), hi.max(*g)));
        assert!(greys.len() > guided.pixels.len() / 4 && hi - lo > 40, "a textured cut: red {lo}..{hi}");
    }

    /// A built exemplar with a Depth channel (strata along z) and a spec with a depth axis
    /// give a layered guided cut: across the block's axis the strata lie at their depth,
    /// rings around the axis, so pixels at one distance from it are alike (most of the
    /// picture's variance lies between rings, not within them); the same strata without
    /// their Depth channel are not layered and show no rings.
    #[test]
    fn a_layered_exemplar_gives_a_layered_guided_cut() {
        let dir = tempfile::tempdir().unwrap();
        let mut cube = filled_cube(None);
        let model = &mut cube.model;
        for v in model.mesh.vertices.iter_mut().chain(&mut model.surface.vertices) {
            *v = (*v * 2.0 - Vec3::ONE) * Vec3::new(1.0, 0.5, 0.5);
        }
        let mut spec = cube.spec.clone();
        spec.built = dir.path().to_path_buf();
        spec.directions = vec![vec![Vec3::new(-0.8, 0.0, 0.0), Vec3::new(0.8, 0.0, 0.0)]];
        spec.depth.axes = vec![vec![Vec3::new(-0.9, 0.0, 0.0), Vec3::new(0.9, 0.0, 0.0)]];
        let strata = crate::procedural::generate(crate::procedural::Recipe::Strata, [48; 3], 1).unwrap();
        let path = crate::library::files::volume(dir.path(), "marble");
        let view = plane_view(&cube, crate::volume::Axis::X, 0.5, 96);
        // (the variance within rings of 2 pixels around the picture's centre, the whole
        // variance), over the pixels within 30 of it
        let rings = |volume: &crate::Volume| {
            crate::io::write_volume(&path, volume).unwrap();
            let picture =
                crate::library::guided::picture(&cube, &spec, Overlay::Guided, &view, &crate::progress::NoProgress)
                    .unwrap();
            let mut by_ring = vec![Vec::new(); 16];
            for (i, p) in picture.pixels.iter().enumerate() {
                let (dx, dy) = ((i % 96) as f32 - 47.5, (i / 96) as f32 - 47.5);
                let r = (dx * dx + dy * dy).sqrt();
                if let (Some(p), true) = (p, r < 30.0) {
                    by_ring[(r / 2.0) as usize].push(p.iter().map(|&c| f32::from(c)).sum::<f32>());
                }
            }
            let variance = |xs: &[f32]| {
                let mean = xs.iter().sum::<f32>() / xs.len().max(1) as f32;
                xs.iter().map(|x| (x - mean).powi(2)).sum::<f32>()
            };
            let all: Vec<f32> = by_ring.concat();
            (by_ring.iter().map(|r| variance(r)).sum::<f32>(), variance(&all))
        };
        let (within, whole) = rings(&strata);
        assert!(within < 0.5 * whole, "layered: {within} of {whole} within rings");
        let c = strata.channel_count();
        let rgb: Vec<f32> = strata.data().chunks_exact(c).flat_map(|px| px[..3].to_vec()).collect();
        let colours = crate::Volume::from_data([48; 3], crate::Channel::rgb(), rgb).unwrap();
        let (within, whole) = rings(&colours);
        assert!(within > 0.6 * whole, "not layered: {within} of {whole} within rings");
    }

    #[test]
    fn constraints_placed_on_the_cut_make_the_fill_spec() {
        let mut m = filling(filled_cube(None));
        let Screen::Fill(view) = &m.screen else { panic!("the fill preview") };
        let centre = cursor_point(view).unwrap();
        assert!((centre - Vec3::new(0.5, 0.5, 0.5)).length() < 0.02, "{centre}");
        // a stroke: two points, the second 8 cursor steps to the right
        assert!(update(&mut m, Message::FinishStroke).is_empty() && m.status.contains("needs two different points"));
        update(&mut m, Message::StrokePoint);
        (0..8).for_each(|_| _ = update(&mut m, Message::MoveCursor(1.0, 0.0)));
        update(&mut m, Message::StrokePoint);
        update(&mut m, Message::FinishStroke);
        let stroke = &edit(&m).spec.directions[0];
        assert!(
            stroke.len() == 2 && (stroke[1] - stroke[0]).x > 0.2 && (stroke[1] - stroke[0]).y.abs() < 1e-5,
            "{stroke:?}"
        );
        // depth points at the current depth, lowered with [
        update(&mut m, Message::DepthPoint);
        update(&mut m, Message::DepthValue(-DEPTH_STEP));
        update(&mut m, Message::FaceGroup);
        let depth = &edit(&m).spec.depth;
        assert_eq!((depth.points[0].1, depth.faces[0].value), (1.0, 0.75));
        // a paste at the cursor, turned about the cut's normal and scaled
        update(&mut m, Message::Paste);
        update(&mut m, Message::WarpPaste(15.0, 1.0));
        update(&mut m, Message::WarpPaste(0.0, 1.25));
        let paste = &edit(&m).spec.pastes[0];
        let (axis, angle) = paste.rotation.to_axis_angle();
        assert!((angle.to_degrees() - 15.0).abs() < 0.01 && axis.z > 0.99, "{axis} {angle}");
        let first = model_size_of(&m) / 4.0;
        assert!((paste.scale - first * 1.25).abs() < 1e-5, "{} {first}", paste.scale);
        update(&mut m, Message::Undo);
        assert!((edit(&m).spec.pastes[0].scale - first).abs() < 1e-5, "undo takes the last change back");
        // r refills with the spec, w writes it
        let spec = edit(&m).spec.clone();
        assert_eq!(
            update(&mut m, Message::Refill),
            vec![Effect::Refill("marble".into(), Box::new(spec.clone()), "block".into())]
        );
        assert!(update(&mut m, Message::Refill).is_empty(), "one refill at a time");
        // a refill that fails (a point outside the shape) keeps the fill and the constraints
        update(&mut m, Message::Filled("marble".into(), Err("depth.points[0] lies outside the mesh".into())));
        assert!(matches!(m.screen, Screen::Fill(FillView { filled: Some(_), .. })), "{}", m.status);
        assert!(m.status.contains("outside the mesh") && m.status.contains("u undoes"), "{}", m.status);
        assert_eq!(edit(&m).spec.pastes.len(), 1);
        assert!(!update(&mut m, Message::Refill).is_empty(), "a new refill may start");
        update(&mut m, Message::Filled("marble".into(), Ok(Arc::new(filled_cube(None)))));
        assert_eq!(
            update(&mut m, Message::WriteSpec),
            vec![Effect::WriteSpec("marble".into(), Box::new(spec), "block".into())]
        );
        // no depth field: c says so
        update(&mut m, Message::Filled("marble".into(), Ok(Arc::new(filled_cube(None)))));
        update(&mut m, Message::ShowDepth);
        assert!(m.status.contains("no depth field") && !edit(&m).show_depth, "{}", m.status);
    }

    fn model_size_of(m: &Model) -> f32 {
        let Screen::Fill(view) = &m.screen else { panic!("the fill preview") };
        model_size(view)
    }

    /// A drag on the cut draws a stroke through the points it passes; letting go ends it.
    #[test]
    fn a_drag_draws_a_stroke() {
        let mut m = filling(filled_cube(None));
        update(&mut m, Message::CursorAt(0.2, 0.5));
        for x in [0.21, 0.3, 0.4, 0.5] {
            update(&mut m, Message::DragStroke(x, 0.5));
        }
        assert_eq!(edit(&m).stroke.len(), 4, "the start, then every cursor step: 0.21 is too close");
        update(&mut m, Message::EndDrag);
        let e = edit(&m);
        assert!(e.stroke.is_empty() && e.spec.directions.len() == 1 && e.spec.directions[0].len() == 4);
        update(&mut m, Message::EndDrag);
        assert_eq!(edit(&m).spec.directions.len(), 1, "a lone button release adds nothing");
    }
    /// With a depth point placed, q, esc and ctrl-c (quit) ask before the constraints go; a
    /// type-0 fill says it ignores the point; once written the preview leaves at once, and
    /// a written spec's constraints load back (u gives the old ones back).
    #[test]
    fn placed_constraints_are_guarded_and_a_written_spec_loads_back() {
        let mut m = filling(filled_cube(None));
        update(&mut m, Message::DepthPoint);
        assert!(m.status.contains("[depth] is not used by type 0"), "{}", m.status);
        update(&mut m, Message::Quit);
        assert!(!m.quit && m.status.contains("unsaved fill constraints: w writes them"), "{}", m.status);
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Fill(_)) && m.status.contains("esc again leaves"), "{}", m.status);
        let spec = edit(&m).spec.clone();
        assert!(matches!(update(&mut m, Message::WriteSpec).as_slice(), [Effect::WriteSpec(..)]));
        update(&mut m, Message::SpecWritten(Box::new(spec.clone()), Ok(("out/exports".into(), vec![], vec![]))));
        update(&mut m, Message::Undo);
        assert!(edit(&m).spec.depth.points.is_empty());
        let folder = PathBuf::from("out/exports");
        assert_eq!(
            update(&mut m, Message::OpenSpec),
            vec![Effect::List(folder, crate::tui::new_entry::FileKind::FillSpec)]
        );
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Fill(_)) && m.status.contains("no fill spec loaded"), "{}", m.status);
        let path = PathBuf::from("out/exports/marble.fill.toml");
        update(&mut m, Message::SpecLoaded(path, Ok(Box::new(spec.clone()))));
        assert_eq!(edit(&m).spec.depth.points, spec.depth.points);
        assert!(m.status.contains("loaded 0 stroke(s), 1 depth point(s)"), "{}", m.status);
        update(&mut m, Message::Quit);
        assert!(m.quit, "the loaded constraints are saved in that file: q quits at once");
    }
}
