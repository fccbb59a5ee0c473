#!/usr/bin/env bash
# Before (BIN_BASE, BIN_BASE_EMBREE: 3ce4746) against after (BIN_NEW, BIN_NEW_EMBREE: the
# buffers kept across tiles), interleaved run by run, 30 s, 2 threads, seeds 1-3, then the new
# binaries against Mitsuba 3 `path` (scripts/bench-vs-mitsuba.sh). Prints one line per render:
# label method scene accel seed passes whole-run S/s render S/s.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${OUT:-out/wavefront-buffers}; mkdir -p "$out"
one() { # LABEL BIN METHOD SCENE ACCEL SEED
  local o="$out/$1-$3-$(basename "${4%.*}")-$5-$6"
  "$2" render "$4" --method "$3" --resolution 256x256 --time 30s --threads 2 --seed "$6" --accel "$5" \
      --quiet --out "$o" >/dev/null
  python3 - "$o.json" "$1" "$3" "$4" "$5" "$6" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); (w, h), t = j["resolution"], j["timings"]
print(*sys.argv[2:7], j["passes"], f'{j["passes"] * w * h / t["total_s"]:.4g}', f'{j["samples_per_s"]:.4g}')
PY
}
for seed in 1 2 3; do
  for v in BASE NEW; do
    b=BIN_$v; be=BIN_${v}_EMBREE
    one ${v,,} "${!be}" pt scenes/ring.toml embree $seed
    one ${v,,} "${!b}" pt scenes/ring.toml obvhs $seed
    one ${v,,} "${!b}" pt-cf scenes/ring.toml obvhs $seed
  done
done
for s in "scenes/ring.toml 256x256" "scenes/cornell-box.toml 640x640"; do
  set -- $s
  echo "### embree $1 $2"
  OUT=out/wavefront-buffers/bench-embree-$(basename "${1%.*}") FORECAST=$BIN_NEW_EMBREE FORECAST_ARGS="--accel embree" \
      bash scripts/bench-vs-mitsuba.sh "$1" "$2" 30 3 2>&1 | tail -5
  echo "### obvhs $1 $2"
  OUT=out/wavefront-buffers/bench-obvhs-$(basename "${1%.*}") FORECAST=$BIN_NEW bash scripts/bench-vs-mitsuba.sh "$1" "$2" 30 3 2>&1 | tail -5
done
