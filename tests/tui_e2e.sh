#!/usr/bin/env bash
# End-to-end: drive the real terminal UI in tmux (send-keys, capture-pane).
# Usage: bash tests/tui_e2e.sh path/to/solidtex
set -euo pipefail
bin=$(realpath "$1")
if ! command -v tmux >/dev/null; then
  (apt-get install -y tmux >/dev/null 2>&1 || (apt-get update >/dev/null 2>&1 && apt-get install -y tmux >/dev/null 2>&1)) || true
fi
if ! command -v tmux >/dev/null; then
  if [ -n "${CI:-}" ]; then
    echo "tui e2e: FAILED: tmux could not be installed, and CI must run this test"
    exit 1
  fi
  echo "tui e2e: SKIPPED: tmux could not be installed (install it to run this test)"
  exit 0
fi
out=$(mktemp -d)
session=solidtex-e2e-$$
cleanup() { tmux kill-session -t "$session" 2>/dev/null || true; rm -rf "$out"; }
trap cleanup EXIT
screen() { tmux capture-pane -t "$session" -p; }
wait_for() { # text, seconds (also found when the status line wraps it)
  for _ in $(seq 1 $(( $2 * 10 ))); do
    screen | grep -q "$1" && return 0
    screen | sed 's/ *? help  M log  q quit$//' | tr '\n' ' ' | tr -s ' ' | grep -q "$1" && return 0
    sleep 0.1
  done
  echo "tui e2e: never saw '$1'; the screen was:"; screen; exit 1
}
quits() { # seconds: whether the session ends within them (a loaded machine is slow to exit)
  for _ in $(seq 1 $(( $1 * 10 ))); do
    tmux has-session -t "$session" 2>/dev/null || return 0
    sleep 0.1
  done
  return 1
}
press() { # text, seconds, keys...: send the keys, then wait for the screen they lead to
  local text=$1 seconds=$2; shift 2
  tmux send-keys -t "$session" "$@"
  wait_for "$text" "$seconds"
}
# a copy of the default library, so the editor can save into it
cp -r exemplars "$out/lib"
tmux new-session -d -s "$session" -x 100 -y 30 "$bin tui $out/lib/library.toml -o $out/built"
wait_for "solidtex library: .*library.toml" 10
wait_for "not built" 5
press "built marble (measured type 0)" 60 b
press "XY z=32/63 colour" 10 Enter
press "YZ x=34/63" 5 x Right Right
press "keys: slices" 5 '?'
wait_for "cycle colour" 5
# the help's search: only the matching keys stay; f does not open a fill under the help
press "/zoom_" 5 / z o o m
screen | grep -q "cycle colour" && { echo "tui e2e: the search kept a key without 'zoom'"; screen; exit 1; }
press "/zoom  (/ changes it" 5 Enter
tmux send-keys -t "$session" f
sleep 0.3
screen | grep -q "fill: marble" && { echo "tui e2e: f acted under the help"; screen; exit 1; }
press "/ search  esc close" 5 Escape
tmux send-keys -t "$session" Escape
sleep 0.5
# E exports the exemplar: every format, its contact sheet and the slice on screen
press "exported 8 files" 30 E
for f in marble.exr marble.nrrd marble.vol marble.vdb marble.dds marble.png marble.sheet.png marble.slice-x34.png; do
  [ -s "$out/built/exports/marble/$f" ] || { echo "tui e2e: the export lacks $f"; ls "$out/built/exports/marble"; exit 1; }
done
# fill preview: a shape filled with marble, the cut moved
press "fill: marble" 5 f
wait_for "tets, [0-9]* patches" 60
press "cut z +0.00" 5 PageUp z
press "cut z +0.05" 5 Right
# E exports the cut as a PNG; a second export never replaces the first
press "marble.fill-cut-z+0.05.png" 30 E
press "marble.fill-cut-z+0.05-2.png" 30 E
for f in marble.fill-cut-z+0.05.png marble.fill-cut-z+0.05-2.png; do
  [ -s "$out/built/exports/$f" ] || { echo "tui e2e: the cut export lacks $f"; ls "$out/built/exports"; exit 1; }
done
press "back to marble" 5 Escape
press "solidtex library" 5 Escape
# recipe editor: size 64 -> 32 (validated, previewed), saved with the comments kept
press "recipe: marble" 10 e
wait_for "size = 64" 10
press "out of range" 5 Down Down Enter BSpace BSpace 0 Enter
press "recipe: marble \[modified\]" 5 BSpace 3 2 Enter
wait_for "preview (low resolution)" 20
press "undone" 5 u
press "saved" 5 r s
grep -q "^size = 32" "$out/lib/library.toml" || { echo "tui e2e: the edit was not saved"; exit 1; }
grep -q "^# The default exemplar library" "$out/lib/library.toml" || { echo "tui e2e: comments were lost"; exit 1; }
press "solidtex library" 5 Escape
# stamp mode: a seed moved, stamped and saved as a manifest step
press "XY z=" 10 Enter
press "stamp mode (bubble.obj)" 10 m
press "stamped" 5 Right Right r + Enter
press "saved the steps" 5 s
grep -q '^  stamp = "bubble.obj"' "$out/lib/library.toml" || { echo "tui e2e: the stamp step was not saved"; exit 1; }
press "solidtex library" 5 Escape
# b. a build cancelled mid-synthesis says so and keeps the previous output byte for byte
press "built marble-synth" 120 Up Up Up Down Down Down Down Down Down b
before=$(md5sum < "$out/built/marble-synth.exr")
sed -i '/^name = "marble-synth"/,/^seed/{s/^size = 32/size = 64/;s/^levels = 2/levels = 3/;s/^seed = 1/seed = 2/}' "$out/lib/library.toml"
press "level 3/3" 60 b
press "cancelled marble-synth: its previous output is kept" 10 Escape
[ "$(md5sum < "$out/built/marble-synth.exr")" = "$before" ] || { echo "tui e2e: the cancelled build replaced the output"; exit 1; }
screen | grep -q "marble-synth.*changed since built" || { echo "tui e2e: the cancelled entry is not marked changed"; screen; exit 1; }
# c. Esc on the idle library does not quit; q with unsaved edits asks first
tmux send-keys -t "$session" Escape
sleep 0.5
tmux has-session -t "$session" 2>/dev/null || { echo "tui e2e: Esc on the library quit"; exit 1; }
press "recipe: marble" 10 Up Up Up Up Up Up e
wait_for "seed = 3" 10
press "recipe: marble \[modified\]" 5 Down Down Down Enter BSpace 2 Enter
press "q again quits without saving" 5 q
tmux send-keys -t "$session" q
quits 5 || { echo "tui e2e: q did not quit"; exit 1; }

# a, e. At 80x24: a stamp at x > 31 saved into the kiwi, then the editor's preview of the
# kiwi is not stale, and its build warning stays in the status line, not over the screen.
tmux new-session -d -s "$session" -x 80 -y 24 "$bin tui $out/lib/library.toml -o $out/built"
wait_for "solidtex library" 10
# i. entries edited since their build are found stale when the UI opens, with the reason
wait_for "changed since their last build (select one to see why)" 5
press "marble changed since its last build (the recipe changed)" 5 Down Up
# R builds the changed entries and those never built, with done/total, elapsed time and an
# estimate; esc cancels what is left
press "building 1/[0-9]* · 0:0" 10 R
for _ in $(seq 1 1200); do screen | grep -q "waiting (queued)\|level [0-9]/\|building" || break; sleep 0.1; done
screen | grep -q "changed since built\|not built" && { echo "tui e2e: R left a changed or unbuilt entry"; screen; exit 1; }
screen | grep -q "^│marble  *32x32x32 .*built" || { echo "tui e2e: R did not build marble"; screen; exit 1; }
press "built kiwi" 60 Down Down Down b
press "XY z=32/63" 10 Enter
# k. constraints on the fill preview's cut: a depth point, the depth map, a refill, the spec
# written and run by `solidtex fill`
press "fill: kiwi" 5 f
wait_for "tets, [0-9]* patches" 120
press "depth 0.50 at" 5 L L L L '[' '[' d
press "the depth field" 5 c
press "filling again with 1 stroke" 5 r
wait_for "tets, [0-9]* patches" 120
press "kiwi.fill.toml, kiwi.fill-fruit.obj" 10 w
grep -q '^points = \[\[' "$out/built/exports/kiwi.fill.toml" || { echo "tui e2e: the depth point is not in the spec"; cat "$out/built/exports/kiwi.fill.toml"; exit 1; }
(cd "$out/built/exports" && "$bin" fill kiwi.fill-fruit.obj --spec kiwi.fill.toml -o kiwi.lst >/dev/null 2>&1) || { echo "tui e2e: solidtex fill refused the written spec"; exit 1; }
press "back to kiwi" 5 Escape
press "stamp mode" 10 m
press "stamped" 5 Right Right Right Enter
press "unsaved stamps" 5 Escape
press "saved the steps" 5 s
press "solidtex library" 5 Escape
sed -i 's/^  count = 280$/  count = 600/' "$out/lib/library.toml"
press "recipe: kiwi" 10 e
wait_for "preview: placed [0-9]* of [0-9]* seeds" 60
if screen | grep -q "stale"; then echo "tui e2e: the preview after a stamp at x > 31 is stale"; screen; exit 1; fi
if screen | head -n 18 | grep -q "placed [0-9]* of"; then echo "tui e2e: a warning was printed over the screen"; screen; exit 1; fi
screen | head -n 1 | grep -q "recipe: kiwi" || { echo "tui e2e: the top border was overwritten"; screen; exit 1; }
# closing the terminal (SIGHUP) ends the UI
tmux kill-session -t "$session"
sleep 1
if pgrep -f "tui $out/lib/library.toml -o $out/built" >/dev/null; then echo "tui e2e: the UI outlived its terminal"; exit 1; fi

# d. A manifest with two broken entries: both errors listed, B builds the valid ones, a
# broken entry opens in the editor.
cp tests/manifests/two-broken.toml "$out/lib/broken.toml"
tmux new-session -d -s "$session" -x 80 -y 24 "$bin tui $out/lib/broken.toml -o $out/broken"
wait_for "the manifest has 2 error" 10
wait_for "broken1" 5
screen | grep -q "size" && screen | grep -q "weave" || { echo "tui e2e: not every error is shown"; screen; exit 1; }
press "built b" 60 B
[ -f "$out/broken/a.exr" ] && [ -f "$out/broken/b.exr" ] || { echo "tui e2e: B did not build the valid entries"; exit 1; }
press "recipe: broken2" 10 Up Up Up Down Down Down e
press "solidtex library" 5 Escape
# f. c copies an entry into the manifest, d twice deletes it: the file comes back byte for byte
press "copied b as b-2" 10 Up c
grep -q '^name = "b-2"' "$out/lib/broken.toml" || { echo "tui e2e: the copy is not in the manifest"; exit 1; }
press "d again deletes b-2" 5 d
press "deleted b-2" 10 d
cmp -s "$out/lib/broken.toml" tests/manifests/two-broken.toml || { echo "tui e2e: copy then delete changed the manifest"; diff "$out/lib/broken.toml" tests/manifests/two-broken.toml; exit 1; }
# g. the editor adds a blur step at the centre (a), saved; x removes it again
press "recipe: b[^r]" 10 Up e
wait_for "size = 8" 10
press "added a blur at 4,4,4" 10 a
press "saved" 10 s
grep -q '^  blur = "4,4,4"' "$out/lib/broken.toml" || { echo "tui e2e: the blur step was not saved"; exit 1; }
press "removed step 1" 10 x
press "saved" 10 s
cmp -s "$out/lib/broken.toml" tests/manifests/two-broken.toml || { echo "tui e2e: adding then removing a step changed the manifest"; diff "$out/lib/broken.toml" tests/manifests/two-broken.toml; exit 1; }
press "solidtex library" 5 Escape
# h. r renames the entry (a taken name refused with the reason); renaming it back gives the
# file back byte for byte
press "new name: b_" 5 r
press "new name: a_  refused: the manifest already has" 10 C-u a Enter
press "the name stays" 5 Escape
press "new name: b_" 5 r
press "renamed b to bark" 10 C-u b a r k Enter
grep -q '^name = "bark"' "$out/lib/broken.toml" || { echo "tui e2e: the new name is not in the manifest"; exit 1; }
press "new name: bark_" 5 r
press "renamed bark to b" 10 C-u b Enter
cmp -s "$out/lib/broken.toml" tests/manifests/two-broken.toml || { echo "tui e2e: renaming back changed the manifest"; diff "$out/lib/broken.toml" tests/manifests/two-broken.toml; exit 1; }
# j. n makes an entry from a photo chosen in the picker: appended, the rest byte for byte
press "new exemplar: what makes it" 5 n
press "brick_photo.png" 10 Enter
press "gravel_photo.png (shown" 10 Down Down Down Down
press "added gravel_photo (synth from" 10 Enter
size=$(wc -c < tests/manifests/two-broken.toml)
head -c "$size" "$out/lib/broken.toml" | cmp -s - tests/manifests/two-broken.toml || { echo "tui e2e: adding an entry changed the others"; diff "$out/lib/broken.toml" tests/manifests/two-broken.toml; exit 1; }
tail -c +"$((size + 1))" "$out/lib/broken.toml" | grep -q '^image = "gravel_photo.png"$' || { echo "tui e2e: the new entry is not at the end"; cat "$out/lib/broken.toml"; exit 1; }
# built small (the debug binary synthesizes slowly), its figures at a glance, its photo beside a slice
sed -i '/^name = "gravel_photo"/,/^seed/{s/^max_exemplar = 128/max_exemplar = 32/;s/^size = 64/size = 16\nlevels = 2/}' "$out/lib/broken.toml"
press "built gravel_photo" 120 b
wait_for "gravel_photo: sharp" 5
press "XY z=" 10 Enter
press "gravel_photo across z: sharp" 10 p
press "photo 32x32" 10 y
press "solidtex library" 5 Escape
# v marks it, v on another built entry shows both side by side
press "gravel_photo marked" 5 v
press "gravel_photo | b  across z" 10 Up Up v
press "solidtex library" 5 Escape
# a rebuild keeps the previous build; V compares them, d brings the previous back
before=$(md5sum < "$out/broken/gravel_photo.exr")
sed -i '/^name = "gravel_photo"/,/^seed/{s/^seed = 1/seed = 2/}' "$out/lib/broken.toml"
press "built; previous kept" 120 Down Down b
press "gravel_photo before | gravel_photo after" 10 V
press "previous build again" 10 d
[ "$(md5sum < "$out/broken/gravel_photo.exr")" = "$before" ] || { echo "tui e2e: d did not bring the previous build back"; exit 1; }
[ ! -e "$out/broken/.cache/previous/gravel_photo" ] || { echo "tui e2e: the kept copy stayed after d"; exit 1; }
tmux send-keys -t "$session" q
quits 5 || { echo "tui e2e: q did not quit"; exit 1; }
# l. Work is never lost (80x24): outside edits survive an editor save, a deletion is undone
# onto the file as it reads now, a failed rebuild keeps the last good volume, `b` keeps the
# report's other rows, the fill preview asks before dropping constraints and loads a written
# spec back, a panicking build leaves the UI running, the terminal is restored after q and
# after SIGTERM, and a read-only manifest is saved under another name.
lib="$out/safe/library.toml"
cp -r exemplars "$out/safe"
cp "$out/safe/kiwi_section.png" "$out/safe/tile.png"
printf '\n[[exemplar]]\nname = "tile"\nrecipe = "sweep"\nimage = "tile.png"\nlength = 16\naxis = "x"\ndepth_axis = "z"\n' >> "$lib"
tmux new-session -d -s "$session" -x 80 -y 24 bash --norc
tmux send-keys -t "$session" "SOLIDTEX_TEST_PANIC=strata $bin tui $lib -o $out/safe-built" Enter
wait_for "solidtex library" 10
press "recipe: marble" 10 e
wait_for "size = 64" 10
sed -i 's/^# out\/NAME.exr (the volume)/# out\/NAME.exr (the volume; noted outside)/; /^name = "wood"/,/^seed/{s/^seed = 3/seed = 44/}' "$lib"
printf '\n[[exemplar]]\nname = "outside"\nrecipe = "procedural:wood"\nsize = 16\n' >> "$lib"
wait_for "changed on disk: Ctrl-R reloads" 5
press "recipe: marble \[modified\]" 5 Down Down Enter BSpace BSpace 3 2 Enter
press "with the file's other changes kept" 10 s
sed -n '/^name = "marble"/,/^seed/p' "$lib" | grep -q '^size = 32' || { echo "tui e2e: the editor's change was not saved"; cat "$lib"; exit 1; }
grep -q 'noted outside' "$lib" && grep -q '^name = "outside"' "$lib" && sed -n '/^name = "wood"/,/^seed/p' "$lib" | grep -q '^seed = 44' || { echo "tui e2e: the save lost an outside edit"; cat "$lib"; exit 1; }
# the entry changed on disk too: asked, both shown, mine kept
press "recipe: marble \[modified\]" 5 Down Enter BSpace 9 Enter
sed -i '/^name = "marble"/,/^seed/{s/^seed = 3/seed = 5/}' "$lib"
press "m keeps yours, t takes the file's" 10 s
press "yours (m keeps it)" 5 b
press "saved" 10 m
sed -n '/^name = "marble"/,/^seed/p' "$lib" | grep -q '^seed = 9' || { echo "tui e2e: m did not keep mine"; cat "$lib"; exit 1; }
press "solidtex library" 5 Escape
# delete an entry, edit the file outside, u: the entry is back and the outside edit stays
press "d again deletes strata" 5 Down d
press "deleted strata" 10 d
sed -i 's/^size = 16$/size = 20/' "$lib"
press "undid the deletion of strata" 10 u
grep -q '^name = "strata"' "$lib" && grep -q '^size = 20' "$lib" || { echo "tui e2e: undo lost strata or the outside edit"; cat "$lib"; exit 1; }
# a panicking build: the entry fails with the reason, the UI goes on
press "strata failed: internal error" 60 Up Up Up Up Up Up Down b
screen | grep -q "panicked at" && { echo "tui e2e: the panic was printed over the screen"; screen; exit 1; }
press "built marble" 60 Up b
# a failed rebuild keeps the last good volume; b on one entry keeps the other rows
n=$(grep -c '^name = ' "$lib")
press "built tile" 120 $(for _ in $(seq 1 13); do printf 'Down '; done) b
[ "$(grep -c '^| ' "$out/safe-built/report.md")" -eq $((n + 1)) ] && grep -q '^| marble | .*earlier build' "$out/safe-built/report.md" || { echo "tui e2e: b on one entry dropped report rows"; cat "$out/safe-built/report.md"; exit 1; }
rm "$out/safe/tile.png"
press "its earlier build stays" 60 b
press "tile (earlier build: the latest failed)" 10 Enter
press "solidtex library" 5 Escape
# the fill preview asks before dropping a depth point; type 0 says it ignores it
press "fill: marble" 10 $(for _ in $(seq 1 20); do printf 'Up '; done) Enter f
wait_for "tets, [0-9]* patches" 120
press ".depth. is not used by type 0" 5 d
press "q again quits without saving; unsaved fill" 5 q
press "esc again leaves without saving" 5 Escape
press "q again quits without saving" 5 C-c
press "marble.fill.toml" 10 w
press "undone" 5 u
press "unsaved fill constraints" 5 Escape
press "choose a fill spec" 5 o
wait_for "marble.fill.toml" 5
press "loaded 1 stroke(s), 1 depth point(s)" 10 Down Enter
press "back to marble" 5 Escape
press "solidtex library" 5 Escape
tmux send-keys -t "$session" q
sleep 1
tmux send-keys -t "$session" "stty -a | tr ' ' '\n' | grep -x -e -icanon -e icanon -e -echo -e echo | tr '\n' ' '; echo END" Enter
press "icanon echo END" 10
# SIGTERM: the terminal comes back too
tmux send-keys -t "$session" "clear; chmod a-w $lib; $bin tui $lib -o $out/safe-built" Enter
wait_for "(read-only)" 10
press "recipe: marble" 10 e
wait_for "size = 32" 10
press "recipe: marble \[modified\]" 5 Down Down Enter BSpace BSpace 1 6 Enter
press "is read-only" 10 s
press "save as: .*library-2.toml" 5 S
press "saved as .*library-2.toml" 10 Enter
sed -n '/^name = "marble"/,/^seed/p' "$out/safe/library-2.toml" | grep -q '^size = 16' && sed -n '/^name = "marble"/,/^seed/p' "$lib" | grep -q '^size = 32' || { echo "tui e2e: save-as wrote the wrong file"; exit 1; }
pkill -TERM -f "tui $lib" || true
sleep 1
tmux send-keys -t "$session" "stty -a | tr ' ' '\n' | grep -x -e -icanon -e icanon -e -echo -e echo | tr '\n' ' '; echo END" Enter
press "icanon echo END" 10
tmux kill-session -t "$session"
# l. At 80x24, no text editor needed: the help scrolls to its last section; a field added
# through the picker and one through $EDITOR (a scripted editor that adds a line after the
# entry's name); a 128³ synthesis shows its progress moving at least every 3 s (release).
fresh="$out/fresh"
mkdir -p "$fresh" && cp -r exemplars/. "$fresh/"
cat > "$out/editor.sh" <<'EOS'
#!/bin/sh
# called as `editor.sh +LINE FILE`, as vi would be
line=${1#+}
sed -i "${line}a mask_falloff = 0.1" "$2"
EOS
chmod +x "$out/editor.sh"
tmux new-session -d -s "$session" -x 80 -y 24 "EDITOR=$out/editor.sh $bin tui $fresh/library.toml -o $out/fresh-built"
wait_for "solidtex library" 10
press "keys: library" 5 '?'
screen | grep -q "quit (asks if work is unsaved)" && { echo "tui e2e: the help fit without scrolling"; screen; exit 1; }
press "quit (asks if work is unsaved)" 5 G
press "solidtex library" 5 Escape
press "recipe: marble" 10 e
wait_for "seed = 3" 10
press "add a field: enter adds it" 5 +
press 'exports = \["nrrd"\]_' 5 G Enter
press "recipe: marble \[modified\]" 5 Enter
press "saved" 10 s
press "mask_falloff = 0.1" 10 o
sed -n '/^name = "marble"$/,/^seed/p' "$fresh/library.toml" | grep -q '^mask_falloff = 0.1' || { echo "tui e2e: the outside editor's field is missing"; cat "$fresh/library.toml"; exit 1; }
sed -n '/^name = "marble"$/,/^\[\[/p' "$fresh/library.toml" | grep -q '^exports = \["nrrd"\]' || { echo "tui e2e: the picked field was not saved"; cat "$fresh/library.toml"; exit 1; }
press "solidtex library" 5 Escape
# a release binary builds at 128³ and its gauge may stand still 3 s at most; the debug
# binary CI tests with is ten times slower: 64³ and 10 s
case "$bin" in
  */debug/*) side=64 stall=100 ;;
  *) side=128 stall=30 ;;
esac
sed -i "/^name = \"marble-synth\"/,/^seed/{s/^size = 32/size = $side/;s/^levels = 2/levels = 3/}" "$fresh/library.toml"
press "read .* again" 10 C-r
press "filter \"marble-s\" (1 of 13)" 10 /marble-s Enter
tmux send-keys -t "$session" b
# a dimmed key that does nothing says why
wait_for "marble-synth .*level [0-9]/3" 120
press "b build: building" 10 b
last="" still=0 seen=0
for _ in $(seq 1 3000); do
  row=$(screen | grep "^│marble-synth" || true)
  case "$row" in *built*|*failed*) break ;; esac
  gauge=$(printf '%s' "$row" | grep -o 'level [0-9]/[0-9] [#-]* [0-9]*%' || true)
  if [ -n "$gauge" ] && [ "$gauge" = "$last" ]; then still=$((still + 1)); else still=0; fi
  [ -n "$gauge" ] && seen=$((seen + 1))
  [ "$still" -gt "$stall" ] && { echo "tui e2e: the $side³ build's progress stood at '$gauge' for over $((stall / 10)) s"; screen; exit 1; }
  last=$gauge
  sleep 0.1
done
[ "$seen" -gt 10 ] || { echo "tui e2e: no progress gauge seen during the 128³ build"; screen; exit 1; }
wait_for "built marble-synth" 300
tmux send-keys -t "$session" q
sleep 1
tmux kill-session -t "$session" 2>/dev/null || true
echo "e2e: 1 passed, 0 failed"
