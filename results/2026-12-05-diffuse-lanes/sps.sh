#!/usr/bin/env bash
# sps.sh SCENE RES SPP RUNS METHOD "ARGS" BIN... : samples per CPU-second per binary, alternating
scene=$1; res=$2; spp=$3; runs=$4; method=$5; args=$6; shift 6
w=${res%x*}; h=${res#*x}
for r in $(seq 1 $runs); do for b in "$@"; do
  /usr/bin/time -f '%U %S' -o /tmp/sps.time $b render $scene --method $method --resolution $res --spp $spp --threads 2 --seed 1 $args --out /tmp/sps-out >/dev/null 2>&1
  read u s < /tmp/sps.time
  echo "$(basename $b) run$r $(python3 -c "print('%.4f' % ($w*$h*$spp/($u+$s)/1e6))") Msamples/cpu-s"
done; done
