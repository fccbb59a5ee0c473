#!/bin/bash
# The twenty-first stop's quiet-machine measurements, in order: the SMS scenes at equal time (60 s,
# 3 seeds) with every peer rendering forecast's box pixel (PIXEL_FILTER=box, the default since
# results/2026-12-08-pixel-filter.md), then the pool's speed row. Run from the repository root with
# nothing else running; writes out/q21/.
set -x
mkdir -p out/q21
export MITSUBA_VENV=/work/mitsuba-venv LUXCORE_VENV=/work/luxcore-venv THREADS=2 FORECAST=target/release/forecast
BLENDER_VENV=/work/blender-venv PEERS="path" LUXCORE="" CYCLES="cycles" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-pool/scene.xml 480x270 60 3 out/q21/et-pool > out/q21/et-pool.txt 2>&1
PEERS="path ptracer" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-sphere/scene.xml 480x270 60 3 out/q21/et-sms-sphere > out/q21/et-sms-sphere.txt 2>&1
PEERS="path ptracer" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-plane/scene.xml 480x270 60 3 out/q21/et-sms-plane > out/q21/et-sms-plane.txt 2>&1
PEERS="path ptracer" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-sphere-smooth/scene.xml 480x270 60 3 out/q21/et-sms-sphere-smooth > out/q21/et-sms-sphere-smooth.txt 2>&1
FORECAST_DEFAULT=target/release/forecast BACKENDS=wide SCENES="scenes/external/sms-pool/scene.xml 384x216" OUT=out/q21/bench \
  scripts/bench-set-vs-mitsuba.sh 15 3 > out/q21/bench-pool.txt 2>&1
echo done
# after the suite: sms-sphere at 4 minutes (ptracer renders neither of its target crops: path only)
# PEERS="path" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-sphere/scene.xml 480x270 240 3 out/q21/et-sms-sphere-240
