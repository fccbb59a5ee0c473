#!/bin/bash
# load.sh A B N: load_s of the pool (2 threads), A and B alternated
cd "$(dirname "$0")/../.."
for i in $(seq 1 ${3:-4}); do for b in $1 $2; do
  $b render scenes/external/sms-pool/scene.xml --method pt --resolution 96x54 --spp 1 --threads 2 --quiet --out /tmp/pfperf/load-$(basename $b) >/dev/null 2>&1
  python3 -c "import json;d=json.load(open('/tmp/pfperf/load-$(basename $b).json'));print('$(basename $b)', d['timings']['load_s'])"
done; done
