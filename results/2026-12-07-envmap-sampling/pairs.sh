#!/bin/bash
# pairs.sh OUTDIR OLD NEW N [EXTRA...]: N pairs of `pt` renders of the pool (192x108, 128 spp,
# 1 thread, seed 1), the two binaries alternated (old first in odd pairs, new first in even ones),
# each under `perf record -e cpu-clock -F 999 -g` and `/usr/bin/time -f "%U %S"`; prints
# "pair binary user+sys envmap-share" per run (envmap share: split.py's class).
OUT=$1; OLD=$2; NEW=$3; N=$4; shift 4
SCENE=${SCENE:-scenes/external/sms-pool/scene.xml}
HERE=$(dirname "$0")
mkdir -p "$OUT"
for p in $(seq 1 "$N"); do
  if [ $((p % 2)) = 1 ]; then ORDER="old new"; else ORDER="new old"; fi
  for which in $ORDER; do
    B=$OLD; [ $which = new ] && B=$NEW
    tag=$OUT/$which-$p
    /usr/bin/time -o "$tag.time" -f "%U %S" perf record -q -e cpu-clock -F 999 -g -o "$tag.perf" \
      "$B" render "$SCENE" --method pt --resolution 192x108 --spp 128 --threads 1 --seed 1 --quiet "$@" \
      --out "$tag" >/dev/null 2>"$tag.err"
    env=$(python3 "$HERE/split.py" "$tag.perf" | awk '/^envmap/ {print $2}')
    echo "$p $which $(awk '{print $1 + $2}' "$tag.time") $env"
  done
done
