#!/bin/bash
# sms-sphere pt-cf: --split 16 (default) / 4 / 1; per-sample variance over 6 seeds and CPU per sample
cd "$(dirname "$0")"
F=$(realpath ${F:-../../target/release/forecast})
S=$(realpath ../../scenes/external/sms-sphere/scene.xml)
mkdir -p out && cd out
A="--method pt-cf --resolution 120x68 --threads 1 --quiet --light-paths 4080"
for s in 1 2 3 4 5 6; do for k in 16 4 1; do
  /usr/bin/time -f "%U %S" -o k$k-s$s.time $F render $S $A --spp 64 --seed $s --split $k --out k$k-s$s 2>/dev/null
done; done
for k in 16 4 1; do for n in 8 264; do
  /usr/bin/time -f "%U %S" -o cost-k$k-n$n.time $F render $S $A --spp $n --seed 9 --split $k --out cost-k$k-n$n 2>/dev/null
done; done
echo done > done
