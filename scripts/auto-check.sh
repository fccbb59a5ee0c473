#!/usr/bin/env bash
# Checks `--method auto` against equal-time measurements (issue 32): for each committed scene,
# auto's choice must have a whole-image RMSE within 1.1x of the best method's at 1 min.
#   scripts/auto-check.sh [OUT]                      e.g. scripts/auto-check.sh results/auto-check
# For each scene: the method auto picks (from the JSON `method` of a tiny render), then one
# `forecast compare SCENE --methods pt,pt-cf,iws-cf --budgets 1m --seeds 3` against a reference;
# the mean over seeds of each method's `full` RMSE (results.json), and the ratio of auto's pick to
# the best. Exit 1 when a scene's ratio exceeds LIMIT.
# Env: SCENES (default "cornell-box ring figurines"), METHODS (pt,pt-cf,iws-cf), BUDGET (1m),
# SEEDS (3), RES (256x256), THREADS (2), LIMIT (1.1), REF_SPP (16384, for the references made
# here), REF_<scene with _ for -> (an existing reference EXR; cornell-box defaults to the in-repo
# Mitsuba render). About 30 min of renders plus the references: run it on a quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-results/auto-check}"
scenes="${SCENES:-cornell-box ring figurines}"
methods="${METHODS:-pt,pt-cf,iws-cf}"
budget="${BUDGET:-1m}"; seeds="${SEEDS:-3}"; res="${RES:-256x256}"; threads="${THREADS:-2}"
limit="${LIMIT:-1.1}"
bin=target/release/forecast
cargo build --release --quiet
mkdir -p "$out"
fail=0
for s in $scenes; do
    scene="scenes/$s.toml"
    var="REF_${s//-/_}"
    ref="${!var:-}"
    if [ -z "$ref" ] && [ "$s" = cornell-box ] && [ "$res" = 256x256 ]; then
        ref=tests/reference/cornell-box-mitsuba-256.exr
    fi
    if [ -z "$ref" ]; then
        ref="$out/$s-ref.exr"
        [ -f "$ref" ] || "$bin" reference "$scene" --spp "${REF_SPP:-16384}" --resolution "$res" \
            --threads "$threads" --seed 9001 --quiet --out "${ref%.exr}"
    fi
    "$bin" render "$scene" --spp 1 --resolution 8x8 --threads 1 --quiet --out "$out/$s-auto"
    "$bin" compare "$scene" --methods "$methods" --budgets "$budget" --seeds "$seeds" --threads "$threads" \
        --resolution "$res" --reference "$ref" --out "$out/$s" --quiet
    python3 - "$out/$s-auto.json" "$out/$s/results.json" "$limit" "$s" <<'EOF' || fail=1
import json, sys
auto = json.load(open(sys.argv[1]))["method"]
runs = json.load(open(sys.argv[2]))["runs"]
limit, scene = float(sys.argv[3]), sys.argv[4]
rmse = {}
for r in runs:
    full = [e["rmse"] for e in r["regions"] if e["region"] == "full"]
    if r.get("error") is None and r["spp"] > 0 and full:
        rmse.setdefault(r["method"], []).append(full[0])
mean = {m: sum(v) / len(v) for m, v in rmse.items()}
if auto not in mean:
    sys.exit(f"{scene}: auto picks {auto}, which the comparison did not measure (METHODS)")
best = min(mean, key=mean.get)
ratio = mean[auto] / mean[best]
table = ", ".join(f"{m} {v:.4g} ({len(rmse[m])} seeds)" for m, v in sorted(mean.items(), key=lambda x: x[1]))
verdict = "ok" if ratio <= limit else "FAILED"
print(f"{scene}: auto picks {auto}: {ratio:.3f}x the best ({best}); whole-image RMSE {table}: {verdict}")
sys.exit(0 if ratio <= limit else 1)
EOF
done
exit "$fail"
