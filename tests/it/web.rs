//! `solidtex web`: pages that a real browser (Debian's chromium, software WebGL, driven by
//! tests/web/check.js) opens without errors, whose slices and cuts drawn one pixel per voxel
//! are `solidtex slice` of the volume and of `solidtex bake`, and whose views answer drags
//! and the wheel.

use crate::fill::{draw, fill, spec};
use crate::support::{assert_usage, at, solidtex, stderr};
use base64::Engine;
use serde_json::{Value, json};
use std::path::Path;
use std::process::Command;

/// The browser checks of tests/web/check.js on `page` with `plan`'s other fields; `None`
/// when the browser or puppeteer-core is missing outside CI (under CI that fails).
fn opened(page: &str, mut plan: Value) -> Option<Value> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/web");
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !folder.join("node_modules/puppeteer-core").exists() || !Path::new(&chromium).exists() {
        assert!(std::env::var_os("CI").is_none(), "chromium or puppeteer-core is missing (.ci/run installs them)");
        eprintln!("skipping the browser checks (needs {chromium} and npm ci --prefix tests/web)");
        return None;
    }
    plan["page"] = json!(page);
    let plan_file = format!("{page}.plan.json");
    std::fs::write(&plan_file, plan.to_string()).unwrap();
    let run = Command::new("node").arg(folder.join("check.js")).arg(&plan_file).output().expect("node runs");
    assert!(run.status.success(), "check.js failed:\n{}", String::from_utf8_lossy(&run.stderr));
    let report: Value = serde_json::from_slice(&run.stdout).expect("check.js prints JSON");
    assert_eq!(report["failure"], Value::Null, "the page failed: {report}");
    assert_eq!(report["console_errors"], json!([]), "console errors");
    assert_eq!(report["page_errors"], json!([]), "page errors");
    assert_eq!(report["gl_error"], 0, "gl.getError() after the first frame");
    assert_eq!(report["gl_error_at_end"], 0, "gl.getError() after the checks");
    eprintln!("{page}: first frame at {} ms, {} frames/s", report["first_frame_ms"], report["fps"]);
    Some(report)
}

/// Mean absolute difference (0 to 255) between a snapshot and a PNG of the same size.
fn difference(snapshot: &Value, png: &str) -> f64 {
    let rgb = base64::engine::general_purpose::STANDARD.decode(snapshot["rgb"].as_str().unwrap()).unwrap();
    let want = image::open(png).unwrap().to_rgb8();
    assert_eq!(
        (snapshot["width"].as_u64().unwrap(), snapshot["height"].as_u64().unwrap()),
        (want.width() as u64, want.height() as u64),
        "{png}"
    );
    let total: f64 = rgb.iter().zip(want.as_raw()).map(|(a, b)| (*a as f64 - *b as f64).abs()).sum();
    total / rgb.len() as f64
}

/// Every snapshot of `report` against `solidtex slice` of `volume` at the same place.
fn snapshots_match(report: &Value, volume: &str, dir: &Path) {
    for shot in report["snapshots"].as_array().unwrap() {
        let (axis, index) = (shot["axis"].as_u64().unwrap() as usize, shot["index"].as_u64().unwrap());
        let png = at(dir, &format!("slice_{axis}_{index}.png"));
        let run =
            solidtex(&["slice", volume, "--axis", ["x", "y", "z"][axis], "--index", &index.to_string(), "-o", &png]);
        assert!(run.status.success(), "{}", stderr(&run));
        let off = difference(shot, &png);
        assert!(off <= 3.0, "slice {axis} at {index}: the page differs by {off:.2}/255 on average");
    }
}

/// The interaction's steps: a drag on the handle moved it about five voxels, a drag on the
/// background orbited, the wheel zoomed out, shift-drag panned; each changed the picture.
fn interaction_answers(report: &Value, axis: usize) {
    let steps = &report["interaction"];
    let state = |step: &str| &steps[step]["state"];
    let hash = |step: &str| steps[step]["picture"]["hash"].as_u64().unwrap();
    assert!(steps["handle"].is_object(), "no visible handle for axis {axis}: {steps}");
    let moved = state("slice")["slices"][axis].as_i64().unwrap() - state("start")["slices"][axis].as_i64().unwrap();
    assert!((3..=6).contains(&moved), "a drag of five voxels moved the slice by {moved}");
    let camera = |step: &str, key: &str| state(step)["camera"][key].clone();
    assert_ne!(camera("orbit", "yaw"), camera("slice", "yaw"), "a drag on the background orbits");
    assert!(camera("wheel", "dist").as_f64() > camera("orbit", "dist").as_f64(), "the wheel zooms out");
    assert_ne!(camera("pan", "target"), camera("wheel", "target"), "shift-drag pans");
    for (before, after) in [("start", "slice"), ("slice", "orbit"), ("orbit", "wheel"), ("wheel", "pan")] {
        assert_ne!(hash(before), hash(after), "the picture after {after} is the one before");
    }
}

fn page_size(page: &str) -> u64 {
    std::fs::metadata(page).unwrap().len()
}

#[test]
fn a_volume_page_draws_the_slices_of_solidtex_slice_and_answers_the_mouse() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let volume = at(d, "wood.exr");
    assert!(solidtex(&["make", "wood", "--size", "64", "-o", &volume]).status.success());
    let page = at(d, "wood.html");
    let run = solidtex(&["web", &volume, "-o", &page]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(page_size(&page) <= 2_000_000, "a 64³ exemplar's page is {} bytes", page_size(&page));
    // --res and --max-mb set a bake of filled models: a volume's page refuses them
    let other = at(d, "other.html");
    assert_usage(&solidtex(&["web", &volume, "--res", "64", "-o", &other]), &["--res", "filled models"]);
    assert!(!Path::new(&other).exists());
    let plan = json!({ "snapshots": [[0, 0], [0, 40], [1, 63], [2, 17]], "drag": 2, "fps": 20 });
    let Some(report) = opened(&page, plan) else { return };
    snapshots_match(&report, &volume, d);
    interaction_answers(&report, 2);
}

#[test]
fn a_model_page_cuts_as_bake_does_and_its_cut_can_be_dragged() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fruit = draw(d, "fruit");
    let kiwi = spec(
        d,
        "kiwi.toml",
        "exemplar = \"kiwi\"\nseed = 3\ntets = 5000\n[depth]\naxis = [[[-0.75, 0, 0], [0.75, 0, 0]]]\n[[direction]]\npoints = [[-0.75, 0, 0], [0.75, 0, 0]]\n",
    );
    fill(d, &fruit, &kiwi, "kiwi.lst");
    let (model, page, baked) = (at(d, "kiwi.lst"), at(d, "kiwi.html"), at(d, "kiwi.exr"));
    let run = solidtex(&["web", &model, "-o", &page]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(page_size(&page) <= 8_000_000, "a 5k-tet kiwi's page is {} bytes", page_size(&page));
    assert!(solidtex(&["bake", &model, "--res", "128", "-o", &baked]).status.success());
    let plan = json!({ "keys": ["z"], "snapshots": [[2, 40], [0, 64], [1, 30]], "drag": 2, "fps": 20 });
    let Some(report) = opened(&page, plan) else { return };
    snapshots_match(&report, &baked, d);
    interaction_answers(&report, 2);
    assert_eq!(report["interaction"]["start"]["state"]["cut"], "plane", "the key z shows the plane across z");
    // o: an oblique cut facing the camera, dragged towards it
    let Some(report) = opened(&page, json!({ "keys": ["o"], "drag": "o" })) else { return };
    let steps = &report["interaction"];
    assert_eq!(steps["start"]["state"]["cut"], "oblique");
    let shift = |step: &str| steps[step]["state"]["shift"].as_i64().unwrap();
    assert!((3..=6).contains(&(shift("slice") - shift("start"))), "{steps}");
    assert_ne!(steps["start"]["picture"]["hash"], steps["slice"]["picture"]["hash"]);
}

#[test]
fn a_skin_page_draws_the_skin() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fruit = draw(d, "fruit");
    let (skin, page) = (at(d, "skin.ply"), at(d, "skin.html"));
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    assert!(solidtex(&["surface", &fruit, "--exemplar", photo, "--points", "2000", "-o", &skin]).status.success());
    let run = solidtex(&["web", &skin, "-o", &page]);
    assert!(run.status.success(), "{}", stderr(&run));
    let plan = json!({ "drag": null, "fps": 10 });
    let Some(report) = opened(&page, plan) else { return };
    // The background alone has a mean of (24 + 24 + 28 + 255) / 4 = 82.75.
    let mean = report["picture"]["mean"].as_f64().unwrap();
    assert!((mean - 82.75).abs() > 2.0, "the skin is not drawn: the canvas mean is {mean}");
}

#[test]
fn bad_input_to_web_is_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (volume, big, page) = (at(d, "v.exr"), at(d, "big.exr"), at(d, "v.html"));
    assert!(solidtex(&["make", "marble", "--size", "8", "-o", &volume]).status.success());
    assert!(solidtex(&["make", "marble", "--size", "257x2x2", "-o", &big]).status.success());
    let fruit = draw(d, "fruit");
    assert_usage(&solidtex(&["web", &volume, &fruit.replace(".obj", ".lst"), "-o", &page]), &["not a mix"]);
    let run = solidtex(&["web", &big, "-o", &at(d, "big.html")]);
    assert!(
        run.status.success() && stderr(&run).contains("one voxel in 2 along each axis (129x1x1)"),
        "{}",
        stderr(&run)
    );
    assert_usage(&solidtex(&["web", &volume, "--res", "8", "-o", &page]), &["--res", "16"]);
    assert_usage(&solidtex(&["web", &volume, "-o", &at(d, "v.png")]), &["v.png", "html"]);
    let before = std::fs::read(&volume).unwrap();
    assert_usage(&solidtex(&["web", &volume, "-o", &volume]), &["v.exr"]);
    assert_eq!(std::fs::read(&volume).unwrap(), before, "an input is never overwritten");
    assert!(!Path::new(&page).exists(), "nothing is written on bad input");
}

#[test]
fn a_library_build_writes_a_3d_view_of_each_exemplar_that_its_report_opens() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let manifest = at(d, "lib.toml");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 32\n").unwrap();
    let out = d.join("out");
    let run = solidtex(&["build", &manifest, "-o", &out.to_string_lossy()]);
    assert!(run.status.success(), "{}", stderr(&run));
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("<details data-view=\"m.view.html\">"), "{report}");
    let markdown = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(markdown.contains("[3D view](m.view.html)"), "{markdown}");
    let page = out.join("m.view.html").to_string_lossy().into_owned();
    let Some(shown) = opened(&page, json!({ "snapshots": [[2, 5], [0, 31]] })) else { return };
    snapshots_match(&shown, &out.join("m.exr").to_string_lossy(), d);
    let report = out.join("report.html").to_string_lossy().into_owned();
    opened(&report, json!({ "report": true }));
}
