#!/usr/bin/env bash
# Interleaved samples-per-second of several builds, run by run (issue #33).
#   BINS="base=/path/to/forecast new=/path/to/forecast" [METHOD=pt] [ACCEL=embree] \
#       bash results/2026-12-04-lazy-hits/interleaved.sh SCENE RES SECONDS RUNS
# Prints "label run samples_per_s" per render (2 threads, seed = run).
set -euo pipefail
scene=$1; res=$2; sec=$3; runs=$4
for r in $(seq 1 "$runs"); do
  for lb in $BINS; do
    label=${lb%%=*}; bin=${lb#*=}
    "$bin" render "$scene" --method "${METHOD:-pt}" --accel "${ACCEL:-embree}" --resolution "$res" \
        --time "${sec}s" --threads 2 --quiet --seed "$r" --out /tmp/interleaved >/dev/null 2>&1
    python3 -c "import json; j = json.load(open('/tmp/interleaved.json')); print('$label', $r, round(j['samples_per_s']))"
  done
done
