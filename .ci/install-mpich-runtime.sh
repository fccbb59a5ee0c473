#!/usr/bin/env bash
# The MPI runtime of the multi-host tests (scripts/mpi-netns.sh): MPICH 5.0.2 from its PyPI wheel
# (`pip install mpich`: hydra's mpiexec, libmpi.so.12 with the ch4:ucx and ch4:ofi netmods, its own
# UCX and libfabric), in a virtual environment at $FORECAST_MPICH_RUNTIME (default
# /opt/forecast-mpich-5.0.2). Prints the folder on its last line.
#
# Why: Debian's MPICH 4.0.2, which builds the `mpi` feature (.ci/install-mpi.sh) and runs the
# 2-rank tests, hangs in MPI_Finalize when ranks on different hosts talk over UCX's TCP
# (docs/mpi.md). The binary built against it runs unchanged on this runtime: MPICH keeps its ABI
# (libmpi.so.12, the MPICH ABI compatibility initiative), and the link libmpich.so.12 ->
# libmpi.so.12 made here lets the loader find the library under the name the binary asks for.
# Use: PATH="$dir/bin:$PATH" LD_LIBRARY_PATH="$dir/lib" mpiexec ... target/mpi/release/forecast ...
#
# Idempotent: when the runtime is there it changes nothing. Needs python3 with venv and pip (on
# Debian's own python3: apt-get install python3-venv, done here as root) and the PyPI registry.
set -euo pipefail
version=5.0.2
dir="${FORECAST_MPICH_RUNTIME:-/opt/forecast-mpich-$version}"

have() {
    [ -x "$dir/bin/mpiexec" ] && [ -e "$dir/lib/libmpich.so.12" ] \
        && "$dir/bin/mpichversion" 2>/dev/null | grep -q "Version: *$version\$"
}
if have; then
    echo "install-mpich-runtime: MPICH $version already in $dir"
    echo "$dir"
    exit 0
fi
command -v python3 >/dev/null 2>&1 || bash "$(dirname "$0")/apt-install.sh" install-mpich-runtime python3
if ! python3 -m venv "$dir" 2>/dev/null; then
    rm -rf "$dir"
    bash "$(dirname "$0")/apt-install.sh" install-mpich-runtime python3-venv python3-pip
    python3 -m venv "$dir"
fi
"$dir/bin/python3" -m pip install --quiet --disable-pip-version-check "mpich==$version"
ln -sf libmpi.so.12 "$dir/lib/libmpich.so.12"
if ! have; then
    echo "install-mpich-runtime: pip installed mpich==$version but $dir/bin/mpiexec or" \
        "$dir/lib/libmpi.so.12 is not usable" >&2
    exit 1
fi
echo "install-mpich-runtime: MPICH $version in $dir"
echo "$dir"
