#!/usr/bin/env bash
# Synthesis quality on the real images in ../shared/data/images (not part of the project).
# Usage: bash docs/evaluate.sh [OUT_DIR]   (default out/eval). Prints one line per exemplar.
set -euo pipefail
cd "$(dirname "$0")/.."
data=../shared/data/images
out=${1:-out/eval}
mkdir -p "$out"
cargo build --release --quiet
bin=./target/release/solidtex
row() { # name image mode
  local name=$1 image=$data/$2 mode=$3 flags=""
  [ "$mode" = layered ] && flags="--layered"
  local size=64; [ "$mode" = layered ] && size=64x64x128
  local started=$(date +%s.%N)
  $bin synth "$image" $flags --max-exemplar 128 --size $size --seed 1 -o "$out/$name.exr" 2>/dev/null
  local took=$(echo "$(date +%s.%N) - $started" | bc)
  $bin sheet "$out/$name.exr" -o "$out/$name.sheet.png" --title "$name" 2>/dev/null
  local q=$($bin quality "$out/$name.exr" --exemplar "$image" --max-exemplar 128 --json)
  local extra=""
  if [ "$mode" = layered ]; then
    $bin synth "$image" $flags --no-anti-sweeping --max-exemplar 128 --size $size --seed 1 -o "$out/$name-norule.exr" 2>/dev/null
    local q2=$($bin quality "$out/$name-norule.exr" --exemplar "$image" --max-exemplar 128 --json)
    extra=$(python3 -c "import json,sys; a=json.loads(sys.argv[1]); b=json.loads(sys.argv[2]); print('sweep %.3f (rule off %.3f)' % (a['layered']['sweeping_index'], b['layered']['sweeping_index']))" "$q" "$q2")
  fi
  python3 -c "
import json,sys
r=json.loads(sys.argv[1])
ratios=' '.join('%s %.2f' % (a['axis'], a['ratio']) for a in r['axes'])
hist=max(h['distance'] for h in r['histograms'])
grad=[a['gradient_ratio'] for a in r['sharpness']]
length=[a['length_ratio'] for a in r['sharpness']]
sharp='gradient %.2f-%.2f  length %.2f-%.2f' % (min(grad), max(grad), min(length), max(length))
print('%-12s %6.2fs  ratio %s  hist %.3f  %s  %s' % (sys.argv[2], float(sys.argv[3]), ratios, hist, sharp, sys.argv[4]))
" "$q" "$name" "$took" "$extra"
}
row gravel skimage_gravel.png homogeneous
row grass skimage_grass.png homogeneous
row brick skimage_brick.png homogeneous
row marble gimp_marble1.png homogeneous
row granite gimp_granite1.png homogeneous
row pebbles sh3d_pebbles.png homogeneous
row coffee gimp_java_coffee_beans.png homogeneous
row wood gimp_wood1.png homogeneous
row strata stk_rockStrata_a_512.png layered
row cliff stk_cliff_layered_512.png layered
