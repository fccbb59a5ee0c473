#!/bin/bash
# ab.sh BASE NEW: alternated single-thread pt-cf renders, CPU seconds (user + sys) of each
S=scenes/external/sms-sphere/scene.xml; P=scenes/external/sms-pool/scene.xml
BASE=$(realpath $1); NEW=$(realpath $2); cd "$(dirname "$0")/../.."; mkdir -p /tmp/ab
for r in 1 2 3; do for b in base new; do B=$BASE; [ $b = new ] && B=$NEW
  /usr/bin/time -f "sphere $b %U %S" $B render $S --method pt-cf --resolution 480x270 --spp 64 --seed 1 --threads 1 --quiet --out /tmp/ab/s-$b-$r 2>&1 >/dev/null | tail -1
done; done
for r in 1 2 3; do for b in base new; do B=$BASE; [ $b = new ] && B=$NEW
  /usr/bin/time -f "pool $b %U %S" $B render $P --method pt-cf --resolution 480x270 --spp 8 --seed 1 --threads 1 --quiet --out /tmp/ab/p-$b-$r 2>&1 >/dev/null | tail -1
done; done
