#!/usr/bin/env bash
# A point-light caustic (tests/scenes/point-mirror.toml) against Mitsuba 3 `ptracer` (issue #34):
# `pt-cf` (its light paths render the light the mirror reflects onto the patch) and `pt` (which
# cannot), each checked with `forecast diff`'s Mitsuba agreement test against 8 × 1,024 spp of
# `ptracer` and its two independent halves.
#   FORECAST=BIN bash results/2026-12-06-point-light-vs-ptracer/run.sh OUT
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"; here="$root/results/2026-12-06-point-light-vs-ptracer"
out=$1; mkdir -p "$out"
bin=${FORECAST:-$root/target/release/forecast}; py=${MITSUBA_VENV:-$root/out/mitsuba-venv}/bin/python
"$bin" export-mitsuba "$root/tests/scenes/point-mirror.toml" --out "$out/pm.xml"
"$py" "$here/mitsuba_seeds.py" "$out/pm.xml" 64 64 1024 8 "$out/ptracer"
for m in pt-cf pt; do
    "$bin" render "$root/tests/scenes/point-mirror.toml" --method $m --resolution 64x64 --spp 8192 \
        --seed 1 --threads ${THREADS:-2} --quiet --out "$out/$m"
    echo "== $m against Mitsuba ptracer"
    "$bin" diff "$out/$m.exr" "$out/ptracer.exr" --half0 "$out/ptracer.half0.exr" --half1 "$out/ptracer.half1.exr" || true
done
