#!/bin/bash
# hot.sh BEFORE AFTER OUTDIR: the other users of the chain follower (Direct), 3 alternated pairs:
# iws on cornell-box with --emission-split 1 (no probe; prefix_emission and follow_dirac_chain in
# its estimate), pt-cf on figurines (split pixels: prefix_emission for the extra rays); CPU seconds
# and the probe's wall seconds (to subtract)
A=$(realpath $1); B=$(realpath $2); OUT=$(realpath -m $3); mkdir -p $OUT; cd "$(dirname "$0")/../.."
for c in "scenes/cornell-box.toml --method iws --resolution 128x128 --spp 256 --emission-split 1" "scenes/figurines.toml --method pt-cf --resolution 256x144 --spp 32"; do
  for pair in 1 2 3; do
    for who in before after; do
      bin=$A; [ $who = after ] && bin=$B
      /usr/bin/time -f "%U %S" -o $OUT/t $bin render $c --threads 1 --seed 1 --quiet --out $OUT/r >/dev/null 2>$OUT/err
      echo "$(echo $c | cut -d' ' -f1,3) $who $(cat $OUT/t) $(python3 -c "import json; p=json.load(open('$OUT/r.json'))['pixel_sampler']; print(round(p['probe_s'],3), p['split_pixels'])")"
    done
  done
done
