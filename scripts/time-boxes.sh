#!/usr/bin/env bash
# Issue #63's time-box matrix: every method on `cornell-box` 128² and 2048², `figurines` 640×360
# and `water-caustic` (its own 256²), at each `--time` budget; one line per render with its wall
# and CPU seconds, the passes, the mean pass, the passes cut at the deadline, the verdict and the
# JSON's phases. Run it on a quiet machine (every figure is wall time).
#   scripts/time-boxes.sh [BUDGETS] [OUT]       e.g. scripts/time-boxes.sh "3 5 60" /tmp/tb
# METHODS (default "pt iws iws-pm iws-cf pt-cf"), CASES (default: the four below, as
# "SCENE RESOLUTION" separated by commas) and THREADS (default: all cores) narrow it.
# Verdict: `within` when wall ≤ --time × 1.02; `+1 pass` when wall ≤ --time × 1.02 + the run's
# mean pass (the issue's "Done when" allows one pass over: the first pass always finishes);
# `refused` when the render exits at once (< 1 s) naming the time it needs; `OVER` otherwise.
# Wall is the whole process (`/usr/bin/time`), CPU user + system; cpu/wall below the thread count
# means the render waited for cores.
set -euo pipefail
cd "$(dirname "$0")/.."
budgets="${1:-3 5 60}"; out="${2:-/tmp/time-boxes}"
methods="${METHODS:-pt iws iws-pm iws-cf pt-cf}"
cases="${CASES:-scenes/cornell-box.toml 128x128,scenes/cornell-box.toml 2048x2048,scenes/figurines.toml 640x360,scenes/water-caustic.toml -}"
bin=target/release/forecast
[ "${NO_BUILD:-0}" = 1 ] || cargo build --release --quiet
mkdir -p "$out"
threads=(); [ -n "${THREADS:-}" ] && threads=(--threads "$THREADS")
printf '%-32s %-7s %5s %7s %7s %5s %6s %8s %4s %-9s %s\n' \
    case method time wall cpu c/w passes pass_s cut verdict phases
IFS=',' read -ra case_list <<< "$cases"
for c in "${case_list[@]}"; do
    read -r scene res <<< "$c"
    res_args=(); [ "$res" != - ] && res_args=(--resolution "$res")
    name="$(basename "$scene" .toml)-${res/-/default}"
    for t in $budgets; do
        for m in $methods; do
            prefix="$out/$name-$m-${t}s"
            rm -f "$prefix.json" "$prefix.exr" "$prefix.png"
            set +e
            /usr/bin/time -f "%e %U %S" -o "$prefix.time" "$bin" render "$scene" --method "$m" \
                ${res_args[@]+"${res_args[@]}"} --time "${t}s" --quiet --out "$prefix" \
                ${threads[@]+"${threads[@]}"} > "$prefix.log" 2>&1
            rc=$?
            set -e
            read -r wall user sys < <(tail -n 1 "$prefix.time")
            cpu=$(echo "$user + $sys" | bc -l)
            cw=$(echo "scale=2; $cpu / ($wall + 0.001)" | bc -l)
            if [ "$rc" = 0 ] && [ -f "$prefix.json" ]; then
                passes=$(jq '.passes - .first_pass' "$prefix.json")
                pass_s=$(jq '(.timings.render_s / ([.passes - .first_pass, 1] | max))' "$prefix.json")
                cut=$(jq '.passes_cut // 0' "$prefix.json")
                phases=$(jq -r '[.phases[] | "\(.phase | gsub(" "; "-"))=\(.wall_s * 100 | round / 100)\(if .stopped then "*" else "" end)"] | join(" ")' "$prefix.json")
                verdict=$(echo "$wall $t $pass_s" | awk '{ if ($1 <= $2 * 1.02) print "within";
                    else if ($1 <= $2 * 1.02 + $3) print "+1 pass"; else print "OVER" }')
            else
                passes=-; pass_s=-; cut=-
                phases="rc $rc: $(grep -m1 -o 'error: .*' "$prefix.log" | cut -c1-160)"
                verdict=$(echo "$wall" | awk '{ print ($1 < 1.0) ? "refused" : "FAILED" }')
            fi
            printf '%-32s %-7s %5s %7.2f %7.2f %5s %6s %8.3f %4s %-9s %s\n' \
                "$name" "$m" "$t" "$wall" "$cpu" "$cw" "$passes" "${pass_s/-/0}" "$cut" "$verdict" "$phases"
        done
    done
done
