#!/usr/bin/env bash
# pt-cf with the per-object target cones (BIN_NEW) against the box-circumsphere cone (BIN_BASE)
# and Mitsuba 3 `path` and `ptracer`, equal time, seeds 1..SEEDS, each case scored by
# scripts/equal-time-vs-mitsuba.sh (noise = RMSE of one render from seed-to-seed differences).
#   BIN_BASE=… BIN_NEW=… bash results/2026-12-05-targeted-cones/equal-time.sh BUDGET_S SEEDS OUT [CASE…]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
budget="$1"; seeds="$2"; out="$3"; shift 3
declare -A res scene crops ref
scene[sms]=scenes/external/sms-ring/ring.xml;  res[sms]=640x480; crops[sms]="floor=200,150,250,150"
scene[cornell]=scenes/cornell-box.toml;        res[cornell]=256x256; crops[cornell]="wall=226,198,24,36 glass=158,218,48,20"
ref[cornell]="$root/tests/reference/cornell-box-mitsuba-256.exr"
scene[figurines]=results/2026-12-03-auto-rule/figurines-diffuse-table.toml; res[figurines]=640x360
crops[figurines]="knot=138,180,132,90 blob=308,188,134,88"
scene[ring]=scenes/ring.toml;                  res[ring]=256x256; crops[ring]="cardioid=139,71,71,132 floor=145,100,50,60"
cases=("$@"); [ ${#cases[@]} -gt 0 ] || cases=(sms cornell figurines ring)
for c in "${cases[@]}"; do
  echo "== $c new (+ Mitsuba)"
  FORECAST="$BIN_NEW" CROPS="${crops[$c]}" REFERENCE="${ref[$c]:-}" \
    bash "$root/scripts/equal-time-vs-mitsuba.sh" "${scene[$c]}" "${res[$c]}" "$budget" "$seeds" "$out/$c"
  echo "== $c base"
  FORECAST="$BIN_BASE" CROPS="${crops[$c]}" REFERENCE="${ref[$c]:-}" PEERS="" \
    bash "$root/scripts/equal-time-vs-mitsuba.sh" "${scene[$c]}" "${res[$c]}" "$budget" "$seeds" "$out/$c-base"
done
