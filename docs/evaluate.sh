#!/usr/bin/env bash
# Synthesis quality on a folder of photos, against noise that has each photo's spectrum and
# colours (`solidtex noise`), and on the two 3D truths with long features.
# Usage: [SYNTH_FLAGS=...] bash docs/evaluate.sh [IMAGES_DIR] [OUT_DIR]
#   IMAGES_DIR  default ../shared/data/images (not part of the project); every *.png in it
#   OUT_DIR     default out/eval; volumes and contact sheets go there
#   SYNTH_FLAGS given to every synth run, e.g. "--core coordinates" (the truths' slices are
#               label images, which take the coordinate core unless "--core blend" is given)
# Photos whose name holds "strata" or "layered" are synthesized with --layered.
# One line per photo and per control; `check` counts the figures `quality --check` finds
# outside their bands (docs/synthesis.md, "Checking a volume"); a coordinate-core volume adds
# its coherent neighbour pairs and largest patch ("Coherent patches").
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
data=$(realpath -m "${1:-$root/../shared/data/images}")
out=$(realpath -m "${2:-$root/out/eval}")
[ -d "$data" ] || { echo "evaluate.sh: no folder $data" >&2; exit 2; }
shopt -s nullglob
images=("$data"/*.png)
[ ${#images[@]} -gt 0 ] || { echo "evaluate.sh: no PNG in $data" >&2; exit 2; }
cd "$root"
mkdir -p "$out"
cargo build --release --quiet
bin=./target/release/solidtex
read -r -a extra <<< "${SYNTH_FLAGS:-}"
summary() { # label json check-stderr seconds
  python3 - "$@" <<'PY'
import json, sys
label, report, check, took = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3], sys.argv[4]
span = lambda v: '%.2f-%.2f' % (min(v), max(v))
s = report['sharpness']
lines = [l for l in report['lines'] if l['applies']]
line = ('lines %s pieces %s top3 %s share %s' % (lines[0]['lines']['name'],
        span([l['lines']['pieces_ratio'] for l in lines]), span([l['lines']['top3_ratio'] for l in lines]),
        span([l['lines']['share_ratio'] for l in lines]))) if lines else 'no line structure'
outside = check.split(' figure')[0].split()[-1] if 'outside' in check else '0'
p = report.get('patches')
patches = '  coherent %.2f largest %.3f' % (p['coherent_pairs'], p['largest']) if p else ''
print('%-34s %6ss  gradient %s  length %s  %s  check %s%s' % (label, took, span([a['gradient_ratio'] for a in s]),
      span([a['length_ratio'] for a in s]), line, outside, patches))
PY
}
measure() { # label volume exemplar-args... ; prints the summary line
  local label=$1 volume=$2 took=$3; shift 3
  local json check
  json=$($bin quality "$volume" "$@" --json --check 2>"$out/check.txt") || true
  check=$(grep -E 'outside their bands \(|every figure is within' "$out/check.txt" || true)
  if [ -z "$json" ] || [ -z "$check" ]; then
    echo "evaluate.sh: quality failed on $volume:" >&2; cat "$out/check.txt" >&2; exit 1
  fi
  summary "$label" "$json" "$check" "$took"
}
for image in "${images[@]}"; do
  name=$(basename "$image" .png)
  flags="" size=64
  case "$name" in *strata*|*layered*) flags="--layered"; size=64x64x128 ;; esac
  started=$(date +%s.%N)
  $bin synth "$image" $flags ${extra[@]+"${extra[@]}"} --max-exemplar 128 --size $size --seed 1 -o "$out/$name.exr" 2>/dev/null
  took=$(printf '%.1f' "$(echo "$(date +%s.%N) - $started" | bc)")
  $bin sheet "$out/$name.exr" -o "$out/$name.sheet.png" --title "$name" 2>/dev/null
  measure "$name synth" "$out/$name.exr" "$took" --exemplar "$image" --max-exemplar 128
  if [ -z "$flags" ]; then
    $bin noise "$image" --max-exemplar 128 --size 64 --seed 1 -o "$out/$name.noise.exr" 2>/dev/null
    measure "$name noise" "$out/$name.noise.exr" - --exemplar "$image" --max-exemplar 128
  fi
done
# The truths: synthesis and noise from their central slices, measured against the slices
# and, as label volumes, against the truth itself.
for truth in foam:1 channels:3; do
  name=${truth%:*} seed=${truth#*:}
  $bin make "$name" --size 128 --seed "$seed" -o "$out/$name.truth.exr" 2>/dev/null
  for axis in x y z; do $bin slice "$out/$name.truth.exr" --axis $axis -o "$out/$name-$axis.png" 2>/dev/null; done
  slices=(--exemplar "$out/$name-x.png" --ey "$out/$name-y.png" --ez "$out/$name-z.png")
  measure "$name truth" "$out/$name.truth.exr" - "${slices[@]}"
  started=$(date +%s.%N)
  $bin synth "$out/$name-x.png" --ey "$out/$name-y.png" --ez "$out/$name-z.png" ${extra[@]+"${extra[@]}"} --size 64 --seed 1 \
    -o "$out/$name.exr" 2>/dev/null
  took=$(printf '%.1f' "$(echo "$(date +%s.%N) - $started" | bc)")
  $bin noise "$out/$name-x.png" --ey "$out/$name-y.png" --ez "$out/$name-z.png" --size 64 --seed 1 -o "$out/$name.noise.exr" 2>/dev/null
  for kind in synth noise; do
    volume="$out/$name.exr"; [ $kind = noise ] && volume="$out/$name.noise.exr"
    measure "$name $kind" "$volume" "$([ $kind = synth ] && echo "$took" || echo -)" "${slices[@]}"
    $bin quality "$volume" --labels --truth "$out/$name.truth.exr" --json 2>/dev/null | python3 -c "
import json, sys
r = json.load(sys.stdin)
fmt = lambda v: '-' if v is None else '%.2f' % v
for p, t in zip(r['ratios'], r['truth']['phases']):
    print('    phase %.3f (share %.2f): share %.2f  pieces %.2f  correlation length %s' % (p['label'], t['share'],
          p['share_ratio'], p['pieces_ratio'], ' / '.join(fmt(c) for c in p['correlation_ratio'])))
"
  done
done
rm -f "$out/check.txt"
