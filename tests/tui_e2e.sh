#!/usr/bin/env bash
# End-to-end: drive the real terminal UI in tmux (send-keys, capture-pane).
# Usage: bash tests/tui_e2e.sh path/to/solidtex
set -euo pipefail
bin=$(realpath "$1")
if ! command -v tmux >/dev/null; then
  (apt-get install -y tmux >/dev/null 2>&1 || (apt-get update >/dev/null 2>&1 && apt-get install -y tmux >/dev/null 2>&1)) || true
fi
if ! command -v tmux >/dev/null; then
  echo "tui e2e: skipped (tmux could not be installed)"
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
tmux new-session -d -s "$session" -x 100 -y 30 "$bin tui exemplars/library.toml -o $out"
wait_for "solidtex library: exemplars/library.toml" 10
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
tmux send-keys -t "$session" Escape
wait_for "solidtex library" 5
tmux send-keys -t "$session" q
sleep 0.5
if tmux has-session -t "$session" 2>/dev/null; then echo "tui e2e: q did not quit"; exit 1; fi
echo "e2e: 1 passed, 0 failed"
