#!/usr/bin/env bash
# results/2026-12-05-pt-cf-wavefront/cfsps.sh SCENE RES SPP RUNS "ARGS" BIN... : pt-cf render-loop
# samples/s (the JSON's samples_per_s), seed 1, 2 threads, the binaries alternating; prints the image mean
scene=$1; res=$2; spp=$3; runs=$4; args=$5; shift 5
for r in $(seq 1 $runs); do for b in "$@"; do
  $b render $scene --method pt-cf --resolution $res --spp $spp --threads 2 --seed 1 $args --out /tmp/cfsps >/dev/null 2>&1
  python3 -c "
import json;d=json.load(open('/tmp/cfsps.json'));print('$(basename $b) run$r', round(d['samples_per_s']/1e6,4), 'Ms/s render_s', round(d['timings']['render_s'],2), 'mean', d['image_mean'])"
done; done
