#!/usr/bin/env bash
# Per-sample variance of a method on a crop camera (scenes/crops/*.toml): the crop's squared error
# against a long `pt` image of the same camera, times the samples per pixel, averaged over seeds.
# Equal-time efficiency on the full frame is 1/(variance × the full frame's µs per sample), so two
# methods compare as sqrt(var_a·t_a / var_b·t_b) (results/2026-11-30-crop-cameras.md).
#   scripts/crop-variance.sh CROP METHOD SPP SEEDS [render options…]
#   e.g. scripts/crop-variance.sh scenes/crops/cornell-glass-caustic.toml iws-cf 128 4
# The reference (pt, 32,768 spp, seed 9001; about a minute per crop on 2 cores) is made once, in
# out/crops/. Set FORECAST to use another binary (default: target/release/forecast).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 4 ] || { sed -n 2,9p "$0" >&2; exit 2; }
crop=$1 method=$2 spp=$3 seeds=$4; shift 4
bin=${FORECAST:-target/release/forecast}
[ -x "$bin" ] || cargo build --release
name=$(basename "$crop" .toml); out=out/crops; mkdir -p "$out"
ref=$out/$name-ref
[ -f "$ref.exr" ] || "$bin" render "$crop" --method pt --spp 32768 --seed 9001 --quiet --out "$ref"
total=0
for s in $(seq 1 "$seeds"); do
    run=$out/$name-$method-s$s
    "$bin" render "$crop" --method "$method" --spp "$spp" --seed "$s" --quiet --out "$run" "$@"
    rmse=$("$bin" diff "$run.exr" "$ref.exr" | awk '$1 == "RMSE" { print $2 }')
    var=$(awk -v r="$rmse" -v n="$spp" 'BEGIN { printf "%.4g", r * r * n }')
    us=$(grep -o '"total_us": *[0-9.e+-]*' "$run.json" | head -1 | awk -F: '{ print $2 + 0 }')
    echo "seed $s: RMSE $rmse, variance per sample $var, crop µs per sample $us"
    total=$(awk -v t="$total" -v v="$var" 'BEGIN { print t + v }')
done
awk -v t="$total" -v k="$seeds" -v m="$method" -v c="$name" 'BEGIN { printf "%s %s: mean variance per sample %.4g\n", c, m, t / k }'
# the same from the seeds alone (no reference, so also for a method that omits a term, as `iws`):
# RMSE(seed i, seed i+1)² = 2·var/spp
if [ "$seeds" -ge 2 ]; then
    pairs=0
    for s in $(seq 2 "$seeds"); do
        rmse=$("$bin" diff "$out/$name-$method-s$((s - 1)).exr" "$out/$name-$method-s$s.exr" | awk '$1 == "RMSE" { print $2 }')
        pairs=$(awk -v t="$pairs" -v r="$rmse" -v n="$spp" 'BEGIN { print t + r * r * n / 2 }')
    done
    awk -v t="$pairs" -v k="$((seeds - 1))" -v m="$method" -v c="$name" 'BEGIN { printf "%s %s: variance per sample between seeds %.4g\n", c, m, t / k }'
fi
