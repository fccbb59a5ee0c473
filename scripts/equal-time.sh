#!/usr/bin/env bash
# Equal-time table for issues #11/#12: `forecast compare` of pt, iws-cf and pt-cf on cornell-box
# (against the in-repo Mitsuba reference) and ring (against a long pt reference made first).
#   scripts/equal-time.sh [BUDGETS] [SEEDS] [OUT]      e.g. scripts/equal-time.sh 60s 3 results/equal-time
# SCENES (default "cornell ring") may add `figurines` (its pt reference: FIG_REF, else 8192 spp made here).
# 256x256, 2 threads; budgets count loading and preprocess. The ring reference is rendered once
# (RING_REF_SPP, default 32768 spp, two independent halves) and reused.
# SINGLE_RUN=1 adds `--single-run`: one render per (method, seed) at the largest budget, the smaller
# budgets measured from its snapshots (e.g. BUDGETS 15s,30s,1m,2m,4m costs one 4-min run, not five).
set -euo pipefail
cd "$(dirname "$0")/.."
budgets="${1:-60s}"; seeds="${2:-3}"; out="${3:-results/equal-time}"
methods="${METHODS:-pt,iws-cf,pt-cf}"
bin=target/release/forecast
single=(); [ "${SINGLE_RUN:-0}" = 1 ] && single=(--single-run)
cargo build --release --quiet
mkdir -p "$out"
scenes="${SCENES:-cornell ring}"
run() { # NAME SCENE REFERENCE
    "$bin" compare "$2" --methods "$methods" --budgets "$budgets" --seeds "$seeds" --threads 2 \
        --reference "$3" --out "$out/$1" --quiet ${single[@]+"${single[@]}"}
}
for s in $scenes; do
    case "$s" in
    cornell) run cornell scenes/cornell-box.toml tests/reference/cornell-box-mitsuba-256.exr ;;
    ring)
        ring_ref="${RING_REF:-$out/ring-ref-256}"
        [ -f "$ring_ref.exr" ] || "$bin" reference scenes/ring.toml --spp "${RING_REF_SPP:-32768}" \
            --resolution 256x256 --threads 2 --seed 9001 --quiet --out "$ring_ref"
        run ring scenes/ring.toml "$ring_ref.exr" ;;
    figurines)
        fig_ref="${FIG_REF:-$out/figurines-ref-256}"
        [ -f "$fig_ref.exr" ] || "$bin" reference scenes/figurines.toml --spp 8192 --resolution 256x256 --threads 2 \
            --seed 9001 --quiet --out "$fig_ref"
        run figurines scenes/figurines.toml "$fig_ref.exr" ;;
    *) echo "equal-time: unknown scene $s" >&2; exit 1 ;;
    esac
done
