//! The README's "A short tour", run line by line, in order, as a reader would from the root
//! of a fresh clone: only the repository's input folders and what earlier lines made.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};

/// Tour lines that have their own tests: the terminal UI (src/tui, tests/tui_e2e.sh) and bench.
const SKIPPED: [&str; 2] = ["solidtex", "solidtex bench"];

/// The folders of the repository that tour lines read from.
const REPO_INPUTS: [&str; 2] = ["exemplars", "masks"];

/// The tour has more lines than this; fewer means its block was not found whole.
const MIN_LINES: usize = 30;

/// Characters a shell would treat specially: a tour line with one outside quotes would not
/// run the same when pasted into a shell as here.
const SHELL_SPECIAL: &str = "\"\\$|&;<>*?`~";

#[test]
fn every_tour_line_runs_in_order_in_a_fresh_clone() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lines = tour_lines(&fs::read_to_string(repo.join("README.md")).unwrap());
    assert!(lines.len() >= MIN_LINES, "the tour has {} lines, expected at least {MIN_LINES}", lines.len());
    let clone = tempfile::tempdir().unwrap();
    for name in REPO_INPUTS {
        copy_tree(&repo.join(name), &clone.path().join(name));
    }
    let mut skipped = Vec::new();
    for line in &lines {
        let words = words(line);
        assert_eq!(words.first().map(String::as_str), Some("solidtex"), "a tour line that is not solidtex: {line}");
        if SKIPPED.contains(&words.join(" ").as_str()) {
            skipped.push(words.join(" "));
            continue;
        }
        run_line(clone.path(), line, &words);
    }
    assert_eq!(skipped, SKIPPED, "the tour should still show the terminal UI and bench");
    check_promises(clone.path());
    for name in REPO_INPUTS {
        assert_same_tree(&repo.join(name), &clone.path().join(name));
    }
}

/// The lines of the ```sh block under "## A short tour".
fn tour_lines(readme: &str) -> Vec<String> {
    let section = readme.split_once("\n## A short tour\n").expect("README.md has a \"## A short tour\" section").1;
    let section = section.split("\n## ").next().unwrap();
    let block = section.split_once("```sh\n").expect("the tour section has a ```sh block").1;
    let block = block.split_once("```").expect("the tour's ```sh block is closed").0;
    block.lines().filter(|l| !l.trim().is_empty()).map(str::to_string).collect()
}

/// A line's words as a POSIX shell splits them: whitespace separates, single quotes group,
/// a `#` that starts a word starts the comment. Other shell syntax is refused.
fn words(line: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word: Option<String> = None;
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '\'' => {
                quoted = !quoted;
                word.get_or_insert_default();
            }
            _ if quoted => word.get_or_insert_default().push(c),
            '#' if word.is_none() => break,
            _ if c.is_whitespace() => words.extend(word.take()),
            _ if SHELL_SPECIAL.contains(c) => panic!("the tour line uses shell syntax ({c}): {line}"),
            _ => word.get_or_insert_default().push(c),
        }
    }
    assert!(!quoted, "unclosed quote in the tour line: {line}");
    words.extend(word);
    words
}

/// Run one tour line in `clone`; it must exit 0 and write every output it names.
fn run_line(clone: &Path, line: &str, words: &[String]) {
    let out = solidtex_in(clone, &words[1..]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "tour line failed ({}):\n  {line}\nstderr:\n{err}", out.status);
    for name in named_outputs(words) {
        assert!(clone.join(name).exists(), "tour line did not write {name}:\n  {line}\nstderr:\n{err}");
    }
    if words.iter().any(|w| w == "--json") {
        let json = serde_json::from_slice::<serde_json::Value>(&out.stdout);
        assert!(json.is_ok(), "tour line did not print JSON:\n  {line}\n{json:?}");
    }
}

/// Run the built binary with `args` in `folder`, as a shell there would.
fn solidtex_in(folder: &Path, args: &[String]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(args)
        .current_dir(folder)
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .expect("the solidtex binary runs")
}

/// The outputs a line names: the value of `-o`/`--output`, and `convert`'s second file.
fn named_outputs(words: &[String]) -> Vec<&str> {
    let mut outputs: Vec<&str> =
        words.windows(2).filter(|w| w[0] == "-o" || w[0] == "--output").map(|w| w[1].as_str()).collect();
    if words.get(1).is_some_and(|w| w == "convert") {
        outputs.extend(words.get(3).map(String::as_str));
    }
    outputs
}

/// What the tour says it makes, beyond each line's outputs existing.
fn check_promises(clone: &Path) {
    let budget = 1 << 30;
    let marble = solidtex::io::read_volume(&clone.join("marble.exr"), budget).unwrap();
    let atlas = solidtex::io::read_volume(&clone.join("marble.png"), budget);
    assert_eq!(atlas.map(|v| v.dims()).ok(), Some(marble.dims()), "marble.png is the flipbook atlas of marble.exr");
    let sheet = fs::read(clone.join("marble.sheet.png")).expect("the tour makes the sheet marble.sheet.png");
    assert_ne!(sheet, fs::read(clone.join("marble.png")).unwrap(), "the sheet and the atlas are different files");
    assert!(solidtex::io::read_volume(&clone.join("marble.sheet.png"), budget).is_err(), "the sheet is a picture");
    let want: Vec<String> = (0..marble.dims()[2]).map(|z| format!("z{z:04}.png")).collect();
    assert_eq!(slice_names(&clone.join("slices")), want, "slices/ holds one PNG per z-slice");
    for built in ["out/report.html", "out/kiwi.exr", "out/strata.exr"] {
        assert!(clone.join(built).is_file(), "the build line did not make {built}");
    }
}

/// The `z*.png` names in `folder`, sorted.
fn slice_names(folder: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('z') && n.ends_with(".png"))
        .collect();
    names.sort();
    names
}

/// Copy the folder `from` to `to`, sub-folders included.
fn copy_tree(from: &Path, to: &Path) {
    fs::create_dir_all(to).unwrap();
    for entry in fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// The tour reads the repository's inputs and never changes them.
fn assert_same_tree(original: &Path, copy: &Path) {
    for entry in fs::read_dir(original).unwrap() {
        let entry = entry.unwrap();
        let other = copy.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            assert_same_tree(&entry.path(), &other);
        } else {
            let same = fs::read(&other).ok() == Some(fs::read(entry.path()).unwrap());
            assert!(same, "the tour changed or removed {}", other.display());
        }
    }
}
