#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run calls this script).
#   1. installs MPICH (+ libclang for bindgen) if missing — needs root; FORECAST_NO_MPI=1 skips MPI
#   2. cargo test --release                    (unit + integration tests, single process)
#   3. cargo test --release --features mpi --test mpi   (2-rank tests under mpirun; target/mpi)
#   4. scripts/check-mitsuba.sh                (pt vs the independent Mitsuba 3 reference)
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${FORECAST_NO_MPI:-0}" != "1" ]; then
    if [ "$(id -u)" = "0" ] || command -v sudo >/dev/null 2>&1; then
        bash .ci/install-mpi.sh
    else
        echo "warning: not root and no sudo: skipping the MPI install" >&2
    fi
fi

echo "== cargo test --release"
cargo test --release

if [ "${FORECAST_NO_MPI:-0}" != "1" ] && command -v mpirun >/dev/null 2>&1; then
    echo "== cargo test --release --features mpi --test mpi (2 ranks)"
    # a separate target dir keeps the MPI binary from replacing the default one
    CARGO_TARGET_DIR=target/mpi cargo test --release --features mpi --test mpi
else
    echo "warning: MPI tests skipped (mpirun not found)" >&2
fi

echo "== Mitsuba agreement check"
SPP="${SPP:-1024}" bash scripts/check-mitsuba.sh
