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
wait_for() { # text, seconds
  for _ in $(seq 1 $(( $2 * 10 ))); do screen | grep -q "$1" && return 0; sleep 0.1; done
  echo "tui e2e: never saw '$1'; the screen was:"; screen; exit 1
}
# a copy of the default library, so the editor can save into it
cp -r exemplars "$out/lib"
tmux new-session -d -s "$session" -x 100 -y 30 "$bin tui $out/lib/library.toml -o $out/built"
wait_for "solidtex library: .*library.toml" 10
wait_for "not built" 5
tmux send-keys -t "$session" b
wait_for "built marble (measured type 0)" 60
tmux send-keys -t "$session" Enter
wait_for "XY z=32/63 colour" 10
tmux send-keys -t "$session" x Right Right
wait_for "YZ x=34/63" 5
tmux send-keys -t "$session" '?'
wait_for "cycle colour" 5
tmux send-keys -t "$session" Escape
sleep 0.5
# fill preview: a shape filled with marble, the cut moved
tmux send-keys -t "$session" f
wait_for "fill preview: marble" 5
wait_for "patches" 60
tmux send-keys -t "$session" PageUp z
wait_for "cut across z at +0.00" 5
tmux send-keys -t "$session" Right
wait_for "cut across z at +0.05" 5
tmux send-keys -t "$session" Escape
wait_for "back to marble" 5
tmux send-keys -t "$session" Escape
wait_for "solidtex library" 5
# recipe editor: size 64 -> 32 (validated, previewed), saved with the comments kept
tmux send-keys -t "$session" e
wait_for "recipe: marble" 10
wait_for "size = 64" 10
tmux send-keys -t "$session" Down Down Enter BSpace BSpace 0 Enter
wait_for "out of range" 5
tmux send-keys -t "$session" BSpace 3 2 Enter
wait_for "recipe: marble \[modified\]" 5
wait_for "preview (low resolution)" 20
tmux send-keys -t "$session" u
wait_for "undone" 5
tmux send-keys -t "$session" r s
wait_for "saved" 5
grep -q "^size = 32" "$out/lib/library.toml" || { echo "tui e2e: the edit was not saved"; exit 1; }
grep -q "^# The default exemplar library" "$out/lib/library.toml" || { echo "tui e2e: comments were lost"; exit 1; }
tmux send-keys -t "$session" Escape
wait_for "solidtex library" 5
# stamp mode: a seed moved, stamped and saved as a manifest step
tmux send-keys -t "$session" Enter
wait_for "XY z=" 10
tmux send-keys -t "$session" m
wait_for "stamp mode (kiwi_seed.obj)" 10
tmux send-keys -t "$session" Right Right r + Enter
wait_for "stamped" 5
tmux send-keys -t "$session" s
wait_for "saved the steps" 5
grep -q '^  stamp = "kiwi_seed.obj"' "$out/lib/library.toml" || { echo "tui e2e: the stamp step was not saved"; exit 1; }
tmux send-keys -t "$session" Escape
wait_for "solidtex library" 5
# b. a build cancelled mid-synthesis says so and keeps the previous output byte for byte
tmux send-keys -t "$session" Up Up Up Down Down Down Down Down Down b
wait_for "built marble-synth" 120
before=$(md5sum < "$out/built/marble-synth.exr")
sed -i '/^name = "marble-synth"/,/^seed/{s/^size = 32/size = 64/;s/^levels = 2/levels = 3/;s/^seed = 1/seed = 2/}' "$out/lib/library.toml"
tmux send-keys -t "$session" b
wait_for "level 3/3" 60
tmux send-keys -t "$session" Escape
wait_for "cancelled marble-synth: its previous output is kept" 10
[ "$(md5sum < "$out/built/marble-synth.exr")" = "$before" ] || { echo "tui e2e: the cancelled build replaced the output"; exit 1; }
screen | grep -q "marble-synth.*changed since built" || { echo "tui e2e: the cancelled entry is not marked changed"; screen; exit 1; }
# c. Esc on the idle library does not quit; q with unsaved edits asks first
tmux send-keys -t "$session" Escape
sleep 0.5
tmux has-session -t "$session" 2>/dev/null || { echo "tui e2e: Esc on the library quit"; exit 1; }
tmux send-keys -t "$session" Up Up Up Up Up Up e
wait_for "recipe: marble" 10
wait_for "seed = 3" 10
tmux send-keys -t "$session" Down Down Down Enter BSpace 2 Enter
wait_for "recipe: marble \[modified\]" 5
tmux send-keys -t "$session" q
wait_for "q again quits without saving" 5
tmux send-keys -t "$session" q
sleep 0.5
if tmux has-session -t "$session" 2>/dev/null; then echo "tui e2e: q did not quit"; exit 1; fi

# a, e. At 80x24: a stamp at x > 31 saved into the kiwi, then the editor's preview of the
# kiwi is not stale, and its build warning stays in the status line, not over the screen.
tmux new-session -d -s "$session" -x 80 -y 24 "$bin tui $out/lib/library.toml -o $out/built"
wait_for "solidtex library" 10
# i. entries edited since their build are found stale when the UI opens, with the reason
wait_for "changed since their last build (select one to see why)" 5
tmux send-keys -t "$session" Down Up
wait_for "marble changed since its last build (the recipe changed)" 5
tmux send-keys -t "$session" Down Down Down b
wait_for "built kiwi" 60
tmux send-keys -t "$session" Enter
wait_for "XY z=32/63" 10
tmux send-keys -t "$session" m
wait_for "stamp mode" 10
tmux send-keys -t "$session" Right Right Right Enter
wait_for "stamped" 5
tmux send-keys -t "$session" Escape
wait_for "unsaved stamps" 5
tmux send-keys -t "$session" s
wait_for "saved the steps" 5
tmux send-keys -t "$session" Escape
wait_for "solidtex library" 5
sed -i 's/^  count = 60$/  count = 400/' "$out/lib/library.toml"
tmux send-keys -t "$session" e
wait_for "recipe: kiwi" 10
wait_for "no room for the rest" 60
if screen | grep -q "stale"; then echo "tui e2e: the preview after a stamp at x > 31 is stale"; screen; exit 1; fi
if screen | head -n 18 | grep -q "no room"; then echo "tui e2e: a warning was printed over the screen"; screen; exit 1; fi
screen | head -n 1 | grep -q "recipe: kiwi" || { echo "tui e2e: the top border was overwritten"; screen; exit 1; }
tmux kill-session -t "$session"

# d. A manifest with two broken entries: both errors listed, B builds the valid ones, a
# broken entry opens in the editor.
cp tests/manifests/two-broken.toml "$out/lib/broken.toml"
tmux new-session -d -s "$session" -x 80 -y 24 "$bin tui $out/lib/broken.toml -o $out/broken"
wait_for "the manifest has 2 error" 10
wait_for "broken1" 5
screen | grep -q "size" && screen | grep -q "weave" || { echo "tui e2e: not every error is shown"; screen; exit 1; }
tmux send-keys -t "$session" B
wait_for "built b" 60
[ -f "$out/broken/a.exr" ] && [ -f "$out/broken/b.exr" ] || { echo "tui e2e: B did not build the valid entries"; exit 1; }
tmux send-keys -t "$session" Up Up Up Down Down Down e
wait_for "recipe: broken2" 10
tmux send-keys -t "$session" Escape
wait_for "solidtex library" 5
tmux send-keys -t "$session" q
sleep 0.5
if tmux has-session -t "$session" 2>/dev/null; then echo "tui e2e: q did not quit"; exit 1; fi
echo "e2e: 1 passed, 0 failed"
