#!/bin/bash
# after quiet.sh: sms-sphere-smooth (no normal map), is Mitsuba ptracer's low shadow-crop mean on sms-sphere the normal map?
while pgrep -f quiet.sh >/dev/null; do sleep 5; done
cd /work/main
export MITSUBA_VENV=/work/mitsuba-venv THREADS=2
PEERS="path ptracer" LUXCORE="" CYCLES="" scripts/equal-time-vs-mitsuba.sh scenes/external/sms-sphere-smooth/scene.xml 480x270 60 2 out/q19/et-sms-sphere-smooth > out/q19/et-sms-sphere-smooth.txt 2>&1
echo done2
