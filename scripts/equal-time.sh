#!/usr/bin/env bash
# Equal-time table for issues #11/#12: `forecast compare` of pt, iws-cf and pt-cf on cornell-box
# (against the in-repo Mitsuba reference) and ring (against a long pt reference made first).
#   scripts/equal-time.sh [BUDGETS] [SEEDS] [OUT]      e.g. scripts/equal-time.sh 60s 3 results/equal-time
# 256x256, 2 threads; budgets count loading and preprocess. The ring reference is rendered once
# (RING_REF_SPP, default 32768 spp, two independent halves) and reused.
set -euo pipefail
cd "$(dirname "$0")/.."
budgets="${1:-60s}"; seeds="${2:-3}"; out="${3:-results/equal-time}"
methods="${METHODS:-pt,iws-cf,pt-cf}"
bin=target/release/forecast
cargo build --release --quiet
mkdir -p "$out"
ring_ref="${RING_REF:-$out/ring-ref-256}"
if [ ! -f "$ring_ref.exr" ]; then
    "$bin" reference scenes/ring.toml --spp "${RING_REF_SPP:-32768}" --resolution 256x256 --threads 2 --seed 9001 \
        --quiet --out "$ring_ref"
fi
"$bin" compare scenes/cornell-box.toml --methods "$methods" --budgets "$budgets" --seeds "$seeds" --threads 2 \
    --reference tests/reference/cornell-box-mitsuba-256.exr --out "$out/cornell" --quiet
"$bin" compare scenes/ring.toml --methods "$methods" --budgets "$budgets" --seeds "$seeds" --threads 2 \
    --reference "$ring_ref.exr" --out "$out/ring" --quiet
