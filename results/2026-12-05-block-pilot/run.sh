#!/usr/bin/env bash
# pt-cf at equal time, the block pilot (the default from 9d5c894 on; the measurement of
# 2026-12-05 ran the same rule as --light-path-pilot, before that flag was retired) against a
# fixed count (½ per pixel), four scenes, seeds 1..SEEDS, scored by
# scripts/equal-time-vs-mitsuba.sh without peers. BIN: 9d5c894 or later.
#   BIN=… bash results/2026-12-05-block-pilot/run.sh BUDGET_S SEEDS OUT [CASE…]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
budget="$1"; seeds="$2"; out="$3"; shift 3
cases="${*:-sms ring cornell figurines}"
declare -A res scene crops
scene[sms]=scenes/external/sms-ring/ring.xml;  res[sms]=640x480; crops[sms]="floor=200,150,250,150"
scene[cornell]=scenes/cornell-box.toml;        res[cornell]=256x256; crops[cornell]="wall=226,198,24,36 glass=158,218,48,20"
scene[figurines]=results/2026-12-03-auto-rule/figurines-diffuse-table.toml; res[figurines]=640x360
crops[figurines]="knot=138,180,132,90 blob=308,188,134,88"
scene[ring]=scenes/ring.toml;                  res[ring]=256x256; crops[ring]="cardioid=139,71,71,132 floor=145,100,50,60"
for c in $cases; do
  w=${res[$c]%x*}; h=${res[$c]#*x}; half=$(( (w * h + 1) / 2 ))
  for setting in "pilot:" "half:--light-paths $half"; do
    name="${setting%%:*}"; args="${setting#*:}"
    FORECAST="$BIN" FORECAST_ARGS="$args" CROPS="${crops[$c]}" PEERS="" \
      bash "$root/scripts/equal-time-vs-mitsuba.sh" "${scene[$c]}" "${res[$c]}" "$budget" "$seeds" "$out/$c-$name"
  done
done
