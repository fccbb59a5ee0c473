#!/usr/bin/env bash
cd /work/main
run() { # NAME BIN ARGS SCENE RES
  echo "### $1 $4 $5"
  OUT=out/b33/$1-$(basename ${4%.*}) FORECAST=$2 FORECAST_ARGS="$3" bash scripts/bench-vs-mitsuba.sh $4 $5 30 3 2>&1 | tail -5
}
run base-embree /work/bin/forecast-base-embree "--accel embree" scenes/ring.toml 256x256
run new-embree /work/bin/forecast-new-embree "--accel embree" scenes/ring.toml 256x256
run base-obvhs /work/bin/forecast-base-obvhs "" scenes/ring.toml 256x256
run new-obvhs /work/bin/forecast-new-obvhs "" scenes/ring.toml 256x256
run base-embree /work/bin/forecast-base-embree "--accel embree" scenes/cornell-box.toml 640x640
run new-embree /work/bin/forecast-new-embree "--accel embree" scenes/cornell-box.toml 640x640
run new-obvhs /work/bin/forecast-new-obvhs "" scenes/cornell-box.toml 640x640
run new-embree /work/bin/forecast-new-embree "--accel embree" results/2026-12-03-auto-rule/figurines-diffuse-table.toml 320x180
echo ALL-DONE
