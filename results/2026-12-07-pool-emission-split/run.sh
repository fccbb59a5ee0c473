#!/bin/bash
# pt-cf and pt on the pool with the default emission splitting (16) against none (1): per-sample
# variance (exact) and CPU seconds per sample (1 thread)
F=${F:-/work/main/target/release/forecast}
S=/work/main/scenes/external/sms-pool/scene.xml
mkdir -p out
for s in 1 2 3 4 5 6; do for m in pt-cf pt; do for k in 16 1; do
  /usr/bin/time -f "%U %S" -o out/$m-k$k-s$s.time $F render $S --method $m --resolution 120x68 --spp 32 --threads 1 --seed $s --quiet --emission-split $k --out out/$m-k$k-s$s
done; done; done
