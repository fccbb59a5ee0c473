#!/bin/bash
# rounds.sh OUTDIR N "LABEL=BIN ..." [EXTRA...]: N rounds of `pt` renders of the pool (192x108,
# 128 spp, 1 thread, seed 1), one per binary per round, the order rotated each round so no binary
# always runs first; each under `perf record -e cpu-clock -F 999 -g` and `/usr/bin/time -f "%U %S"`.
# Prints "round label user+sys envmap-share" per run (envmap share: split.py's class).
OUT=$1; N=$2; BINS=($3); shift 3
SCENE=${SCENE:-scenes/external/sms-pool/scene.xml}
HERE=$(dirname "$0")
mkdir -p "$OUT"
for r in $(seq 1 "$N"); do
  k=${#BINS[@]}
  for s in $(seq 0 $((k - 1))); do
    lb=${BINS[$(((s + r - 1) % k))]}; label=${lb%%=*}; B=${lb#*=}
    tag=$OUT/$label-$r
    /usr/bin/time -o "$tag.time" -f "%U %S" perf record -q -e cpu-clock -F 999 -g -o "$tag.perf" \
      "$B" render "$SCENE" --method pt --resolution 192x108 --spp 128 --threads 1 --seed 1 --quiet "$@" \
      --out "$tag" >/dev/null 2>"$tag.err"
    env=$(python3 "$HERE/split.py" "$tag.perf" | awk '/^envmap/ {print $2}')
    echo "$r $label $(awk '{print $1 + $2}' "$tag.time") $env"
  done
done
