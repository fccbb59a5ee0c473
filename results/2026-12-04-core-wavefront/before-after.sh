#!/usr/bin/env bash
# Samples per second of e5ecedc (before the wavefront) and 3ce4746 (after), interleaved run by
# run so that drift of the machine hits both: pt (obvhs and Embree), pt-cf and iws-cf (obvhs).
# BIN_BASE[_EMBREE] / BIN_NEW[_EMBREE]: the four binaries. Prints one line per render.
set -euo pipefail
out=${OUT:-out/before-after}; mkdir -p "$out"
one() { # LABEL BIN SCENE RES METHOD SEED EXTRA...
  local label=$1 bin=$2 scene=$3 res=$4 method=$5 seed=$6; shift 6
  local o="$out/$label-$(basename "${scene%.*}")-$method-$seed"
  "$bin" render "$scene" --method "$method" --resolution "$res" --time 30s --threads 2 --seed "$seed" \
      --quiet --out "$o" "$@" >/dev/null
  python3 - "$o.json" "$label" "$scene" "$method" "$seed" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
w, h = j["resolution"]
t = j["timings"]
# samples per second of the whole run (load, preprocess and render), and of the render phase
print(sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], j["passes"],
      f'{j["passes"] * w * h / t["total_s"]:.4g}', f'{j["samples_per_s"]:.4g}', f'{t["preprocess_s"]:.2f}')
PY
}
for seed in 1 2 3; do
  for v in BASE NEW; do
    b=BIN_$v; be=BIN_${v}_EMBREE
    one ${v,,}-embree "${!be}" scenes/ring.toml 256x256 pt $seed --accel embree
    one ${v,,} "${!b}" scenes/ring.toml 256x256 pt $seed
    one ${v,,} "${!b}" scenes/ring.toml 256x256 pt-cf $seed
    one ${v,,} "${!b}" scenes/ring.toml 256x256 iws-cf $seed
    one ${v,,} "${!b}" scenes/cornell-box.toml 256x256 pt-cf $seed
  done
done
