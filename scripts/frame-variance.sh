#!/usr/bin/env bash
# Variance of one sample over a whole frame, from seeds alone (no reference), and the CPU µs per
# sample: the two numbers whose product ranks methods and options at equal time (results/2026-11-30-crop-cameras.md,
# "Crop cameras"). Renders SEEDS images at SPP and prints half the mean squared difference of
# consecutive seeds times SPP, and each run's `profile_per_sample.total_us`.
#   scripts/frame-variance.sh SCENE METHOD SPP SEEDS [render options…]
#   e.g. scripts/frame-variance.sh scenes/figurines.toml iws-cf 8 3 --resolution 256x256 --direct vpl
# Set FORECAST to use another binary (default: target/release/forecast); images go to out/frames/.
# CROPS="NAME:X,Y,W,H …" also prints the variance inside each region (pixels of the render).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 4 ] || { sed -n 2,8p "$0" >&2; exit 2; }
scene=$1 method=$2 spp=$3 seeds=$4; shift 4
[ "$seeds" -ge 2 ] || { echo "frame-variance: need at least 2 seeds" >&2; exit 2; }
bin=${FORECAST:-target/release/forecast}
[ -x "$bin" ] || cargo build --release
name=$(basename "$scene" .toml); out=out/frames; mkdir -p "$out"
us=""
for s in $(seq 1 "$seeds"); do
    "$bin" render "$scene" --method "$method" --spp "$spp" --seed "$s" --quiet --out "$out/$name-$method-s$s" "$@"
    us="$us $(grep -o '"total_us": *[0-9.e+-]*' "$out/$name-$method-s$s.json" | head -1 | awk -F: '{ printf "%.3g", $2 + 0 }')"
done
# half the mean squared difference of consecutive seeds times spp, [--crop X,Y,W,H]
between() {
    local pairs=0 rmse
    for s in $(seq 2 "$seeds"); do
        rmse=$("$bin" diff "$out/$name-$method-s$((s - 1)).exr" "$out/$name-$method-s$s.exr" "$@" | awk '$1 == "RMSE" { print $2 }')
        pairs=$(awk -v t="$pairs" -v r="$rmse" -v n="$spp" 'BEGIN { print t + r * r * n / 2 }')
    done
    awk -v t="$pairs" -v k="$((seeds - 1))" 'BEGIN { printf "%.4g", t / k }'
}
echo "$name $method: variance per sample between seeds $(between); µs per sample:$us"
for crop in ${CROPS:-}; do
    echo "$name $method: ${crop%%:*} (${crop#*:}) variance per sample $(between --crop "${crop#*:}")"
done
