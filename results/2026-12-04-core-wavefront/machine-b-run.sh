cd /work/main
run() { echo "### $1 $4 $5"; OUT=out/b33/$1-$(basename ${4%.*}) FORECAST=$2 FORECAST_ARGS="$3" bash scripts/bench-vs-mitsuba.sh $4 $5 30 3 2>&1 | tail -5; }
run new-embree /work/bin/forecast-new-embree "--accel embree" scenes/ring.toml 256x256
run new-obvhs /work/bin/forecast-new-obvhs "" scenes/ring.toml 256x256
run new-embree /work/bin/forecast-new-embree "--accel embree" scenes/cornell-box.toml 640x640
run new-obvhs /work/bin/forecast-new-obvhs "" scenes/cornell-box.toml 640x640
echo ALL-DONE
