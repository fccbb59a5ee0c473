#!/usr/bin/env bash
# MPI scaling on one node (issue: 1 rank x 2 threads vs 2 ranks x 1 thread vs 1 rank x 1 thread),
# in samples/s of the render phase for pt and iws-cf on cornell-box, plus the iws-cf broadcast
# size and time on ring (1M forecast photons). Needs the MPI build:
#   cargo build --release --features mpi --target-dir target/mpi
# Usage: scripts/scaling.sh [SPP_PT] [SPP_CF]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/mpi/release/forecast
[ -x "$bin" ] || CARGO_TARGET_DIR=target/mpi cargo build --release --features mpi --quiet
spp_pt="${1:-64}"
spp_cf="${2:-4}"
out="$(mktemp -d)"
sps() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['samples_per_s'])" "$1"; }
for m in pt iws-cf; do
    spp=$spp_pt; [ "$m" = iws-cf ] && spp=$spp_cf
    args=(render scenes/cornell-box.toml --method "$m" --spp "$spp" --resolution 320x320 --seed 1 --quiet)
    "$bin" "${args[@]}" --threads 1 --out "$out/$m-1x1"
    "$bin" "${args[@]}" --threads 2 --out "$out/$m-1x2"
    RAYON_NUM_THREADS=1 mpirun -n 2 "$bin" "${args[@]}" --threads 1 --out "$out/$m-2x1"
    a=$(sps "$out/$m-1x1.json"); b=$(sps "$out/$m-1x2.json"); c=$(sps "$out/$m-2x1.json")
    python3 -c "
a,b,c=$a,$b,$c
print(f'$m: 1x1 {a:,.0f}  1x2 {b:,.0f}  2x1 {c:,.0f} samples/s;  2x1 / 1x2 = {c/b:.3f}, 1x2 / 1x1 = {b/a:.3f}')"
done
RAYON_NUM_THREADS=1 mpirun -n 2 "$bin" render scenes/ring.toml --method iws-cf --spp 2 --resolution 64x64 --quiet --threads 1 --out "$out/ring-bcast"
python3 -c "
import json; j=json.load(open('$out/ring-bcast.json'))
for r in j['per_rank']:
    print(f\"ring iws-cf rank {r['rank']}: bytes broadcast {r['bytes_broadcast']:,}, preprocess {r['preprocess_s']:.2f} s, broadcast {r['broadcast_s']:.3f} s\")"
rm -rf "$out"
