#!/usr/bin/env bash
# pt-cf before and after the guided roulette, at equal time, seed by seed interleaved, then the
# noise of each from scripts/equal-time-vs-mitsuba.sh (which finds the renders and only scores).
#   BIN_BASE=… BIN_NEW=… bash results/2026-12-04-guided-roulette/before-after.sh BUDGET_S SEEDS OUT
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
budget="$1"; seeds="$2"; out="$3"
cases=(
  "cornell scenes/cornell-box.toml wall=226,198,24,36 glass=158,218,48,20"
  "ring scenes/ring.toml cardioid=139,71,71,132 floor=145,100,50,60"
)
for ((s = 1; s <= seeds; s++)); do
  for c in "${cases[@]}"; do
    read -r name scene _ <<<"$c"
    for b in base new; do
      bin="BIN_${b^^}"; d="$out/$name-$b"; mkdir -p "$d"; o="$d/pt-cf-$s"
      [ -f "$o.exr" ] && continue
      [ -f "$d/renders.tsv" ] || printf 'renderer\tseed\tspp\twall_s\tcpu_s\n' >"$d/renders.tsv"
      /usr/bin/time -f '%e %U %S' -o "$o.time" "${!bin}" render "$scene" --method pt-cf --time "${budget}s" \
        --resolution 256x256 --threads "$(nproc)" --max-depth 64 --seed "$s" --out "$o" --quiet 2>/dev/null
      python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); e,u,s=map(float,open(sys.argv[2]).read().split()[-3:]); print("\t".join(["pt-cf", sys.argv[3], str(j["passes"]), "%.2f" % e, "%.2f" % (u+s)]))' \
        "$o.json" "$o.time" "$s" >>"$d/renders.tsv"
    done
  done
done
for c in "${cases[@]}"; do
  read -r name scene crops <<<"$c"
  ref=""; [ "$name" = cornell ] && ref="$root/tests/reference/cornell-box-mitsuba-256.exr"
  for b in base new; do
    echo "== $name $b"
    FORECAST="${BIN_NEW}" CROPS="$crops" REFERENCE="$ref" PEERS="" \
      bash "$root/scripts/equal-time-vs-mitsuba.sh" "$scene" 256x256 "$budget" "$seeds" "$out/$name-$b"
  done
done
