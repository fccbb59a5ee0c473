#!/usr/bin/env bash
# Fuzz every parser for SECONDS (default 600) and print, per parser, the inputs run, how many
# loaded, and the panics, hangs and aborts: scene TOML, Mitsuba XML, PLY, the texture decoders
# (PNG, JPEG, OpenEXR, Radiance HDR, read by a scene), OBJ with UVs, rendered EXRs as `diff`
# and `compare` read them, checkpoints (payloads forged with a valid checksum) and the command
# line. The inputs are seeded mutations of files from the repository (tests/scene_fuzz.rs says
# which and how); each runs in-process on a worker thread with a 10 s limit (past it: a hang,
# the worker abandoned). An abort (or any death by a signal) ends the test process: this script
# then reads which input was running from the state file, counts the abort, keeps the input's
# place (FORMAT ROUND CASE: rerun with FORECAST_FUZZ_FIRST_ROUND=ROUND) and goes on from the next
# round. Runs niced, one input at a time. The short version is in the suite
# (`cargo test --release --test scene_fuzz`).
# Usage: bash scripts/fuzz.sh [SECONDS]     (exit 1 if anything was found)
set -uo pipefail
cd "$(dirname "$0")/.."
secs="${1:-600}"
dir="$(mktemp -d "${TMPDIR:-/tmp}/fuzz.XXXXXX")"
echo "== building tests/scene_fuzz.rs (not counted in the $secs s)"
nice -n 19 cargo test --release --test scene_fuzz --no-run >"$dir/build.log" 2>&1 || {
    cat "$dir/build.log" >&2
    exit 1
}
start=$(date +%s)
round=0
run=0
: >"$dir/aborts"
while :; do
    left=$((secs - ($(date +%s) - start)))
    [ "$left" -gt 0 ] || break
    run=$((run + 1))
    state="$dir/state$run"
    FORECAST_FUZZ_SECS="$left" FORECAST_FUZZ_FIRST_ROUND="$round" FORECAST_FUZZ_STATE="$state" RAYON_NUM_THREADS=1 \
        nice -n 19 cargo test --release --test scene_fuzz -- --ignored --exact fuzz_for_a_while --nocapture \
        --test-threads=1 >"$dir/log$run" 2>&1
    rc=$?
    if grep -q "0 aborts (the process ran to the end)" "$dir/log$run"; then
        grep "^FINDING" -A3 "$dir/log$run" | head -40
        break
    fi
    if [ ! -s "$state" ]; then
        echo "fuzz: the test process ended (rc $rc) before any input:" >&2
        tail -20 "$dir/log$run" >&2
        exit 1
    fi
    read -r fmt r c <"$state"
    why="$(grep -E "signal|memory allocation|overflow|abort" "$dir/log$run" | head -2 | tr '\n' ' ')"
    echo "$fmt $r $c rc=$rc $why" >>"$dir/aborts"
    echo "ABORT: $fmt, round $r, case $c (rc $rc): $why (rerun: FORECAST_FUZZ_FIRST_ROUND=$r)"
    round=$((r + 1))
done
echo
echo "== $secs s of fuzzing ($run test process(es); logs in $dir)"
printf '%-11s %10s %10s %7s %6s %7s %10s\n' parser inputs loaded panics hangs aborts "slowest s"
cat "$dir"/state*.counts 2>/dev/null | awk -v ab="$dir/aborts" '
    BEGIN { while ((getline l < ab) > 0) { split(l, ff, " "); a[ff[1]]++ } }
    $1 != "rounds" { if (!($1 in n)) order[++k] = $1; n[$1] += $2; ld[$1] += $3; p[$1] += $4; h[$1] += $5;
                     if ($6 > w[$1]) w[$1] = $6; tp += $4; th += $5 }
    END { for (i = 1; i <= k; i++) { f = order[i]; ta += a[f]
            printf "%-11s %10d %10d %7d %6d %7d %10.3f\n", f, n[f], ld[f], p[f], h[f], a[f], w[f] }
          exit (tp + th + ta > 0) }'
