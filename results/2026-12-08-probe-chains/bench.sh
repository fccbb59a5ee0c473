#!/bin/bash
# bench.sh BEFORE AFTER OUTDIR: 3 alternated pairs per scene of
# `render SCENE --method pt --spp 1 --threads 1 --seed 1 --quiet`; one line per run:
# scene who user_s sys_s probe_s split_pixels
A=$(realpath $1); B=$(realpath $2); OUT=$(realpath -m $3); mkdir -p $OUT; cd "$(dirname "$0")/../.."
for s in "scenes/ring.toml 256x256" "scenes/external/sms-pool/scene.xml 384x216" "scenes/figurines.toml 640x360" "scenes/cornell-box.toml 640x640"; do
  set -- $s
  for pair in 1 2 3; do
    for who in before after; do
      bin=$A; [ $who = after ] && bin=$B
      n=$(basename $(dirname $1))-$(basename $1 .toml)
      /usr/bin/time -f "%U %S" -o $OUT/t $bin render $1 --resolution $2 --method pt --spp 1 --threads 1 --seed 1 --quiet --out $OUT/r >/dev/null 2>$OUT/err
      echo "$n $2 $who $(cat $OUT/t) $(python3 -c "import json; p=json.load(open('$OUT/r.json'))['pixel_sampler']; print(round(p['probe_s'],3), p['split_pixels'], p['probe_stopped'])")"
    done
  done
done
