#!/usr/bin/env bash
# Samples per second before (BIN_BASE) and after (BIN_NEW) the SubsetGrid's cluster-map answers,
# interleaved run by run, 30 s, 2 threads, seeds 1-3. CASES: "METHOD:SCENE:RES ..." (default:
# pt-cf on ring and cornell-box at 256²). Prints: label method scene seed passes whole-run S/s
# render S/s cluster lookups.
set -euo pipefail
out=${OUT:-out/cluster-grid}; mkdir -p "$out"
cases=${CASES:-"pt-cf:scenes/ring.toml:256x256 pt-cf:scenes/cornell-box.toml:256x256"}
for seed in 1 2 3; do
  for c in $cases; do
    IFS=: read -r method scene res <<<"$c"
    for v in BASE NEW; do
      bin=BIN_$v; o="$out/${v,,}-$method-$(basename "${scene%.*}")-$seed"
      "${!bin}" render "$scene" --method "$method" --resolution "$res" --time 30s --threads 2 --seed $seed \
          --quiet --out "$o" >/dev/null
      python3 - "$o.json" "${v,,}" "$method" "$scene" $seed <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); (w, h), t = j["resolution"], j["timings"]
m = j["method_stats"]
lookups = m["guide"]["lookups"] if "guide" in m else m.get("caustics", {}).get("render", {}).get("lookups")
print(sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5], j["passes"],
      f'{j["passes"] * w * h / t["total_s"]:.4g}', f'{j["samples_per_s"]:.4g}', lookups)
PY
    done
  done
done
