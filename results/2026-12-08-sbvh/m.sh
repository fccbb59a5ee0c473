#!/bin/bash
# m.sh TAG BIN SCENE RES SPP [env...]
TAG=$1; BIN=$2; S=$3; R=$4; N=$5; shift 5
cd /work/wt/sbvh
env "$@" /usr/bin/time -f "%U %S" -o /tmp/sbm/$TAG.time perf record -q -e cpu-clock -F 999 -g -o /tmp/sbm/$TAG.perf $BIN render $S --method pt --resolution $R --spp $N --threads 1 --seed 1 --quiet --emission-split 1 --out /tmp/sbm/x-$TAG >/dev/null 2>&1
perf report -i /tmp/sbm/$TAG.perf --no-children --sort symbol --stdio -F overhead,sample,symbol -g none 2>/dev/null | grep -v "^#" | grep "%" > /tmp/sbm/$TAG.txt
tr=$(grep -E "accel::World::(closest|occluded|intersect)|wide::(WideBvh|node_hits)|bvh8" /tmp/sbm/$TAG.txt | grep -v build | awk '{s+=$2} END {print s}')
bl=$(grep -E "wide::build" /tmp/sbm/$TAG.txt | awk '{s+=$2} END {print s+0}')
tot=$(awk '{s+=$2} END {print s}' /tmp/sbm/$TAG.txt)
echo "$TAG trav=$tr build=$bl total=$tot cpu=$(cat /tmp/sbm/$TAG.time | tr '\n' ' ') $*"
