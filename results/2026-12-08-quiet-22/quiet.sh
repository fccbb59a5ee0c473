#!/bin/bash
# The twenty-second stop's quiet-machine measurements, in order: the speed rows of every scene
# (issue #64), then sms-sphere and the pool at equal time (60 s, 3 seeds; issue #62), every peer
# on forecast's box pixel. Run from the repository root with nothing else running; writes out/q22/.
set -x
mkdir -p out/q22
export MITSUBA_VENV=/work/mitsuba-venv LUXCORE_VENV=/work/luxcore-venv THREADS=2 FORECAST=target/release/forecast
FORECAST_DEFAULT=target/release/forecast BACKENDS=wide OUT=out/q22/bench \
  scripts/bench-set-vs-mitsuba.sh 15 3 > out/q22/bench.txt 2>&1
PEERS="path" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-sphere/scene.xml 480x270 60 3 out/q22/et-sms-sphere > out/q22/et-sms-sphere.txt 2>&1
BLENDER_VENV=/work/blender-venv PEERS="path" LUXCORE="" CYCLES="cycles" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-pool/scene.xml 480x270 60 3 out/q22/et-pool > out/q22/et-pool.txt 2>&1
echo done60
# then sms-sphere at 4 minutes (ptracer renders neither of its target crops: path only)
PEERS="path" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-sphere/scene.xml 480x270 240 3 out/q22/et-sms-sphere-240 > out/q22/et-sms-sphere-240.txt 2>&1
echo done240
