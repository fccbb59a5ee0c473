#!/bin/bash
# The 4-minute cornell-box 256² cell against Mitsuba 3, both samplers (results/2026-12-06-cornell-256-4min.md).
#   FORECAST=BIN bash results/2026-12-06-cornell-256-4min/run.sh [OUT]   (BIN built with --features embree)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-out/et4}
export FORECAST=${FORECAST:-target/release/forecast} THREADS=2 CROPS="wall=226,198,24,36 glass=158,218,48,20" REFERENCE=tests/reference/cornell-box-mitsuba-256.exr
mkdir -p "$out"
FORECAST_ARGS="--accel embree --sampler sobol" bash scripts/equal-time-vs-mitsuba.sh scenes/cornell-box.toml 256x256 240 3 "$out/sobol" > "$out/sobol.txt" 2>&1
FORECAST_ARGS="--accel embree" PEERS="" bash scripts/equal-time-vs-mitsuba.sh scenes/cornell-box.toml 256x256 240 3 "$out/default" > "$out/default.txt" 2>&1
