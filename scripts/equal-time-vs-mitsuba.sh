#!/usr/bin/env bash
# Equal wall-clock time, crop by crop: forecast methods against Mitsuba 3 `path` and `ptracer`
# (issue 34). A benchmark, not a CI test: run it on a quiet machine; it is not in scripts/test.sh.
#
#   scripts/equal-time-vs-mitsuba.sh SCENE RESOLUTION BUDGET_S SEEDS OUT
#   e.g. CROPS="wall=226,198,24,36 glass=158,218,48,20" REFERENCE=tests/reference/cornell-box-mitsuba-256.exr \
#        scripts/equal-time-vs-mitsuba.sh scenes/cornell-box.toml 256x256 60 3 out/et/cornell-256-60
#
# Every renderer gets the same budget, seeds 1..SEEDS, in the order seed by seed (forecast methods,
# then each peer), so that a slow spell of a shared machine falls on all of them alike.
# forecast: `render --time BUDGET` (loading and preprocess inside). Mitsuba: scripts/mitsuba_timed.py
# (loading and JIT inside), max_depth = MAX_DEPTH + 1 and rr_depth 5 (as bench-vs-mitsuba.sh).
#
# Per renderer and crop it prints:
#   noise  the RMSE of one render from the seed-to-seed differences: sqrt(mean over seed pairs of
#          MSE(a, b) / 2). For unbiased renderers this is the RMSE against the true image.
#   ref    (with REFERENCE) sqrt(mean over seeds of MSE against the reference image), which also
#          holds the reference's own noise and any bias.
#   mean   the crop's mean value (pixels and channels, mean over seeds): a renderer that cannot see
#          part of a crop (Mitsuba's ptracer renders mirrors and glass seen directly black) shows
#          a low noise there but a lower mean.
# and, in the log, each render's spp, wall seconds and CPU seconds (a CPU/wall ratio below the
# thread count means the machine was shared).
#
# Environment:
#   CROPS      space-separated NAME=X,Y,W,H in pixels of RESOLUTION ("whole" is always added)
#   REFERENCE  an EXR at RESOLUTION (optional)
#   METHODS    forecast methods (default pt-cf); FORECAST_ARGS extra render arguments
#   PEERS      Mitsuba integrators (default "path ptracer"; empty for none)
#   THREADS    threads of every renderer (default nproc); MAX_DEPTH (default 64)
#   FORECAST   binary (default target/release/forecast, built if missing); MITSUBA_VENV
#              (default out/mitsuba-venv; see docs/mitsuba.md); VARIANT (default llvm_ad_rgb)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -eq 5 ] || { sed -n 2,8p "$0" >&2; exit 2; }
scene="$1"; res="$2"; budget="$3"; seeds="$4"; out="$5"
[[ "$res" =~ ^([0-9]+)x([0-9]+)$ ]] || { echo "equal-time-vs-mitsuba: resolution must be WxH, got $res" >&2; exit 2; }
w="${BASH_REMATCH[1]}"; h="${BASH_REMATCH[2]}"
[[ "$budget" =~ ^[0-9]+$ ]] || { echo "equal-time-vs-mitsuba: budget is whole seconds, got $budget" >&2; exit 2; }
[[ "$seeds" =~ ^[2-9]$|^[1-9][0-9]+$ ]] || { echo "equal-time-vs-mitsuba: at least 2 seeds (the noise needs pairs), got $seeds" >&2; exit 2; }
[ -f "$scene" ] || { echo "equal-time-vs-mitsuba: no scene $scene" >&2; exit 2; }
methods="${METHODS:-pt-cf}"; peers="${PEERS-path ptracer}"
threads="${THREADS:-$(nproc)}"; max_depth="${MAX_DEPTH:-64}"; variant="${VARIANT:-llvm_ad_rgb}"
venv="${MITSUBA_VENV:-$root/out/mitsuba-venv}"
bin="${FORECAST:-$root/target/release/forecast}"
[ -x "$bin" ] || (cd "$root" && cargo build --release --quiet)
if [ -n "$peers" ] && ! "$venv/bin/python" -c 'import mitsuba' 2>/dev/null; then
    echo "equal-time-vs-mitsuba: no Mitsuba in $venv (docs/mitsuba.md: python3 -m venv $venv && $venv/bin/pip install mitsuba numpy)" >&2
    exit 2
fi
mkdir -p "$out"
log="$out/renders.tsv"
[ -f "$log" ] || printf 'renderer\tseed\tspp\twall_s\tcpu_s\n' >"$log"
xml="$out/scene.xml"
if [[ "$scene" == *.xml ]]; then xml="$scene"; elif [ -n "$peers" ]; then "$bin" export-mitsuba "$scene" --out "$xml" >/dev/null; fi

render_forecast() { # METHOD SEED
    local o="$out/$1-$2"
    [ -f "$o.exr" ] && return
    /usr/bin/time -f '%e %U %S' -o "$o.time" "$bin" render "$scene" --method "$1" --time "${budget}s" --resolution "$res" \
        --threads "$threads" --max-depth "$max_depth" --seed "$2" --out "$o" --quiet ${FORECAST_ARGS:-} 2>/dev/null
    python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); e,u,s=map(float,open(sys.argv[2]).read().split()[-3:]); print("\t".join([sys.argv[3], sys.argv[4], str(j["passes"]), "%.2f" % e, "%.2f" % (u+s)]))' \
        "$o.json" "$o.time" "$1" "$2" >>"$log"
}
render_mitsuba() { # INTEGRATOR SEED
    local o="$out/mitsuba-$1-$2"
    [ -f "$o.exr" ] && return
    read -r spp secs cpu < <("$venv/bin/python" "$root/scripts/mitsuba_timed.py" "$xml" "$w" "$h" "$budget" "$threads" \
        "$((max_depth + 1))" 5 "$variant" "$1" "$2" "$o.exr" 2>"$o.log")
    printf 'mitsuba-%s\t%s\t%s\t%.2f\t%.2f\n' "$1" "$2" "$spp" "$secs" "$cpu" >>"$log"
}
renderers=()
for m in $methods; do renderers+=("$m"); done
for p in $peers; do renderers+=("mitsuba-$p"); done
for ((s = 1; s <= seeds; s++)); do
    for m in $methods; do echo "equal-time-vs-mitsuba: $m seed $s" >&2; render_forecast "$m" "$s"; done
    for p in $peers; do echo "equal-time-vs-mitsuba: Mitsuba $p seed $s" >&2; render_mitsuba "$p" "$s"; done
done

mse() { # A B CROP -> "MSE mean-of-A" (the mean over the crop's pixels and channels)
    local c=(); [ "$3" = "whole" ] || c=(--crop "$3")
    "$bin" diff "$1" "$2" "${c[@]}" 2>/dev/null |
        awk '/^RMSE/ { e = $2 * $2 } /^mean A/ { m = ($3 + $4 + $5) / 3 } END { printf "%.9g %.9g\n", e, m }'
}
crops="whole=whole ${CROPS:-}"
{
    printf '# %s %s, %s s, seeds 1..%s, %s threads (commit %s)\n' "$scene" "$res" "$budget" "$seeds" "$threads" \
        "$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
    printf '%-18s %-8s %-12s %-12s %-12s\n' renderer crop noise ref mean
    for r in "${renderers[@]}"; do
        for c in $crops; do
            name="${c%%=*}"; rect="${c#*=}"
            pairs=""
            for ((a = 1; a <= seeds; a++)); do for ((b = a + 1; b <= seeds; b++)); do
                pairs+="$(mse "$out/$r-$a.exr" "$out/$r-$b.exr" "$rect" | cut -d' ' -f1) "
            done; done
            noise="$(awk -v l="$pairs" 'BEGIN { n = split(l, v, " "); for (i = 1; i <= n; i++) t += v[i]; printf "%.4e", sqrt(t / n / 2) }')"
            means=""
            for ((a = 1; a <= seeds; a++)); do means+="$(mse "$out/$r-$a.exr" "$out/$r-$a.exr" "$rect" | cut -d' ' -f2) "; done
            mean="$(awk -v l="$means" 'BEGIN { n = split(l, v, " "); for (i = 1; i <= n; i++) t += v[i]; printf "%.4e", t / n }')"
            ref="-"
            if [ -n "${REFERENCE:-}" ]; then
                errs=""
                for ((a = 1; a <= seeds; a++)); do errs+="$(mse "$out/$r-$a.exr" "$REFERENCE" "$rect" | cut -d' ' -f1) "; done
                ref="$(awk -v l="$errs" 'BEGIN { n = split(l, v, " "); for (i = 1; i <= n; i++) t += v[i]; printf "%.4e", sqrt(t / n) }')"
            fi
            printf '%-18s %-8s %-12s %-12s %-12s\n' "$r" "$name" "$noise" "$ref" "$mean"
        done
    done
} | tee "$out/table.txt"
