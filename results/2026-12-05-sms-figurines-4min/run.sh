#!/usr/bin/env bash
# pt-cf at its default (the block pilot) against Mitsuba 3 for 4 minutes where issue #34 had
# 60 s only: the SMS ring (640×480; peers path and ptracer), figurines (640×360, diffuse table;
# peer path: ptracer renders the figurines black, see results/2026-12-05-targeted-cones.md) and
# cornell-box at 640² (peers path and ptracer); seeds 1..3 (scripts/equal-time-vs-mitsuba.sh).
#   FORECAST=BIN bash results/2026-12-05-sms-figurines-4min/run.sh OUT [CASE…]
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
out="$1"; shift
cases="${*:-sms-240 figurines-240}"
for c in $cases; do
  case "$c" in
    sms-240) CROPS="floor=200,150,250,150" \
        bash "$root/scripts/equal-time-vs-mitsuba.sh" scenes/external/sms-ring/ring.xml 640x480 240 3 "$out/$c" ;;
    figurines-240) CROPS="knot=138,180,132,90 blob=308,188,134,88" PEERS="path" \
        bash "$root/scripts/equal-time-vs-mitsuba.sh" results/2026-12-03-auto-rule/figurines-diffuse-table.toml 640x360 240 3 "$out/$c" ;;
    cornell640-240) CROPS="wall=565,495,60,90 glass=395,545,120,50" REFERENCE="$root/tests/reference/cornell-box-mitsuba-640.exr" \
        bash "$root/scripts/equal-time-vs-mitsuba.sh" scenes/cornell-box.toml 640x640 240 3 "$out/$c" ;;
    *) echo "unknown case $c" >&2; exit 2 ;;
  esac
done
