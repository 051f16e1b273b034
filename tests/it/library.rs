//! The library build: caching, partial failure, reports.

use crate::support::{at, solidtex, stderr};
use std::path::Path;

/// A small library: two procedural entries and one sweep reading `section.png`.
fn library(dir: &Path) -> String {
    let section = at(dir, "section.png");
    assert!(solidtex(&["draw", "carrot", "--size", "16x16", "-o", &section]).status.success());
    let manifest = dir.join("lib.toml");
    std::fs::write(
        &manifest,
        "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 12\nseed = 1\n\
         [[exemplar]]\nname = \"b\"\nrecipe = \"procedural:strata\"\nsize = 12\n\
         [[exemplar]]\nname = \"c\"\nrecipe = \"sweep\"\nimage = \"section.png\"\nlength = 12\naxis = \"x\"\ndepth_axis = \"z\"\n",
    )
    .unwrap();
    manifest.to_string_lossy().into_owned()
}

#[test]
fn a_second_build_rebuilds_nothing_and_a_touched_input_rebuilds_only_its_exemplar() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let out = at(dir.path(), "out");
    let first = solidtex(&["build", &manifest, "-o", &out]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(stderr(&first).contains("3 built, 0 cached"), "{}", stderr(&first));
    let c_before = std::fs::read(dir.path().join("out/c.exr")).unwrap();
    let second = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&second).contains("0 built, 3 cached"), "{}", stderr(&second));
    assert!(
        solidtex(&["draw", "carrot", "--size", "16x16", "--seed", "2", "-o", &at(dir.path(), "section.png")])
            .status
            .success()
    );
    let third = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&third).contains("1 built, 2 cached") && stderr(&third).contains("built  c "), "{}", stderr(&third));
    assert_ne!(std::fs::read(dir.path().join("out/c.exr")).unwrap(), c_before);
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text += "[[exemplar]]\nname = \"e\"\nrecipe = \"load\"\nvolume = \"out/a.exr\"\nexports = [\"nrrd\", \"vdb\"]\n";
    std::fs::write(&manifest, text).unwrap();
    let loaded = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&loaded).contains("1 built, 3 cached"), "{}", stderr(&loaded));
    let a = solidtex::io::read_volume(&dir.path().join("out/a.exr"), u64::MAX).unwrap();
    for export in ["e.nrrd", "e.vdb"] {
        let copy = solidtex::io::read_volume(&dir.path().join("out").join(export), u64::MAX).unwrap();
        assert_eq!(copy.data(), a.data(), "{export} holds the loaded volume");
    }
    let forced = solidtex(&["build", &manifest, "-o", &out, "--force", "--only", "a"]);
    assert!(stderr(&forced).contains("1 built, 0 cached"), "{}", stderr(&forced));
    let report = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
    assert!(report.contains("| a | 12x12x12 | 0 |"), "{report}");
    // a build of one entry keeps every other row, marked as an earlier build
    for row in ["| b | ", "| c | ", "| e | "] {
        assert!(report.lines().any(|l| l.starts_with(row) && l.contains("earlier build")), "{row} {report}");
    }
    assert!(std::fs::read_to_string(dir.path().join("out/report.html")).unwrap().contains("<img src=\"a.sheet.png\""));
}

#[test]
fn a_failing_exemplar_does_not_stop_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    std::fs::remove_file(dir.path().join("section.png")).unwrap();
    let out = at(dir.path(), "out");
    let run = solidtex(&["build", &manifest, "-o", &out]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("FAILED c:") && err.contains("section.png"), "{err}");
    assert!(err.contains("2 built, 0 cached, 1 failed"), "{err}");
    assert!(err.contains("error: 1 exemplar(s) failed: c"), "{err}");
    assert!(dir.path().join("out/a.exr").exists() && dir.path().join("out/b.exr").exists());
    assert!(!dir.path().join("out/c.exr").exists());
    let unknown = solidtex(&["build", &manifest, "-o", &out, "--only", "zz"]);
    assert!(stderr(&unknown).contains("--only \"zz\" is not in the manifest; it has a, b, c"), "{}", stderr(&unknown));
}

/// An entry that reads what it writes itself fails without touching it: otherwise each
/// build would blur the blurred volume again and replace its input.
#[test]
fn an_entry_reading_its_own_output_is_refused_and_the_file_kept() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let manifest = at(d, "lib.toml");
    let out = at(d, "out");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"z\"\nrecipe = \"procedural:marble\"\nsize = 8\n").unwrap();
    assert!(solidtex(&["build", &manifest, "-o", &out]).status.success());
    let before = std::fs::read(d.join("out/z.exr")).unwrap();
    let blurred = "[[exemplar]]\nname = \"z\"\nrecipe = \"load\"\nvolume = \"out/z.exr\"\n\n  [[exemplar.steps]]\n  \
                   blur = \"4,4,4\"\n  radius = 4\n  strength = 1\n";
    std::fs::write(&manifest, blurred).unwrap();
    for _ in 0..2 {
        let run = solidtex(&["build", &manifest, "-o", &out]);
        let err = stderr(&run);
        assert_eq!(run.status.code(), Some(1), "{err}");
        assert!(
            err.contains("volume = \"")
                && err.contains("is a file this entry writes")
                && err.contains("outside the output folder"),
            "{err}"
        );
        assert_eq!(std::fs::read(d.join("out/z.exr")).unwrap(), before, "the input is kept");
    }
}

/// A folder output holding a person's file fails its entry before the entry writes
/// anything: the volume of the earlier build stays as it was.
#[test]
fn a_folder_output_holding_a_users_file_fails_its_entry_before_any_file_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (manifest, out) = (at(d, "lib.toml"), at(d, "out"));
    let entry = |seed: u32| {
        format!(
            "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = {seed}\nexports = [\"slices\"]\n"
        )
    };
    std::fs::write(&manifest, entry(1)).unwrap();
    assert!(solidtex(&["build", &manifest, "-o", &out]).status.success());
    let before = std::fs::read(d.join("out/a.exr")).unwrap();
    std::fs::write(d.join("out/a_slices/notes.txt"), "mine").unwrap();
    std::fs::write(&manifest, entry(2)).unwrap();
    let run = solidtex(&["build", &manifest, "-o", &out]);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("a_slices") && err.contains("notes.txt"), "{err}");
    assert_eq!(std::fs::read(d.join("out/a.exr")).unwrap(), before, "nothing of the entry was written");
    assert_eq!(std::fs::read_to_string(d.join("out/a_slices/notes.txt")).unwrap(), "mine");
}

#[test]
fn three_shards_merged_equal_one_build() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let single = at(dir.path(), "single");
    assert!(solidtex(&["build", &manifest, "-o", &single]).status.success());
    let mut shards = Vec::new();
    let mut built = 0;
    for k in 0..3 {
        let out = at(dir.path(), &format!("shard{k}"));
        let run = solidtex(&["build", &manifest, "-o", &out, "--shard", &format!("{k}/3")]);
        assert!(run.status.success(), "{}", stderr(&run));
        built += stderr(&run).matches("built  ").count();
        shards.push(out);
    }
    assert_eq!(built, 3, "every exemplar is built by exactly one shard");
    let merged = at(dir.path(), "merged");
    let mut args = vec!["build", &manifest, "-o", &merged, "--merge"];
    args.extend(shards.iter().map(String::as_str));
    let run = solidtex(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    for name in ["a", "b", "c"] {
        for ext in ["exr", "sheet.png"] {
            let file = format!("{name}.{ext}");
            assert_eq!(
                std::fs::read(dir.path().join("single").join(&file)).unwrap(),
                std::fs::read(dir.path().join("merged").join(&file)).unwrap(),
                "{file}"
            );
        }
    }
    let rows = |folder: &str| -> Vec<String> {
        let text = std::fs::read_to_string(dir.path().join(folder).join("report.md")).unwrap();
        text.lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| exemplar"))
            .map(|l| l.split(" | ").take(4).collect::<Vec<_>>().join("|"))
            .collect()
    };
    assert_eq!(rows("single"), rows("merged"));
    // a merge missing shards names what is missing and why, line by line
    let partial = solidtex(&["build", &manifest, "-o", &at(dir.path(), "partial"), "--merge", &shards[0]]);
    assert_eq!(partial.status.code(), Some(1), "{}", stderr(&partial));
    let err = stderr(&partial);
    let failed = err.matches("FAILED ").count();
    assert!(failed >= 1 && err.matches("built by none of the merged folders").count() == failed, "{err}");
    assert!(err.contains(&format!("{failed} failed")), "{err}");
    // a shard's build of an entry the manifest changed since, or missing one of its files, is
    // not merged as up to date: that entry fails, saying why, and none of its files is copied
    let shard_of = |name: &str| shards.iter().find(|s| Path::new(s).join(format!("{name}.exr")).exists()).unwrap();
    std::fs::remove_file(Path::new(shard_of("b")).join("b.view.html")).unwrap();
    let text = std::fs::read_to_string(&manifest).unwrap();
    std::fs::write(&manifest, text.replacen("seed = 1", "seed = 4", 1)).unwrap();
    let stale = at(dir.path(), "stale");
    let mut args = vec!["build", &manifest, "-o", &stale, "--merge"];
    args.extend(shards.iter().map(String::as_str));
    let run = solidtex(&args);
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("FAILED a") && err.contains("out of date (the recipe changed)"), "{err}");
    assert!(err.contains("FAILED b") && err.contains("b.view.html"), "{err}");
    for file in ["a.exr", "b.exr", "b.sheet.png"] {
        assert!(!dir.path().join("stale").join(file).exists(), "{file} copied");
    }
    assert!(dir.path().join("stale/c.exr").is_file(), "the entry up to date is merged");
}

#[test]
fn shard_arguments_are_checked_and_taken_from_the_scheduler() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let out = at(dir.path(), "out");
    crate::support::assert_usage(
        &solidtex(&["build", &manifest, "-o", &out, "--shard", "3/3"]),
        &["--shard \"3/3\"", "0 <= K < N"],
    );
    crate::support::assert_usage(
        &solidtex(&["build", &manifest, "-o", &out, "--shard", "auto/2"]),
        &["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"],
    );
    crate::support::assert_usage(
        &crate::support::solidtex_env(
            &["build", &manifest, "-o", &out, "--shard", "auto/2"],
            &[("JOB_COMPLETION_INDEX", "7")],
        ),
        &["JOB_COMPLETION_INDEX=7", "below N = 2"],
    );
    assert!(!Path::new(&out).exists(), "nothing built");
    // a file as the output folder is refused by name, and left as it is
    let file = at(dir.path(), "section.png");
    let before = std::fs::read(&file).unwrap();
    let run = solidtex(&["build", &manifest, "-o", &file]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains("section.png: is a file, not a folder"), "{}", stderr(&run));
    assert_eq!(std::fs::read(&file).unwrap(), before);
    let run = crate::support::solidtex_env(
        &["build", &manifest, "-o", &out, "--shard", "auto/2"],
        &[("SLURM_ARRAY_TASK_ID", "1")],
    );
    assert!(run.status.success() && stderr(&run).contains("shard 1 of 2"), "{}", stderr(&run));
}

#[test]
fn each_invalid_manifest_gets_its_own_clear_message() {
    let cases = [
        ("unknown-recipe.toml", vec!["line 2: entry 1 (a)", "recipe = \"weave\"", "allowed", "procedural:channels"]),
        ("unknown-mask.toml", vec!["line 2: entry 1 (a)", "masks: \"blob\"", "allowed: splotch, layered"]),
        ("unknown-step.toml", vec!["unknown field `smudge`", "line"]),
        ("wrong-type.toml", vec!["entry 1 (a)", "type", "\"3-a\"", "allowed: 0, 1-a"]),
        ("size-out-of-range.toml", vec!["size = 4096 is out of range", "1..=512"]),
        ("missing-input.toml", vec!["FAILED a: ", "line 5, field \"image\": ", "no-such-image.png"]),
        ("duplicate-id.toml", vec!["line 6: entry 2: name = \"a\" is used twice"]),
        ("bad-size.toml", vec!["size = [8, 8]", "one whole number or three, each 1 to 512"]),
        ("wrong-value-type.toml", vec!["size", "line 5"]),
        ("layered-with-ey.toml", vec!["line 6: ey does not apply to recipe \"synth-layered\""]),
    ];
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/manifests/invalid");
    let dir = tempfile::tempdir().unwrap();
    for (k, (file, needles)) in cases.into_iter().enumerate() {
        let out = at(dir.path(), &format!("out{k}"));
        let run = solidtex(&["build", &folder.join(file).to_string_lossy(), "-o", &out]);
        assert_eq!(run.status.code(), Some(1), "{file}");
        let err = stderr(&run);
        assert!(err.contains(file), "the message names the manifest {file}: {err}");
        for n in needles {
            assert!(err.contains(n), "{file}: {n:?} not in {err}");
        }
    }
}

/// An entry's input files are found wanting only when it is built: a misspelt image, a
/// mesh given where an image goes, an image whose sweep does not make the size asked for,
/// a missing seed mesh of a step. Each failure names the manifest, the line of the field
/// that names the file (or states the size), the field, and the file.
#[test]
fn an_input_file_error_names_the_manifest_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert!(solidtex(&["draw", "carrot", "--size", "16x16", "-o", &at(d, "section.png")]).status.success());
    assert!(solidtex(&["draw", "seed", "-o", &at(d, "seed.obj")]).status.success());
    let sweep = "recipe = \"sweep\"\nlength = 8\naxis = \"x\"\n";
    let text = format!(
        "# input files that fail only at build time\n\
         [[exemplar]]\nname = \"typo\"\n{sweep}image = \"sectoin.png\"\n\n\
         [[exemplar]]\nname = \"mesh\"\n{sweep}image = \"seed.obj\"\n\n\
         [[exemplar]]\nname = \"sized\"\n{sweep}size = [8, 16, 9]\nimage = \"section.png\"\n\n\
         [[exemplar]]\nname = \"stamped\"\nrecipe = \"procedural:marble\"\nsize = 8\n\
         [[exemplar.steps]]\nblur = \"4,4,4\"\nradius = 2\nstrength = 0.5\n\
         [[exemplar.steps]]\nstamp = \"sede.obj\"\nat = \"4,4,4\"\ncolor = \"#000000\"\n"
    );
    let manifest = d.join("lib.toml");
    std::fs::write(&manifest, &text).unwrap();
    let line = |needle: &str| text.lines().position(|l| l.starts_with(needle)).unwrap() + 1;
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &at(d, "out")]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    let failed = |name: &str| {
        let prefix = format!("FAILED {name}: ");
        err.lines()
            .find_map(|l| l.strip_prefix(&prefix))
            .unwrap_or_else(|| panic!("no {prefix:?} in {err}"))
            .to_string()
    };
    let starts = |name: &str, field: &str, at: usize| {
        let said = failed(name);
        let want = format!("{}: line {at}, {field}: ", manifest.display());
        assert!(said.starts_with(&want), "{name}: {said:?} does not start with {want:?}");
        said
    };
    let typo = starts("typo", "field \"image\"", line("image = \"sectoin.png\""));
    assert!(typo.contains("sectoin.png") && typo.contains("No such file"), "{typo}");
    let mesh = starts("mesh", "field \"image\"", line("image = \"seed.obj\""));
    assert!(mesh.contains("seed.obj") && mesh.contains("cannot decode image"), "{mesh}");
    let sized = starts("sized", "field \"size\"", line("size = [8, 16, 9]"));
    assert!(sized.contains("section.png") && sized.contains("not the size [8, 16, 9]"), "{sized}");
    let stamped = starts("stamped", "step 2, field \"stamp\"", line("stamp = \"sede.obj\""));
    assert!(stamped.contains("sede.obj"), "{stamped}");
}

#[test]
fn an_interrupted_build_resumes_and_ends_identical() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text += "[[exemplar]]\nname = \"d\"\nrecipe = \"synth\"\nimage = \"section.png\"\nsize = 24\nlevels = 1\nmasks = [\"splotch\", \"layered\"]\nexports = [\"nrrd\", \"slices\"]\n";
    std::fs::write(&manifest, text).unwrap();
    let clean = at(dir.path(), "clean");
    assert!(solidtex(&["build", &manifest, "-o", &clean]).status.success());
    let resumed = at(dir.path(), "resumed");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(["build", &manifest, "-o", &resumed])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(150));
    let _ = child.kill();
    let _ = child.wait();
    let run = solidtex(&["build", &manifest, "-o", &resumed]);
    assert!(run.status.success(), "{}", stderr(&run));
    let files = |folder: &str| -> Vec<(String, Vec<u8>)> {
        let mut out = Vec::new();
        let mut stack = vec![dir.path().join(folder)];
        while let Some(f) = stack.pop() {
            for e in std::fs::read_dir(&f).unwrap() {
                let p = e.unwrap().path();
                let rel = p.strip_prefix(dir.path().join(folder)).unwrap().to_string_lossy().into_owned();
                if p.is_dir() {
                    stack.push(p);
                } else if !rel.ends_with(".json") && !rel.starts_with("report") && rel != ".cache/written.txt" {
                    // records, reports and the ledger of written files hold build times
                    out.push((rel, std::fs::read(&p).unwrap()));
                }
            }
        }
        out.sort();
        out
    };
    let (a, b) = (files("clean"), files("resumed"));
    assert_eq!(a.iter().map(|f| &f.0).collect::<Vec<_>>(), b.iter().map(|f| &f.0).collect::<Vec<_>>());
    assert!(a == b, "a resumed build differs from a clean one");
    assert!(!a.iter().any(|f| f.0.ends_with(".tmp")), "no temporaries are left");
}

/// What an in-process build tells its observer.
#[derive(Default)]
struct Heard {
    stages: std::sync::Mutex<Vec<String>>,
    levels: std::sync::Mutex<Vec<(usize, usize, [usize; 3])>>,
    finished: std::sync::Mutex<Vec<String>>,
}

impl solidtex::library::Observer for Heard {
    fn progress(&self, name: &str, stage: &str, _fraction: f32) {
        self.stages.lock().unwrap().push(format!("{name}: {stage}"));
    }
    fn level_done(&self, _: &str, level: usize, levels: usize, dims: [usize; 3], _: usize, _: &[f32]) {
        self.levels.lock().unwrap().push((level, levels, dims));
    }
    fn finished(&self, outcome: &solidtex::library::Outcome) {
        self.finished.lock().unwrap().push(outcome.name().to_string());
    }
}

/// Both front ends build in-process: the observer hears each synthesis level (with the
/// level's volume, for a preview) and each finished entry.
#[test]
fn an_in_process_build_reports_each_synthesis_level() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let image =
        image::RgbImage::from_fn(24, 24, |x, y| image::Rgb([(x * 10) as u8, (y * 10) as u8, ((x ^ y) * 8) as u8]));
    image.save(d.join("ex.png")).unwrap();
    let manifest = d.join("lib.toml");
    std::fs::write(
        &manifest,
        "[[exemplar]]\nname = \"s\"\nrecipe = \"synth\"\nimage = \"ex.png\"\nsize = 16\nlevels = 2\n",
    )
    .unwrap();
    let request =
        solidtex::library::Request { manifest, output: d.join("out"), force: false, only: Vec::new(), shard: None };
    let entries = solidtex::library::build::select(&request).unwrap();
    let heard = Heard::default();
    let outcomes = solidtex::library::build::build(&request, &entries, &heard).unwrap();
    assert!(matches!(outcomes[..], [solidtex::library::Outcome::Built(_)]), "{outcomes:?}");
    let stages = heard.stages.lock().unwrap();
    assert!(stages.iter().any(|s| s.starts_with("s: level 2/2")), "{stages:?}");
    assert_eq!(*heard.levels.lock().unwrap(), [(1, 2, [8; 3]), (2, 2, [16; 3])]);
    assert_eq!(*heard.finished.lock().unwrap(), ["s"]);
}

/// The editor's preview hands its build's warnings back instead of printing them (printed,
/// they land over the terminal UI): 2000 kiwi seeds do not all find room.
#[test]
fn a_preview_returns_its_warnings() {
    let manifest = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/library.toml"));
    let text = std::fs::read_to_string(manifest).unwrap().replace("count = 180", "count = 2000");
    let (_, warnings) = solidtex::library::recipe::preview(manifest, "kiwi", &text).unwrap();
    assert!(warnings.iter().any(|w| w.contains("seeds") && w.contains("no room")), "{warnings:?}");
}

/// An entry with steps previews at its full size: a stamp at x = 40 lands inside the volume
/// (a preview capped at 32 voxels refused it as outside).
#[test]
fn a_preview_keeps_stamps_beyond_its_cap() {
    let manifest = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/library.toml"));
    let original = std::fs::read_to_string(manifest).unwrap();
    let step =
        "\n[[exemplar.steps]]\nstamp = \"kiwi_seed.obj\"\nat = \"40,32,32\"\nscale = \"8\"\ncolor = \"#000000\"\n";
    let at = original.find("\n[[exemplar]]\nname = \"carrot\"").expect("the carrot follows the kiwi");
    let text = format!("{}{step}{}", &original[..at], &original[at..]);
    let (before, _) = solidtex::library::recipe::preview(manifest, "kiwi", &original).unwrap();
    let (after, _) = solidtex::library::recipe::preview(manifest, "kiwi", &text).unwrap();
    assert_eq!(after.dims(), before.dims());
    let black = |v: &[f32]| v[..3].iter().all(|c| *c < 0.01);
    let stamped = (30..50)
        .flat_map(|x| (22..42).flat_map(move |y| (22..42).map(move |z| (x, y, z))))
        .filter(|&(x, y, z)| black(after.voxel(x, y, z)) && !black(before.voxel(x, y, z)))
        .count();
    assert!(stamped > 10, "{stamped} voxels near (40, 32, 32) turned black");
}

/// With `--only`, only the named entries must be valid: the valid entries of a manifest with
/// two broken ones build, and naming a broken one fails with that entry's own mistake.
#[test]
fn only_the_named_entries_must_be_valid() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("lib.toml");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/manifests/two-broken.toml");
    std::fs::copy(fixture, &manifest).unwrap();
    let (m, out) = (manifest.to_string_lossy().into_owned(), at(dir.path(), "out"));
    let run = solidtex(&["build", &m, "-o", &out, "--only", "a", "--only", "b"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("2 built, 0 cached, 0 failed"), "{}", stderr(&run));
    let run = solidtex(&["build", &m, "-o", &out, "--only", "broken2"]);
    assert_eq!(run.status.code(), Some(1));
    assert!(stderr(&run).contains("(broken2)") && stderr(&run).contains("weave"), "{}", stderr(&run));
    let run = solidtex(&["build", &m, "-o", &out]);
    assert_eq!(run.status.code(), Some(1), "a whole build still needs every entry valid");
}

/// The clean-up of an interrupted build removes only its own temporaries: a link shaped
/// like one goes, the folder it points to and the user's files beside it stay.
#[cfg(unix)]
#[test]
fn cleaning_up_never_touches_what_a_user_made() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let out = dir.path().join("out");
    let keep = dir.path().join("keep");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&keep).unwrap();
    std::fs::write(keep.join("precious.txt"), "mine").unwrap();
    std::os::unix::fs::symlink(&keep, out.join(".kiwi.solidtex-Ab12Cd.tmp")).unwrap();
    for user in ["notes.solidtex-draft.tmp", ".notes.solidtex-draft.tmp", ".kiwi.solidtex-Ab12C.tmp"] {
        std::fs::write(out.join(user), "mine").unwrap();
    }
    let run = solidtex(&["build", &manifest, "-o", &out.to_string_lossy()]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(std::fs::symlink_metadata(out.join(".kiwi.solidtex-Ab12Cd.tmp")).is_err(), "the stale temporary is gone");
    assert_eq!(std::fs::read_to_string(keep.join("precious.txt")).unwrap(), "mine");
    for user in ["notes.solidtex-draft.tmp", ".notes.solidtex-draft.tmp", ".kiwi.solidtex-Ab12C.tmp"] {
        assert_eq!(std::fs::read_to_string(out.join(user)).unwrap(), "mine", "{user}");
    }
}

/// A build refuses an output folder whose `.cache` is a symbolic link (it would write and
/// clean up where the link points) or a file, and leaves both as they were.
#[cfg(unix)]
#[test]
fn a_linked_or_plain_file_cache_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let out = dir.path().join("out");
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join(".cache")).unwrap();
    let run = solidtex(&["build", &manifest, "-o", &out.to_string_lossy()]);
    crate::support::assert_fails(&run, &[".cache", "is a symbolic link"]);
    assert_eq!(crate::support::listing(&elsewhere), Vec::<String>::new(), "nothing is written where it points");
    assert_eq!(crate::support::listing(&out), [".cache"]);
    std::fs::remove_file(out.join(".cache")).unwrap();
    std::fs::write(out.join(".cache"), "mine").unwrap();
    let run = solidtex(&["build", &manifest, "-o", &out.to_string_lossy()]);
    crate::support::assert_fails(&run, &[".cache", "is not a folder"]);
    assert_eq!(std::fs::read_to_string(out.join(".cache")).unwrap(), "mine");
}

/// An exemplar name longer than a file name may be is refused when the manifest is read,
/// the message naming the field and the limit and showing the name clipped; a 1 MB name
/// gives a short line.
#[test]
fn a_name_too_long_for_a_file_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = at(dir.path(), "out");
    for length in [201, 300, 1 << 20] {
        let manifest = dir.path().join("long.toml");
        let name = "n".repeat(length);
        std::fs::write(
            &manifest,
            format!("[[exemplar]]\nname = \"{name}\"\nrecipe = \"procedural:marble\"\nsize = 8\n"),
        )
        .unwrap();
        let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &out]);
        let says = format!("({length} bytes) is too long: a name has at most 200 bytes");
        crate::support::assert_fails(&run, &["long.toml", "entry 1", "name = \"nnnn", &says]);
        assert!(stderr(&run).len() < 400, "{}", stderr(&run));
    }
    assert!(!dir.path().join("out").exists());
    let manifest = dir.path().join("ok.toml");
    let name = "n".repeat(200);
    std::fs::write(&manifest, format!("[[exemplar]]\nname = \"{name}\"\nrecipe = \"procedural:marble\"\nsize = 8\n"))
        .unwrap();
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &out]);
    assert!(run.status.success(), "a name of 200 bytes is fine: {}", stderr(&run));
}

/// One image whose features run one way, asked for a homogeneous solid, gets the directional
/// warning in a build (on the error stream, named by entry), in the library report (also
/// after a second build that took the entry from the cache) and in the editor's preview
/// (for the terminal UI's status line); an image without a direction gets none. The same
/// image asked for a layered solid, its stripes down the columns, gets the layering warning.
#[test]
fn a_directional_photo_is_warned_about_in_builds_and_previews() {
    let dir = tempfile::tempdir().unwrap();
    let stripes = |period: usize| {
        let data = (0..48 * 48).map(|i| if ((i % 48) / period).is_multiple_of(2) { 0.2 } else { 0.8 }).collect();
        solidtex::volume::Image2d::from_data(48, 48, solidtex::Channel::grey(), data).unwrap()
    };
    solidtex::io::write_image(&dir.path().join("grain.png"), &stripes(3)).unwrap();
    let checks =
        (0..48 * 48usize).map(|i| if ((i % 48) / 3 + (i / 48) / 3).is_multiple_of(2) { 0.2 } else { 0.8 }).collect();
    let checks = solidtex::volume::Image2d::from_data(48, 48, solidtex::Channel::grey(), checks).unwrap();
    solidtex::io::write_image(&dir.path().join("checks.png"), &checks).unwrap();
    let manifest = dir.path().join("lib.toml");
    let entry = |name: &str, image: &str| {
        format!("[[exemplar]]\nname = \"{name}\"\nrecipe = \"synth\"\nimage = \"{image}\"\nsize = 8\nlevels = 1\n")
    };
    // the same stripes for a layered solid run down the columns, not along the rows
    let layered =
        "[[exemplar]]\nname = \"upright\"\nrecipe = \"synth-layered\"\nimage = \"grain.png\"\nsize = 8\nlevels = 1\n";
    let text = entry("grain", "grain.png") + &entry("checks", "checks.png") + layered;
    std::fs::write(&manifest, &text).unwrap();
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &at(dir.path(), "out")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("warning: grain:") && err.contains("features run one way"), "{err}");
    assert!(err.contains("synth-layered"), "the advice names the manifest's keys: {err}");
    assert!(!err.contains("warning: checks:"), "{err}");
    assert!(err.contains("warning: upright:") && err.contains("layers run down the columns"), "{err}");
    assert!(err.contains("depth_image"), "the advice names the manifest's key: {err}");
    for build in ["first", "cached"] {
        if build == "cached" {
            let again = solidtex(&["build", &manifest.to_string_lossy(), "-o", &at(dir.path(), "out")]);
            assert!(again.status.success() && !stderr(&again).contains("warning:"), "{}", stderr(&again));
        }
        let md = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
        let row =
            |name: &str| md.lines().find(|l| l.starts_with(&format!("| {name} |"))).unwrap_or_default().to_string();
        assert!(row("grain").contains("warning: ") && row("grain").contains("features run one way"), "{build}: {md}");
        assert!(!row("checks").contains("warning"), "{build}: {md}");
        let html = std::fs::read_to_string(dir.path().join("out/report.html")).unwrap();
        assert!(html.contains("<span class=warning>warning: ") && html.contains("features run one way"), "{html}");
    }
    let (_, warnings) = solidtex::library::recipe::preview(&manifest, "grain", &text).unwrap();
    assert!(warnings.iter().any(|w| w.contains("features run one way")), "{warnings:?}");
    let (_, warnings) = solidtex::library::recipe::preview(&manifest, "upright", &text).unwrap();
    assert!(warnings.iter().any(|w| w.contains("layers run down the columns")), "{warnings:?}");
}

/// A report row of an entry that failed while its earlier build is kept says so and shows
/// that build (its size and sheet, labelled as the earlier one); the others are as built.
/// The kept files stay in the ledger as solidtex's (not left claimed by the failed build).
#[test]
fn a_failed_entry_shows_its_kept_earlier_build_in_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = library(dir.path());
    let out = at(dir.path(), "out");
    assert!(solidtex(&["build", &manifest, "-o", &out]).status.success());
    assert!(dir.path().join("out/c.sheet.png").is_file());
    std::fs::remove_file(dir.path().join("section.png")).unwrap();
    std::fs::write(&manifest, std::fs::read_to_string(&manifest).unwrap() + "\n").unwrap();
    let failed = solidtex(&["build", &manifest, "-o", &out, "--force"]);
    assert!(!failed.status.success(), "{}", stderr(&failed));
    let md = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
    let row = md.lines().find(|l| l.starts_with("| c |")).unwrap_or_default();
    assert!(row.contains("failed") && row.contains("(earlier build kept)") && row.contains("c.sheet.png"), "{md}");
    assert!(!row.contains("| - | - |"), "the kept build's size and types: {row}");
    assert!(md.lines().any(|l| l.starts_with("| a |") && l.contains("![a](a.sheet.png)")), "{md}");
    // the kept files stay recorded as solidtex's, none left claimed
    let ledger = std::fs::read_to_string(dir.path().join("out/.cache/written.txt")).unwrap();
    assert!(!ledger.contains("pending") && ledger.lines().any(|l| l.ends_with("  c.exr")), "{ledger}");
    // without a kept build, a failed row shows nothing of an older one
    std::fs::remove_file(dir.path().join("out/c.exr")).unwrap();
    assert!(!solidtex(&["build", &manifest, "-o", &out]).status.success());
    let md = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
    let row = md.lines().find(|l| l.starts_with("| c |")).unwrap_or_default();
    assert!(row.contains("failed") && !row.contains("c.sheet.png"), "{md}");
}

/// `recipe = "load"` reads a stack of PNG slices as it reads any volume: built, then cached,
/// then rebuilt when a slice changes; an output folder that is the stack (or inside it) is
/// refused before anything is written there.
#[test]
fn a_loaded_stack_of_slices_is_built_and_never_written_into() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let volume = at(d, "m.exr");
    assert!(solidtex(&["make", "marble", "--size", "12", "-o", &volume]).status.success());
    assert!(solidtex(&["convert", &volume, &at(d, "stack")]).status.success());
    let manifest = at(d, "lib.toml");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"k\"\nrecipe = \"load\"\nvolume = \"stack\"\n").unwrap();
    let stack: Vec<(String, Vec<u8>)> = crate::support::listing(&d.join("stack"))
        .into_iter()
        .map(|n| (n.clone(), std::fs::read(d.join("stack").join(n)).unwrap()))
        .collect();
    for inside in ["stack", "stack/out"] {
        let run = solidtex(&["build", &manifest, "-o", &at(d, inside)]);
        crate::support::assert_usage(&run, &["is inside the folder volume", "exemplar k"]);
    }
    let now: Vec<String> = crate::support::listing(&d.join("stack"));
    assert_eq!(now, stack.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(), "nothing written into the stack");
    let out = at(d, "out");
    let first = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&first).contains("1 built"), "{}", stderr(&first));
    let again = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&again).contains("1 cached"), "{}", stderr(&again));
    assert!(solidtex(&["make", "marble", "--size", "12", "--seed", "2", "-o", &volume]).status.success());
    assert!(solidtex(&["convert", &volume, &at(d, "stack")]).status.success(), "the stack is solidtex's");
    let changed = solidtex(&["build", &manifest, "-o", &out]);
    assert!(stderr(&changed).contains("1 built"), "a changed slice rebuilds: {}", stderr(&changed));
}

/// An entry whose mask cannot be made fails before any of its files is written: its earlier
/// build's volume, sheet, view page and mask stay as they were, as the report says; a first
/// build that fails so leaves none of its files.
#[test]
fn an_entry_whose_mask_fails_leaves_its_earlier_build_whole() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("m.toml");
    let entry = |seed: u32, falloff: f32| {
        format!(
            "[[exemplar]]\nname = \"k\"\nrecipe = \"procedural:marble\"\nsize = 16\nseed = {seed}\nmasks = \
             [\"splotch\"]\nmask_falloff = {falloff}\n"
        )
    };
    std::fs::write(&manifest, entry(1, 0.1)).unwrap();
    let out = at(dir.path(), "out");
    let m = manifest.to_string_lossy().into_owned();
    assert!(solidtex(&["build", &m, "-o", &out]).status.success());
    let names = ["k.exr", "k.sheet.png", "k.view.html", "k.mask.exr"];
    let read = |folder: &str| names.map(|n| std::fs::read(dir.path().join(folder).join(n)).ok());
    let before = read("out");
    std::fs::write(&manifest, entry(2, 0.49)).unwrap();
    let failed = solidtex(&["build", &m, "-o", &out]);
    assert_eq!(failed.status.code(), Some(1), "{}", stderr(&failed));
    assert!(stderr(&failed).contains("opaque nowhere"), "{}", stderr(&failed));
    assert_eq!(read("out"), before, "the earlier build's files stay as they were");
    let md = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
    assert!(md.contains("(earlier build kept)"), "{md}");
    let fresh = at(dir.path(), "fresh");
    assert!(!solidtex(&["build", &m, "-o", &fresh]).status.success());
    assert_eq!(read("fresh"), [None, None, None, None], "a failed first build writes none of its files");
    // a person's file at the mask's name stops the entry and stays as it was
    std::fs::write(&manifest, entry(1, 0.1)).unwrap();
    let theirs = dir.path().join("theirs");
    std::fs::create_dir(&theirs).unwrap();
    std::fs::write(theirs.join("k.mask.exr"), b"my mask").unwrap();
    let run = solidtex(&["build", &m, "-o", &at(dir.path(), "theirs")]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("k.mask.exr") && stderr(&run).contains("not written by solidtex"),
        "{}",
        stderr(&run)
    );
    assert_eq!(std::fs::read(theirs.join("k.mask.exr")).unwrap(), b"my mask");
    assert!(!theirs.join("k.exr").exists(), "the entry is not built");
}

/// A declared type the classifier does not read is flagged in the report (fill and guided go
/// by the declared one); an entry whose types agree gets no such warning.
#[test]
fn the_report_flags_a_declared_type_the_classifier_disagrees_with() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("lib.toml");
    std::fs::write(
        &manifest,
        "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 16\ntype = \"2-b\"\n\
         [[exemplar]]\nname = \"n\"\nrecipe = \"procedural:marble\"\nsize = 16\n",
    )
    .unwrap();
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &at(dir.path(), "out")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let report = std::fs::read_to_string(dir.path().join("out/report.md")).unwrap();
    let row = |name: &str| report.lines().find(|l| l.starts_with(&format!("| {name} | "))).unwrap().to_string();
    let (m, n) = (row("m"), row("n"));
    assert!(m.contains("| 2-b | 0 |") && m.contains("warning: declared type 2-b, classified 0"), "{report}");
    assert!(n.contains("| 0 | 0 |") && !n.contains("declared type"), "{report}");
    let html = std::fs::read_to_string(dir.path().join("out/report.html")).unwrap();
    assert!(html.contains("declared type 2-b, classified 0: fill and guided use the declared type"), "{html}");
}

/// A synthesized entry records its max_exemplar as `synth --max-exemplar` does, so
/// `quality` measures the built volume against the photo shrunk alike without being told.
#[test]
fn a_built_synthesis_records_its_max_exemplar_for_quality() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let photo = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let manifest = at(d, "lib.toml");
    let entry = format!(
        "[[exemplar]]\nname = \"g\"\nrecipe = \"synth\"\nimage = {photo:?}\nmax_exemplar = 64\nsize = 16\nseed = 1\n"
    );
    std::fs::write(&manifest, entry).unwrap();
    let out = at(d, "out");
    let run = solidtex(&["build", &manifest, "-o", &out]);
    assert!(run.status.success(), "{}", stderr(&run));
    let built = at(d, "out/g.exr");
    let info = solidtex(&["info", &built]);
    assert!(String::from_utf8_lossy(&info.stdout).contains("max_exemplar"), "{info:?}");
    let run = solidtex(&["quality", &built, "--exemplar", photo]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("shrunk to 64 px"), "{}", stderr(&run));
}
