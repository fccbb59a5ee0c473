#!/bin/bash
# the quiet-machine measurements of the nineteenth stop, in order
set -x
cd /work/main
export MITSUBA_VENV=/work/mitsuba-venv LUXCORE_VENV=/work/luxcore-venv BLENDER_VENV=/work/blender-venv THREADS=2
FORECAST_OBVHS=target/release/forecast FORECAST_EMBREE=target/embree/release/forecast OUT=out/q19/bench scripts/bench-set-vs-mitsuba.sh 15 3 > out/q19/bench.txt 2>&1
FORECAST_ARGS="--emission-split 1" PEERS="path" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-pool/scene.xml 480x270 60 3 out/q19/et-pool-k1 > out/q19/et-pool-k1.txt 2>&1
for sc in sms-sphere sms-plane; do
  PEERS="path ptracer" LUXCORE="bidir" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/$sc/scene.xml 480x270 60 3 out/q19/et-$sc > out/q19/et-$sc.txt 2>&1
done
echo done
