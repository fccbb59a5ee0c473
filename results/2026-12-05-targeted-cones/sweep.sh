#!/usr/bin/env bash
# pt-cf (BIN) at equal time with --light-paths N (absolute count per pass) for each NAME=N given,
# seeds 1..SEEDS, scored by scripts/equal-time-vs-mitsuba.sh without peers.
#   BIN=… bash results/2026-12-05-targeted-cones/sweep.sh CASE BUDGET_S SEEDS OUT NAME=N…
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
c="$1"; budget="$2"; seeds="$3"; out="$4"; shift 4
declare -A res scene crops ref
scene[sms]=scenes/external/sms-ring/ring.xml;  res[sms]=640x480; crops[sms]="floor=200,150,250,150"
scene[cornell]=scenes/cornell-box.toml;        res[cornell]=256x256; crops[cornell]="wall=226,198,24,36 glass=158,218,48,20"
scene[figurines]=results/2026-12-03-auto-rule/figurines-diffuse-table.toml; res[figurines]=640x360
crops[figurines]="knot=138,180,132,90 blob=308,188,134,88"
scene[ring]=scenes/ring.toml;                  res[ring]=256x256; crops[ring]="cardioid=139,71,71,132 floor=145,100,50,60"
for setting in "$@"; do
  name="${setting%%=*}"; n="${setting#*=}"
  FORECAST="$BIN" FORECAST_ARGS="--light-paths $n" CROPS="${crops[$c]}" PEERS="" \
    bash "$root/scripts/equal-time-vs-mitsuba.sh" "${scene[$c]}" "${res[$c]}" "$budget" "$seeds" "$out/$c-$name"
done
