//! What a command may write: never one of its inputs, only under its own extension, and a
//! side file, a build's file or a file in a folder solidtex wrote only while it is the one
//! solidtex wrote there, unchanged. And images that would take more memory than the process
//! may have are refused from their header, on the command line and in a build.

use crate::support::{assert_fails, assert_usage, at, listing, random_volume, solidtex, stderr};
use solidtex::io::write_volume;
use solidtex::volume::Channel;
use std::path::Path;
use std::process::{Command, Output};

/// The bytes of every file in `dir`, to compare before and after a refused run.
fn contents(dir: &Path) -> Vec<(String, Vec<u8>)> {
    listing(dir)
        .into_iter()
        .filter(|n| dir.join(n).is_file())
        .map(|n| (n.clone(), std::fs::read(dir.join(n)).unwrap()))
        .collect()
}

/// Each writer named with one of its inputs as its output is refused (exit 2) before any
/// work, and no file changes.
#[test]
fn an_output_naming_an_input_is_refused_and_nothing_changes() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| at(dir.path(), n);
    write_volume(&dir.path().join("v.exr"), &random_volume([4, 4, 3], Channel::rgb(), 1)).unwrap();
    write_volume(&dir.path().join("atlas.png"), &random_volume([4, 4, 3], Channel::rgb(), 2)).unwrap();
    assert!(solidtex(&["draw", "kiwi", "--size", "16x16", "-o", &d("k.png")]).status.success());
    assert!(solidtex(&["draw", "fruit", "-o", &d("fruit.obj")]).status.success());
    std::fs::write(dir.path().join("w.lst"), "a model").unwrap();
    std::fs::write(dir.path().join("s.toml"), "exemplar = \"kiwi\"\n").unwrap();
    std::os::unix::fs::symlink(dir.path().join("v.exr"), dir.path().join("link.exr")).unwrap();
    let before = contents(dir.path());
    let runs: Vec<Vec<String>> = [
        vec!["convert", "v.exr", "v.exr"],
        vec!["convert", "v.exr", "link.exr"],
        vec!["snapshot", "v.exr", "-o", "v.exr"],
        vec!["slice", "v.exr", "-o", "v.exr"],
        vec!["slice", "v.exr", "--plane", "1,1,1,0,0,1", "-o", "v.exr"],
        vec!["noise", "k.png", "--size", "8", "-o", "k.png"],
        vec!["sheet", "atlas.png", "-o", "atlas.png"],
        vec!["flipbook", "atlas.png", "-o", "atlas.png"],
        vec!["synth", "k.png", "--size", "8", "-o", "k.png"],
        vec!["sweep", "k.png", "--length", "4", "-o", "k.png"],
        vec!["cut", "w.lst", "-o", "w.lst"],
        vec!["view", "w.lst", "-o", "w.lst"],
        vec!["render", "w.lst", "-o", "w.lst"],
        vec!["export", "w.lst", "-o", "w.lst"],
        vec!["web", "w.lst", "-o", "w.lst"],
        vec!["web", "v.exr", "-o", "v.exr"],
        vec!["field", "fruit.obj", "--spec", "s.toml", "-o", "s.toml"],
        vec!["fill", "fruit.obj", "--spec", "s.toml", "-o", "w.lst", "--json", "s.toml"],
        vec!["fill", "fruit.obj", "--spec", "w.lst", "-o", "w.lst"],
        vec!["surface", "fruit.obj", "--exemplar", "k.png", "--spec", "s.toml", "-o", "fruit.obj"],
        vec!["draw", "fruit", "-o", "s.toml"],
    ]
    .iter()
    .map(|r| r.iter().map(|a| if a.contains('.') { d(a) } else { a.to_string() }).collect())
    .collect();
    for run in &runs {
        let args: Vec<&str> = run.iter().map(String::as_str).collect();
        let out = solidtex(&args);
        assert_eq!(out.status.code(), Some(2), "{run:?}: {}", stderr(&out));
        assert_eq!(contents(dir.path()), before, "{run:?} changed a file");
    }
    assert_usage(&solidtex(&["convert", &d("v.exr"), &d("v.exr")]), &["v.exr", "is the input"]);
    assert_usage(&solidtex(&["cut", &d("w.lst"), "-o", &d("w.lst")]), &["w.lst", ".png"]);
}

/// A stack of PNG slices read as a volume is an input as a whole: an output naming one of
/// its slices, or a new file inside its folder (which would read as one more slice), is
/// refused (exit 2) before any work, and no slice changes.
#[test]
fn an_output_inside_an_input_stack_of_slices_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| at(dir.path(), n);
    write_volume(&dir.path().join("v.exr"), &random_volume([6, 6, 4], Channel::rgb(), 3)).unwrap();
    let run = solidtex(&["convert", &d("v.exr"), &d("st")]);
    assert!(run.status.success(), "{}", stderr(&run));
    let stack = dir.path().join("st");
    let before = contents(&stack);
    let slice = at(&stack, "z0002.png");
    let new = at(&stack, "extra.png");
    std::os::unix::fs::symlink(&stack, dir.path().join("link")).unwrap();
    let through_link = d("link/z0001.png");
    let st = d("st");
    let st = st.as_str();
    let runs: Vec<Vec<&str>> = vec![
        vec!["convert", st, &slice],
        vec!["convert", st, &new],
        vec!["convert", st, &through_link],
        vec!["sheet", st, "-o", &slice],
        vec!["slice", st, "--axis", "z", "--index", "1", "-o", &slice],
    ];
    for args in &runs {
        let out = solidtex(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("an input of this command"), "{args:?}: {}", stderr(&out));
        assert_eq!(contents(&stack), before, "{args:?} changed the stack");
    }
    let run = solidtex(&["convert", st, &d("copy.exr")]);
    assert!(run.status.success(), "an output beside the stack is fine: {}", stderr(&run));
}

/// The editors keep editing a volume in place, as the README's tour runs them.
#[test]
fn the_editors_still_write_over_the_volume_they_edit() {
    let dir = tempfile::tempdir().unwrap();
    let v = at(dir.path(), "v.exr");
    write_volume(Path::new(&v), &random_volume([8, 8, 8], Channel::rgb(), 1)).unwrap();
    let seed = at(dir.path(), "seed.obj");
    assert!(solidtex(&["draw", "seed", "-o", &seed]).status.success());
    let before = std::fs::read(&v).unwrap();
    let run = solidtex(&["stamp", &v, &seed, "--at", "4,4,4", "--scale", "2", "--color", "0,0,0", "-o", &v]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_ne!(std::fs::read(&v).unwrap(), before, "the stamp is in the volume");
    let run = solidtex(&["blur", &v, "--at", "4,4,4", "--radius", "2", "--strength", "0.5", "-o", &v]);
    assert!(run.status.success(), "{}", stderr(&run));
}

/// A small library of two procedural entries.
fn manifest(dir: &Path) -> String {
    let path = dir.join("lib.toml");
    std::fs::write(
        &path,
        "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n\
         [[exemplar]]\nname = \"b\"\nrecipe = \"procedural:strata\"\nsize = 8\n",
    )
    .unwrap();
    path.to_string_lossy().into_owned()
}

/// `build -o DIR` replaces only what it wrote there: a person's report stops the build
/// before any work, a person's volume fails its entry only, an edited output is kept, and
/// its own files are rebuilt freely.
#[test]
fn a_build_never_replaces_a_persons_file_in_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let lib = manifest(dir.path());
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("report.md"), "# my notes\n").unwrap();
    assert_fails(&solidtex(&["build", &lib, "-o", &at(dir.path(), "out")]), &["report.md", "not written by solidtex"]);
    assert_eq!(std::fs::read_to_string(out.join("report.md")).unwrap(), "# my notes\n");
    assert!(!out.join("a.exr").exists(), "nothing was built");
    std::fs::remove_file(out.join("report.md")).unwrap();
    std::fs::write(out.join("b.exr"), "my volume").unwrap();
    let run = solidtex(&["build", &lib, "-o", &at(dir.path(), "out")]);
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    assert!(stderr(&run).contains("b.exr") && stderr(&run).contains("not written by solidtex"), "{}", stderr(&run));
    assert_eq!(std::fs::read(out.join("b.exr")).unwrap(), b"my volume");
    assert!(
        out.join("a.exr").is_file() && out.join("report.md").is_file(),
        "the other entry and the report are written"
    );
    std::fs::remove_file(out.join("b.exr")).unwrap();
    std::fs::write(out.join("b.view.html"), "<p>my page</p>").unwrap();
    let run = solidtex(&["build", &lib, "-o", &at(dir.path(), "out")]);
    assert!(
        stderr(&run).contains("b.view.html") && stderr(&run).contains("not written by solidtex"),
        "{}",
        stderr(&run)
    );
    assert_eq!(std::fs::read(out.join("b.view.html")).unwrap(), b"<p>my page</p>");
    assert!(!out.join("b.exr").exists(), "an entry with a person's file in the way is not built");
    std::fs::remove_file(out.join("b.view.html")).unwrap();
    let run = solidtex(&["build", &lib, "-o", &at(dir.path(), "out"), "--force"]);
    assert!(run.status.success(), "solidtex replaces its own files: {}", stderr(&run));
    std::fs::write(out.join("a.sheet.png"), "edited").unwrap();
    let run = solidtex(&["build", &lib, "-o", &at(dir.path(), "out"), "--force"]);
    assert!(stderr(&run).contains("a.sheet.png") && stderr(&run).contains("changed since"), "{}", stderr(&run));
    assert_eq!(std::fs::read(out.join("a.sheet.png")).unwrap(), b"edited");
}

/// `build -o .` is refused like every folder output, and nothing is written there.
#[test]
fn a_build_into_the_current_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let lib = manifest(dir.path());
    let run =
        Command::new(env!("CARGO_BIN_EXE_solidtex")).args(["build", &lib, "-o", "."]).current_dir(dir.path()).output();
    assert_fails(&run.unwrap(), &["current folder"]);
    assert_eq!(listing(dir.path()), ["lib.toml"]);
}

/// A file a person edited in a folder solidtex wrote, a flipbook's layout and a preset's
/// mask of the same name as a person's file are kept; solidtex's own are replaced.
#[test]
fn side_files_and_edited_folder_files_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    let lib = manifest(dir.path());
    let cake = at(dir.path(), "cake");
    let draw = |d: &Path| {
        Command::new(env!("CARGO_BIN_EXE_solidtex"))
            .args(["draw", "cake", "-o", &cake, "--library", &lib])
            .current_dir(d)
            .output()
            .unwrap()
    };
    assert!(draw(dir.path()).status.success());
    assert!(draw(dir.path()).status.success(), "its own folder is replaced");
    let cream = dir.path().join("cake/cream.toml");
    let edited = std::fs::read_to_string(&cream).unwrap() + "# mine\n";
    std::fs::write(&cream, &edited).unwrap();
    assert_fails(&draw(dir.path()), &["cream.toml", "changed since"]);
    assert_eq!(std::fs::read_to_string(&cream).unwrap(), edited);

    let v = at(dir.path(), "v.exr");
    write_volume(Path::new(&v), &random_volume([4, 4, 4], Channel::rgb(), 1)).unwrap();
    let flip = at(dir.path(), "m.png");
    assert!(solidtex(&["flipbook", &v, "-o", &flip]).status.success());
    assert!(solidtex(&["flipbook", &v, "-o", &flip, "--padding", "1"]).status.success(), "its own layout is replaced");
    std::fs::write(dir.path().join("m.json"), "{\"mine\": 1}").unwrap();
    assert_fails(&solidtex(&["flipbook", &v, "-o", &flip]), &["m.json", "not written by solidtex"]);
    assert_eq!(std::fs::read_to_string(dir.path().join("m.json")).unwrap(), "{\"mine\": 1}");

    let preset = dir.path().join("spot.toml");
    std::fs::write(&preset, "kind = \"splotch\"\nsize = 8\n").unwrap();
    let preset = preset.to_string_lossy().into_owned();
    assert!(solidtex(&["mask", "preset", &preset]).status.success());
    assert!(solidtex(&["mask", "preset", &preset]).status.success(), "its own mask is replaced");
    write_volume(&dir.path().join("spot.exr"), &random_volume([4, 4, 4], Channel::rgb(), 1)).unwrap();
    let mine = std::fs::read(dir.path().join("spot.exr")).unwrap();
    assert_fails(&solidtex(&["mask", "preset", &preset]), &["spot.exr", "not written by solidtex"]);
    assert_eq!(std::fs::read(dir.path().join("spot.exr")).unwrap(), mine);
}

/// A 1-bit grey PNG of `side`² black pixels: tens of kilobytes that decode to hundreds of
/// megabytes (a decompression bomb).
fn bomb(path: &Path, side: u32) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, side, side);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::One);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    let row = vec![0u8; side.div_ceil(8) as usize];
    for _ in 0..side {
        std::io::Write::write_all(&mut stream, &row).unwrap();
    }
    stream.finish().unwrap();
}

/// Run `solidtex` under an address-space limit of `kb` kilobytes.
fn within(kb: u64, args: &[&str]) -> Output {
    let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
    let script = format!("ulimit -v {kb} && exec '{}' {}", env!("CARGO_BIN_EXE_solidtex"), quoted.join(" "));
    Command::new("bash").args(["-c", &script]).output().unwrap()
}

/// Decompression bombs are refused from their header with exit 1, under a 4 GB and a 1 GB
/// address-space limit, by every command that reads a photo; in a build the other entries
/// still build and the report is written.
#[test]
fn decompression_bombs_are_refused_not_aborted() {
    let dir = tempfile::tempdir().unwrap();
    bomb(&dir.path().join("b20k.png"), 20_000);
    bomb(&dir.path().join("b32k.png"), 32_000);
    std::fs::write(dir.path().join("giga.png"), crate::safety::lying_png(32768, 32768)).unwrap();
    assert!(std::fs::metadata(dir.path().join("b20k.png")).unwrap().len() < 200_000);
    let d = |n: &str| at(dir.path(), n);
    write_volume(&dir.path().join("v.exr"), &random_volume([8, 8, 8], Channel::rgb(), 1)).unwrap();
    assert!(solidtex(&["draw", "fruit", "-o", &d("fruit.obj")]).status.success());
    let spec = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/kiwi_fill.toml");
    for kb in [4_000_000, 1_000_000] {
        for photo in ["b20k.png", "b32k.png", "giga.png"] {
            let p = d(photo);
            let runs: [Vec<&str>; 5] = [
                vec!["synth", &p, "--size", "8", "-o", "o.exr"],
                vec!["sweep", &p, "--length", "4", "-o", "o.exr"],
                vec!["quality", "v.exr", "--exemplar", &p],
                vec!["surface", "fruit.obj", "--exemplar", &p, "--spec", spec, "-o", "o.ply"],
                vec!["info", &p],
            ];
            for run in runs {
                let named = |a: &&str| if a.contains('.') && !a.contains('/') { d(a) } else { a.to_string() };
                let run: Vec<String> = run.iter().map(named).collect();
                let args: Vec<&str> = run.iter().map(String::as_str).collect();
                let out = within(kb, &args);
                assert_eq!(out.status.code(), Some(1), "{kb} kB, {args:?}: {}", stderr(&out));
                assert!(stderr(&out).contains(photo), "{kb} kB, {args:?}: {}", stderr(&out));
            }
        }
    }
    let lib = dir.path().join("lib.toml");
    std::fs::write(
        &lib,
        "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n\
         [[exemplar]]\nname = \"boom\"\nrecipe = \"synth\"\nimage = \"b20k.png\"\nsize = 8\n",
    )
    .unwrap();
    for (kb, folder) in [(4_000_000, "out4"), (1_000_000, "out1")] {
        let out = within(kb, &["build", &lib.to_string_lossy(), "-o", &d(folder)]);
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(stderr(&out).contains("FAILED boom") && stderr(&out).contains("too large"), "{}", stderr(&out));
        assert!(dir.path().join(folder).join("a.exr").is_file() && dir.path().join(folder).join("report.md").is_file());
    }
}

/// Under a 4 GB address-space limit, the largest values of each documented range are
/// refused with a message naming the budget, or run, and never abort: `make`, `sweep`,
/// `guided` and `render`.
#[test]
fn the_largest_options_never_abort_under_a_memory_cap() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cap = 4_000_000;
    let refused = |out: Output, says: &str| {
        assert!(matches!(out.status.code(), Some(1 | 2)), "{}", stderr(&out));
        assert!(stderr(&out).contains(says), "{}", stderr(&out));
    };
    refused(within(cap, &["make", "marble", "--size", "512", "-o", &at(d, "m.exr")]), "voxel budget");
    let big = at(d, "big.png");
    assert!(solidtex(&["draw", "kiwi", "--size", "2048x2048", "-o", &big]).status.success());
    refused(within(cap, &["sweep", &big, "--length", "40", "-o", &at(d, "s.exr")]), "voxel budget");
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let gravel = concat!(env!("CARGO_MANIFEST_DIR"), "/exemplars/gravel_photo.png");
    let guided = ["guided", &fruit, "--spec", &spec, "--exemplar", gravel, "--res", "512", "-o", &at(d, "g.exr")];
    refused(within(cap, &guided), "budget");
    let model = at(d, "kiwi.lst");
    assert!(solidtex(&["fill", &fruit, "--spec", &spec, "-o", &model]).status.success());
    refused(within(cap, &["render", &model, "--size", "4096", "-o", &at(d, "r.png")]), "budget");
    let run = within(cap, &["render", &model, "--size", "1024", "--slices", "16", "-o", &at(d, "r.png")]);
    assert!(run.status.success(), "a render within the budget runs: {}", stderr(&run));
    assert!(!d.join("m.exr").exists() && !d.join("s.exr").exists() && !d.join("g.exr").exists());
}

/// A folder built before solidtex recorded hashes (folder lists of names only, no ledger)
/// is taken over where the build's records vouch for its files, and its lists get hashes.
#[test]
fn a_build_folder_from_before_hashes_is_taken_over() {
    let dir = tempfile::tempdir().unwrap();
    let lib = dir.path().join("lib.toml");
    std::fs::write(
        &lib,
        "[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\nexports = [\"slices\"]\n",
    )
    .unwrap();
    let (lib, out) = (lib.to_string_lossy().into_owned(), at(dir.path(), "out"));
    assert!(solidtex(&["build", &lib, "-o", &out]).status.success());
    let list = dir.path().join("out/a_slices/solidtex-folder.txt");
    let names: String = std::fs::read_to_string(&list)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{}\n", l.split_once("  ").unwrap().1))
        .collect();
    std::fs::write(&list, format!("# Written by solidtex.\n{names}")).unwrap();
    std::fs::remove_file(dir.path().join("out/.cache/written.txt")).unwrap();
    let run = solidtex(&["build", &lib, "-o", &out, "--force"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(std::fs::read_to_string(&list).unwrap().lines().any(|l| l.ends_with("  z0000.png")), "hashes again");
}
