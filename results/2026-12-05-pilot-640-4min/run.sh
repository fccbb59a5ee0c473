#!/usr/bin/env bash
# pt-cf at its default (the block pilot) against Mitsuba 3 path and ptracer at the budgets and
# sizes issue #34 names beyond 256² and 60 s: cornell-box and ring at 640² for 60 s, cornell-box
# at 256² for 240 s; seeds 1..3 (scripts/equal-time-vs-mitsuba.sh, peers included).
#   FORECAST=BIN bash results/2026-12-05-pilot-640-4min/run.sh OUT [CASE…]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="$1"; shift
cases="${*:-cornell-640 ring-640 cornell-256-240}"
for c in $cases; do
  case "$c" in
    cornell-640) CROPS="wall=565,495,60,90 glass=395,545,120,50" REFERENCE="$root/tests/reference/cornell-box-mitsuba-640.exr" \
        bash "$root/scripts/equal-time-vs-mitsuba.sh" scenes/cornell-box.toml 640x640 60 3 "$out/$c" ;;
    ring-640) CROPS="cardioid=348,178,178,330 floor=362,250,125,150" \
        bash "$root/scripts/equal-time-vs-mitsuba.sh" scenes/ring.toml 640x640 60 3 "$out/$c" ;;
    cornell-256-240) CROPS="wall=226,198,24,36 glass=158,218,48,20" REFERENCE="$root/tests/reference/cornell-box-mitsuba-256.exr" \
        bash "$root/scripts/equal-time-vs-mitsuba.sh" scenes/cornell-box.toml 256x256 240 3 "$out/$c" ;;
    *) echo "unknown case $c" >&2; exit 2 ;;
  esac
done
