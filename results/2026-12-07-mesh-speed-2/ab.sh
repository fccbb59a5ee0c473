#!/bin/bash
# ab.sh SPP RES BIN1 BIN2 ...: pt CPU seconds (user+sys), alternating, 1 thread
SPP=$1; RES=$2; shift 2
for rep in 1 2; do for B in "$@"; do
 /usr/bin/time -o /tmp/s2/ab-time -f "%U %S" $B render ${SCENE:-/work/wt/speed2/scenes/external/sms-pool/scene.xml} --method pt --accel ${ACCEL:-obvhs} --resolution $RES --spp $SPP --threads 1 --seed 1 --quiet $EXTRA --out /tmp/s2/ab-out >/dev/null 2>/tmp/s2/ab-err
 echo "$(basename $B) $SPP $(cat /tmp/s2/ab-time)" | awk '{print $1, $2, $3+$4}'
done; done
