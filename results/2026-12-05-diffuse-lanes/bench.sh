#!/usr/bin/env bash
# The Mitsuba comparison of results/2026-12-05-diffuse-lanes.md: before (f084e6a) and after
# (7f85217, then b868738), Embree, 15 s, 3 runs each; BIN_DIR holds forecast-<rev>-embree.
BIN_DIR=${BIN_DIR:-/work/bin}
for sc in "scenes/ring.toml 256x256" "scenes/cornell-box.toml 640x640" "results/2026-12-03-auto-rule/figurines-diffuse-table.toml 640x360"; do
  set -- $sc
  for b in ${REVS:-7f85217 f084e6a}; do
    echo "== $1 $2 $b"
    FORECAST=$BIN_DIR/forecast-$b-embree FORECAST_ARGS="--accel embree" THREADS=2 OUT=out/bench-$b \
      bash scripts/bench-vs-mitsuba.sh $1 $2 15 3 2>&1 | tail -6
  done
done
