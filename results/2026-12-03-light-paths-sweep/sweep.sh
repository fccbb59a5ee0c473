#!/usr/bin/env bash
# The light-paths-per-pixel sweep of results/2026-12-03-light-paths-sweep.md (stop 39).
# The recorded run used the release binary of 643fb8f; FORECAST names another.
#   FORECAST=BIN bash results/2026-12-03-light-paths-sweep/sweep.sh   (writes out/lp2/)
set -u
cd "$(dirname "$0")/../.."
BIN="${FORECAST:-target/release/forecast}"
run() { # NAME SCENE RES N SEED
  local d=out/lp2/$1-$4; mkdir -p "$d"
  local o=$d/pt-cf-$5
  [ -f "$o.exr" ] && return
  /usr/bin/time -f '%e %U %S' -o "$o.time" "$BIN" render "$2" --method pt-cf --light-paths "$4" --time 60s --resolution "$3" --threads 2 --max-depth 64 --seed "$5" --out "$o" --quiet
}
for s in 1 2 3; do
  for n in 65536 131072 262144; do run sms scenes/external/sms-ring/ring.xml 256x192 $((n*3/4)) $s; done
  for n in 65536 131072 262144; do run ring scenes/ring.toml 256x256 $n $s; done
  for n in 65536 131072 262144; do run cornell scenes/cornell-box.toml 256x256 $n $s; done
  for n in 28800 57600 115200; do run fig results/2026-12-03-auto-rule/figurines-diffuse-table.toml 320x180 $n $s; done
done
echo done > out/lp2/DONE
