#!/bin/bash
# ident-split.sh BIN OUTDIR: renders with many split pixels; split_pixels from the JSON and sha256 of the EXRs
BIN=$(realpath $1); OUT=$(realpath -m $2); mkdir -p $OUT; cd "$(dirname "$0")/../.."
run() { $BIN render "$@" --threads 2 --quiet >/dev/null 2>>$OUT/err || echo "FAIL $*"; }
run scenes/figurines.toml --method pt-cf --resolution 256x144 --spp 2 --seed 3 --out $OUT/fig-ptcf
run scenes/external/sms-pool/scene.xml --method pt --resolution 96x54 --spp 2 --seed 3 --emission-split 16 --out $OUT/pool-split
cd $OUT && sha256sum *.exr > sums.txt
for j in *.json; do echo "$j $(python3 -c "import json,sys; p=json.load(open('$j'))['pixel_sampler']; print(p['split_pixels'], p['probe_stopped'], p['probe_s'])")"; done > split.txt
