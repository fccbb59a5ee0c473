#!/bin/bash
# run.sh TAG BASE NEW PAIRS: perf record -e cpu-clock of the three renders, base and new alternated
TAG=$1; A=$2; B=$3; N=${4:-3}; cd "$(dirname "$0")/../.."
P=scenes/external/sms-pool/scene.xml; S=scenes/external/sms-sphere/scene.xml
declare -A CFG
CFG[poolpt]="$P --method pt --emission-split 1 --resolution 480x270 --spp 48"
CFG[poolptcf]="$P --method pt-cf --resolution 480x270 --spp 6"
CFG[sphereptcf]="$S --method pt-cf --resolution 480x270 --spp 16"
CFG[pooldef]="$P --method pt --resolution 480x270 --spp 4"
for c in ${CFGS:-poolpt poolptcf sphereptcf}; do
  for i in $(seq 1 $N); do
    for b in base new; do
      bin=$A; [ $b = new ] && bin=$B
      perf record -q -e cpu-clock -o ${PERF_DIR:-/tmp/pfperf}/$TAG-$c-$b-$i.data -- /usr/bin/time -o ${PERF_DIR:-/tmp/pfperf}/$TAG-$c-$b-$i.time -f "%U %S" \
        $bin render ${CFG[$c]} --seed 7 --threads 1 --quiet --out /tmp/pfperf/out-$b >/dev/null 2>&1
    done
  done
done
