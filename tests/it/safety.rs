//! Data safety: solidtex never deletes or overwrites what it did not write, checks every
//! size from a file before taking memory, reads only regular files, and keeps one build
//! from disturbing another.

use crate::support::{assert_fails, at, listing, random_volume, solidtex, solidtex_env, stderr};
use solidtex::io::write_volume;
use solidtex::volume::Channel;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A small RGB volume written at `dir/name`.
fn volume_file(dir: &Path, name: &str, z: usize) -> String {
    let path = dir.join(name);
    write_volume(&path, &random_volume([4, 4, z], Channel::rgb(), 3)).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn a_folder_with_other_files_is_refused_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let input = volume_file(dir.path(), "v.exr", 3);
    let folder = dir.path().join("d");
    std::fs::create_dir(&folder).unwrap();
    std::fs::write(folder.join("a.txt"), "keep").unwrap();
    for target in [at(dir.path(), "d"), format!("{}/", at(dir.path(), "d"))] {
        assert_fails(&solidtex(&["convert", &input, &target]), &["d", "a.txt", "did not write"]);
        assert_eq!(listing(&folder), ["a.txt"]);
        assert_eq!(std::fs::read_to_string(folder.join("a.txt")).unwrap(), "keep");
    }
}

#[test]
fn the_current_folder_is_never_an_output() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    volume_file(&work, "v.exr", 3);
    let run = Command::new(env!("CARGO_BIN_EXE_solidtex")).args(["convert", "v.exr", "."]).current_dir(&work).output();
    let run = run.unwrap();
    assert_fails(&run, &["current folder"]);
    assert_eq!(listing(&work), ["v.exr"]);
    let up = Command::new(env!("CARGO_BIN_EXE_solidtex")).args(["convert", "v.exr", ".."]).current_dir(&work).output();
    assert_fails(&up.unwrap(), &[".."]);
    assert_eq!(listing(dir.path()), ["work"]);
}

#[test]
fn a_stack_solidtex_wrote_is_replaced_whole() {
    let dir = tempfile::tempdir().unwrap();
    let five = volume_file(dir.path(), "five.exr", 5);
    let two = volume_file(dir.path(), "two.exr", 2);
    let stack = at(dir.path(), "slices/");
    assert!(solidtex(&["convert", &five, &stack]).status.success());
    let folder = dir.path().join("slices");
    let names = ["solidtex-folder.txt", "z0000.png", "z0001.png", "z0002.png", "z0003.png", "z0004.png"];
    assert_eq!(listing(&folder), names);
    let converted = solidtex(&["convert", &two, &stack]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert_eq!(listing(&folder), ["solidtex-folder.txt", "z0000.png", "z0001.png"], "no old slice is left");
    let back = at(dir.path(), "back.exr");
    assert!(solidtex(&["convert", &stack, &back]).status.success());
    assert_eq!(solidtex::io::read_volume(Path::new(&back), u64::MAX).unwrap().dims(), [4, 4, 2]);
    assert_eq!(listing(dir.path()), ["back.exr", "five.exr", "slices", "two.exr"], "no temporary is left");
    std::fs::write(folder.join("notes.txt"), "mine").unwrap();
    assert_fails(&solidtex(&["convert", &five, &stack]), &["notes.txt"]);
    assert_eq!(listing(&folder), ["notes.txt", "solidtex-folder.txt", "z0000.png", "z0001.png"]);
}

#[test]
fn a_folder_holding_the_input_or_a_link_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let v = volume_file(dir.path(), "v.exr", 2);
    let stack = at(dir.path(), "s");
    assert!(solidtex(&["convert", &v, &stack]).status.success());
    assert_fails(&solidtex(&["convert", &stack, &stack]), &["holds the input"]);
    std::os::unix::fs::symlink(dir.path().join("s"), dir.path().join("link")).unwrap();
    assert_fails(&solidtex(&["convert", &v, &at(dir.path(), "link")]), &["link", "symbolic link"]);
    // `link/` names the link too (the file system would follow it), and nothing is left behind
    let before = listing(dir.path());
    assert_fails(&solidtex(&["convert", &v, &format!("{}/", at(dir.path(), "link"))]), &["link", "symbolic link"]);
    assert_eq!(listing(dir.path()), before, "no temporary folder is left");
}

#[test]
fn the_named_output_file_may_be_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let v = volume_file(dir.path(), "v.exr", 2);
    let run = solidtex(&["blur", &v, "--at", "2,2,1", "--radius", "2", "--strength", "0.5", "-o", &v]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(listing(dir.path()), ["v.exr"]);
}

/// A symbolic link named as a file output is refused before any work (exit 2): it is not
/// replaced (the link is the user's) nor written through (the file it names may be anything).
#[test]
fn an_output_that_is_a_link_is_neither_replaced_nor_followed() {
    let dir = tempfile::tempdir().unwrap();
    let v = volume_file(dir.path(), "v.exr", 2);
    let elsewhere = dir.path().join("elsewhere.txt");
    std::fs::write(&elsewhere, "precious").unwrap();
    for name in ["out.nrrd", "out.png"] {
        std::os::unix::fs::symlink(&elsewhere, dir.path().join(name)).unwrap();
    }
    let link = at(dir.path(), "out.nrrd");
    crate::support::assert_usage(&solidtex(&["convert", &v, &link]), &["out.nrrd", "symbolic link"]);
    crate::support::assert_usage(&solidtex(&["slice", &v, "-o", &at(dir.path(), "out.png")]), &["symbolic link"]);
    assert_eq!(std::fs::read_to_string(&elsewhere).unwrap(), "precious");
    for name in ["out.nrrd", "out.png"] {
        assert!(std::fs::symlink_metadata(dir.path().join(name)).unwrap().file_type().is_symlink(), "{name} stays");
    }
}

#[test]
fn planted_links_at_temporary_names_are_not_followed() {
    let dir = tempfile::tempdir().unwrap();
    let elsewhere = dir.path().join("elsewhere.txt");
    std::fs::write(&elsewhere, "precious").unwrap();
    let pid = std::process::id();
    for name in [format!(".out.txt.{pid}.tmp"), format!(".out.txt.solidtex-{pid}.tmp"), ".out.txt.tmp".to_string()] {
        std::os::unix::fs::symlink(&elsewhere, dir.path().join(name)).unwrap();
    }
    let out = dir.path().join("out.txt");
    solidtex::io::write_bytes(&out, b"new").unwrap();
    assert_eq!(std::fs::read_to_string(&elsewhere).unwrap(), "precious");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    assert!(std::fs::symlink_metadata(&out).unwrap().is_file(), "the output is a file, not a link");
}

/// A NRRD file with `sizes` and a few data bytes.
fn nrrd(dir: &Path, sizes: &str) -> String {
    let dimension = sizes.split_whitespace().count();
    let text = format!("NRRD0004\ntype: float\ndimension: {dimension}\nsizes: {sizes}\nencoding: raw\n\n\0\0\0\0");
    let path = dir.join("huge.nrrd");
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn huge_nrrd_sizes_are_refused_before_allocation() {
    let dir = tempfile::tempdir().unwrap();
    for sizes in ["2147483647 1 1 1", "9223372036854775807 1 1 1", "3 4096 4096 4096"] {
        let file = nrrd(dir.path(), sizes);
        assert_fails(&solidtex(&["convert", &file, &at(dir.path(), "out.exr")]), &["huge.nrrd", "voxel budget"]);
        assert_eq!(listing(dir.path()), ["huge.nrrd"], "nothing is left behind");
    }
    let within_budget = nrrd(dir.path(), "100000000 1 1");
    assert_fails(&solidtex(&["info", &within_budget]), &["huge.nrrd", "truncated", "400000000 bytes"]);
    let file = nrrd(dir.path(), "64 64 64 64");
    let small = solidtex_env(&["info", &file], &[("SOLIDTEX_MAX_BYTES", "1000000")]);
    assert_fails(&small, &["huge.nrrd", "64 channel(s)", "voxel budget"]);
}

/// CRC-32 of PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for b in bytes {
        crc ^= *b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xedb8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

fn chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// A tiny PNG whose header claims `width` x `height` grey pixels.
pub fn lying_png(width: u32, height: u32) -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = width.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    chunk(&mut png, b"IHDR", &ihdr);
    chunk(&mut png, b"tEXt", b"solidtex\0dims: 1 1 1\nchannels: R\n");
    chunk(&mut png, b"IDAT", &[0x78, 0x9c, 0x63, 0, 0, 0, 1, 0, 1]);
    chunk(&mut png, b"IEND", &[]);
    png
}

#[test]
fn a_png_claiming_a_huge_size_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let atlas = dir.path().join("atlas.png");
    std::fs::write(&atlas, lying_png(1, 1 << 31)).unwrap();
    let convert = solidtex(&["convert", &atlas.to_string_lossy(), &at(dir.path(), "out.exr")]);
    assert_fails(&convert, &["atlas.png", "voxel budget"]);
    assert_eq!(listing(dir.path()), ["atlas.png"], "nothing is left behind");
    let stack = dir.path().join("stack");
    std::fs::create_dir(&stack).unwrap();
    std::fs::write(stack.join("z0000.png"), lying_png(1 << 20, 1 << 20)).unwrap();
    assert_fails(&solidtex(&["info", &stack.to_string_lossy()]), &["z0000.png", "voxel budget"]);
    let photo = dir.path().join("photo.png");
    std::fs::write(&photo, lying_png(1 << 16, 1 << 16)).unwrap();
    let out = at(dir.path(), "solid.exr");
    let synth = solidtex(&["synth", &photo.to_string_lossy(), "--size", "8", "-o", &out]);
    assert_fails(&synth, &["photo.png", "too large"]);
}

/// Run `args`, killing it after `limit`; `None` when it had to be killed.
fn run_within(args: &[&str], limit: Duration) -> Option<std::process::Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_solidtex"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while start.elapsed() < limit {
        if child.try_wait().unwrap().is_some() {
            return Some(child.wait_with_output().unwrap());
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

#[test]
fn devices_and_pipes_are_refused_not_read() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.exr");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let out = at(dir.path(), "o.nrrd");
    let run = run_within(&["convert", &fifo.to_string_lossy(), &out], Duration::from_secs(30)).expect("no hang");
    assert_fails(&run, &["pipe.exr", "not a regular file"]);
    let fifo_mesh = dir.path().join("seed.obj");
    assert!(Command::new("mkfifo").arg(&fifo_mesh).status().unwrap().success());
    let v = volume_file(dir.path(), "v.exr", 4);
    let args =
        ["stamp", &v, &fifo_mesh.to_string_lossy(), "--at", "2,2,2", "--scale", "1", "--color", "0,0,0", "-o", &out];
    let stamp = run_within(&args, Duration::from_secs(30)).expect("no hang");
    assert_fails(&stamp, &["seed.obj", "not a regular file"]);
    let manifest = dir.path().join("lib.toml");
    std::fs::write(
        &manifest,
        "[[exemplar]]\nname = \"z\"\nrecipe = \"sweep\"\nimage = \"/dev/zero\"\nlength = 8\naxis = \"x\"\n\
         [[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\n",
    )
    .unwrap();
    let build = ["build", &manifest.to_string_lossy(), "-o", &at(dir.path(), "out")];
    let run = run_within(&build, Duration::from_secs(60)).expect("no hang");
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("FAILED z") && err.contains("/dev/zero") && err.contains("not a regular file"), "{err}");
    assert!(dir.path().join("out/m.exr").exists(), "the other entry is built: {err}");
}

#[test]
fn a_second_build_on_the_same_folder_stops_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("lib.toml");
    std::fs::write(&manifest, "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\n").unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join(".cache")).unwrap();
    let lock = std::fs::File::create(out.join(".cache/build.lock")).unwrap();
    lock.lock().unwrap();
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &out.to_string_lossy()]);
    assert_fails(&run, &["out", "another solidtex build"]);
    assert!(!out.join("m.exr").exists());
    lock.unlock().unwrap();
    let run = solidtex(&["build", &manifest.to_string_lossy(), "-o", &out.to_string_lossy()]);
    assert!(run.status.success(), "{}", stderr(&run));
}

#[test]
fn a_truncated_output_is_kept_and_said_never_reported_cached() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("lib.toml");
    std::fs::write(
        &manifest,
        "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\nexports = [\"slices\"]\n",
    )
    .unwrap();
    let (m, out) = (manifest.to_string_lossy().into_owned(), at(dir.path(), "out"));
    assert!(solidtex(&["build", &m, "-o", &out]).status.success());
    let exr = dir.path().join("out/m.exr");
    let whole = std::fs::read(&exr).unwrap();
    std::fs::write(&exr, &whole[..whole.len() / 2]).unwrap();
    // changed since solidtex wrote it: kept, and said, never taken as cached
    let again = solidtex(&["build", &m, "-o", &out]);
    assert!(stderr(&again).contains("0 built, 0 cached, 1 failed"), "{}", stderr(&again));
    assert!(stderr(&again).contains("m.exr") && stderr(&again).contains("changed since"), "{}", stderr(&again));
    assert_eq!(std::fs::read(&exr).unwrap().len(), whole.len() / 2);
    std::fs::remove_file(&exr).unwrap();
    let again = solidtex(&["build", &m, "-o", &out]);
    assert!(stderr(&again).contains("1 built, 0 cached"), "{}", stderr(&again));
    assert_eq!(std::fs::read(&exr).unwrap(), whole);
    std::fs::remove_file(dir.path().join("out/m_slices/z0003.png")).unwrap();
    let third = solidtex(&["build", &m, "-o", &out]);
    assert!(stderr(&third).contains("1 built, 0 cached"), "{}", stderr(&third));
    let fourth = solidtex(&["build", &m, "-o", &out]);
    assert!(stderr(&fourth).contains("0 built, 1 cached"), "{}", stderr(&fourth));
}

#[test]
fn without_a_terminal_the_tui_says_so_and_exits_2() {
    let run = run_within(&[], Duration::from_secs(30)).expect("no hang");
    let err = stderr(&run);
    assert_eq!(run.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error:") && err.contains("needs a terminal") && err.contains("solidtex build"), "{err}");
}

#[test]
fn a_latin1_vol_name_converts_to_exr_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let vol = volume_file(dir.path(), "v.vol", 4);
    let mut bytes = std::fs::read(&vol).unwrap();
    bytes[8..14].copy_from_slice(b"cr\xe8me\0");
    std::fs::write(&vol, bytes).unwrap();
    for out in ["c.exr", "c.png"] {
        let run = solidtex(&["convert", &vol, &at(dir.path(), out)]);
        assert!(run.status.success(), "{out}: {}", stderr(&run));
    }
    let back = solidtex::io::read_volume(&dir.path().join("c.exr"), u64::MAX).unwrap();
    assert_eq!(back.meta.get("name").map(|n| n.to_string()), Some("cr\u{e8}me".to_string()));
}

#[test]
fn error_lines_do_not_echo_input_without_limit() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("long.nrrd");
    let long = "x".repeat(1 << 20);
    std::fs::write(&path, format!("NRRD0004\n{long}\n\n")).unwrap();
    let run = solidtex(&["info", &path.to_string_lossy()]);
    assert_fails(&run, &["long.nrrd", "characters left out"]);
    assert!(stderr(&run).len() < 1000, "{} bytes of error", stderr(&run).len());
}

#[test]
fn an_exr_storing_more_channels_than_it_lists_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rgba = dir.path().join("rgba.exr");
    write_volume(&rgba, &random_volume([4, 4, 4], Channel::rgba(), 1)).unwrap();
    let mut bytes = std::fs::read(&rgba).unwrap();
    let at_list = bytes.windows(15).position(|w| w == b"channels: R,G,B").unwrap();
    // "R,G,B,A" -> "R,G,B  " keeps the header's length while dropping A from the list.
    bytes[at_list + 15..at_list + 17].copy_from_slice(b"  ");
    std::fs::write(&rgba, bytes).unwrap();
    assert_fails(&solidtex(&["info", &rgba.to_string_lossy()]), &["rgba.exr", "lists 3 channel(s)", "stores 4"]);
}

/// A command stopped by SIGTERM or Ctrl-C (SIGINT) while it writes removes its temporary
/// file and exits 143 or 130 (128 plus the signal), leaving no output behind.
#[cfg(unix)]
#[test]
fn a_stopped_command_leaves_no_temporary() {
    for (signal, code) in [("TERM", 143), ("INT", 130)] {
        let dir = tempfile::tempdir().unwrap();
        let output = at(dir.path(), "big.exr");
        let mut child = Command::new(env!("CARGO_BIN_EXE_solidtex"))
            .args(["make", "marble", "--size", "128", "-o", &output])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        let writing = |names: Vec<String>| names.iter().any(|n| n.starts_with(".big.exr.solidtex-"));
        while !writing(listing(dir.path())) {
            assert!(child.try_wait().unwrap().is_none(), "the command ended before it wrote");
            assert!(start.elapsed() < Duration::from_secs(120), "no temporary appeared");
            std::thread::sleep(Duration::from_millis(2));
        }
        let pid = child.id().to_string();
        assert!(Command::new("kill").args([&format!("-{signal}"), &pid]).status().unwrap().success());
        assert_eq!(child.wait().unwrap().code(), Some(code), "SIG{signal}");
        assert_eq!(listing(dir.path()), Vec::<String>::new(), "SIG{signal}: nothing is left");
    }
}

/// A name that ends like a volume file never becomes a folder: an existing folder of that
/// name is refused (left empty), and commands that write folders refuse such a name.
#[test]
fn a_file_name_never_becomes_a_folder() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = volume_file(d, "v.exr", 3);
    std::fs::create_dir(d.join("d.exr")).unwrap();
    crate::support::assert_usage(&solidtex(&["convert", &input, &at(d, "d.exr")]), &["d.exr", "is a folder"]);
    assert!(listing(&d.join("d.exr")).is_empty(), "nothing written into the folder");
    let before = listing(d);
    crate::support::assert_usage(
        &solidtex(&["mask", "layered", "--size", "8", "-o", &at(d, "lay.exr")]),
        &["lay.exr", "writes a folder", "without an extension"],
    );
    let library = Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars/library.toml");
    crate::support::assert_usage(
        &solidtex(&["draw", "cake", "-o", &at(d, "cake.exr"), "--library", &library.to_string_lossy()]),
        &["cake.exr", "writes a folder"],
    );
    assert_eq!(listing(d), before, "nothing written");
    assert!(solidtex(&["mask", "layered", "--size", "8", "-o", &format!("{}/", at(d, "lay.exr"))]).status.success());
    assert_eq!(
        listing(&d.join("lay.exr")).len(),
        4,
        "a name ending in / is a folder: {:?}",
        listing(&d.join("lay.exr"))
    );
}

/// A folder output whose writing fails (a full disk) names the file in the user's folder,
/// not the temporary folder solidtex fills first, and leaves nothing behind.
#[test]
fn a_failed_folder_write_names_the_users_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stack");
    let full = || std::io::Error::from_raw_os_error(28);
    let err = solidtex::io::atomic::write_folder(&out, |temp| {
        std::fs::write(temp.join("z0000.png"), b"one").unwrap();
        Err(solidtex::Error::io(temp.join("z0001.png"), full()))
    })
    .unwrap_err()
    .to_string();
    let named = out.join("z0001.png").to_string_lossy().into_owned();
    assert!(err.starts_with(&format!("{named}: ")) && !err.contains(".stack.solidtex-"), "{err}");
    let err = solidtex::io::atomic::write_folder(&out, |temp| {
        Err(solidtex::Error::file(temp.join("z0002.png"), "cannot write PNG: no space"))
    })
    .unwrap_err()
    .to_string();
    assert!(err.starts_with(&format!("{}: ", out.join("z0002.png").display())), "{err}");
    assert_eq!(listing(dir.path()), Vec::<String>::new());
}
