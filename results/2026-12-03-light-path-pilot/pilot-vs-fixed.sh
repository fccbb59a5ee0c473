#!/usr/bin/env bash
# The light-path pilot against the fixed 1 path per pixel of results/2026-12-03-light-path-pilot.md
# (stop 40): pt-cf --light-path-pilot (the pilot's count) and with --light-paths = 1 per
# pixel, 60 s, seeds 1-3, alternating seed by seed. FORECAST names the binary (the recorded run:
# the work tree before 9eb2449, where no --light-paths meant the pilot).
#   FORECAST=BIN bash results/2026-12-03-light-path-pilot/pilot-vs-fixed.sh   (writes out/pilot/)
set -u
cd "$(dirname "$0")/../.."
BIN="${FORECAST:-target/release/forecast}"
run() { # NAME SCENE RES N SEED   (N = "rule": --light-path-pilot)
  local d=out/pilot/$1-$4; mkdir -p "$d"
  local o=$d/pt-cf-$5
  [ -f "$o.exr" ] && return
  local lp=(--light-paths "$4"); [ "$4" = rule ] && lp=(--light-path-pilot)
  /usr/bin/time -f '%e %U %S' -o "$o.time" "$BIN" render "$2" --method pt-cf "${lp[@]}" --time 60s --resolution "$3" --threads 2 --max-depth 64 --seed "$5" --out "$o" --quiet
}
for s in 1 2 3; do
  for n in rule 65536; do run ring scenes/ring.toml 256x256 $n $s; done
  for n in rule 65536; do run cornell scenes/cornell-box.toml 256x256 $n $s; done
  for n in rule 49152; do run sms scenes/external/sms-ring/ring.xml 256x192 $n $s; done
  for n in rule 57600; do run fig results/2026-12-03-auto-rule/figurines-diffuse-table.toml 320x180 $n $s; done
done
echo done > out/pilot/DONE
