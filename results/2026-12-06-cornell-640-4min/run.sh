#!/bin/bash
# The 4-minute cornell-box 640² cell against Mitsuba 3, both samplers (results/2026-12-06-cornell-640-4min.md).
#   FORECAST=BIN bash results/2026-12-06-cornell-640-4min/run.sh [OUT]   (BIN built with --features embree)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-out/et640}
export FORECAST=${FORECAST:-target/release/forecast} THREADS=2 CROPS="wall=565,495,60,90 glass=395,545,120,50" REFERENCE=tests/reference/cornell-box-mitsuba-640.exr
mkdir -p "$out"
FORECAST_ARGS="--accel embree" bash scripts/equal-time-vs-mitsuba.sh scenes/cornell-box.toml 640x640 240 3 "$out/default" > "$out/default-and-peers.txt" 2>&1
FORECAST_ARGS="--accel embree --sampler sobol" PEERS="" bash scripts/equal-time-vs-mitsuba.sh scenes/cornell-box.toml 640x640 240 3 "$out/sobol" > "$out/sobol.txt" 2>&1
