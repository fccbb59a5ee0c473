#!/bin/bash
# ident.sh BIN OUTDIR [ACCEL]: small renders, sha256 of the EXRs
BIN=$(realpath $1); OUT=$(realpath -m $2); A=${3:-obvhs}; mkdir -p $OUT; cd "$(dirname "$0")/../.."
P=scenes/external/sms-pool/scene.xml
run() { $BIN render "$@" --accel $A --seed 7 --threads 2 --quiet >/dev/null 2>>$OUT/err || echo "FAIL $*"; }
run $P --method pt --resolution 96x54 --spp 4 --out $OUT/pool-pt
run $P --method pt-cf --resolution 96x54 --spp 2 --out $OUT/pool-ptcf
run scenes/ring.toml --method pt --resolution 48x48 --spp 8 --out $OUT/ring-pt
run scenes/ring.toml --method pt-cf --resolution 48x48 --spp 4 --out $OUT/ring-ptcf
run scenes/cornell-box.toml --method iws-cf --resolution 48x48 --spp 4 --out $OUT/cb-iwscf
run scenes/water-caustic.toml --method pt --resolution 48x48 --spp 4 --out $OUT/water-pt
(cd $OUT && sha256sum *.exr > sums.txt)
