#!/usr/bin/env bash
# Install MPICH + headers + libclang, needed only for `cargo build --features mpi`.
#
# Why each package:
#   mpich        mpirun / mpiexec (Hydra launcher) and the runtime library
#   libmpich-dev mpi.h, mpicc, libmpich.so and mpich.pc (found via pkg-config by mpi-sys)
#   libclang-dev libclang.so plus clang's builtin headers (stddef.h); mpi-sys runs bindgen
#                in its build script, which loads libclang at build time
#
# Idempotent: when everything is already present it changes nothing and runs no apt command.
# Needs root (or sudo) only when something is missing. Debian/Ubuntu only.
set -euo pipefail

have_mpi() {
    command -v mpirun >/dev/null 2>&1 || return 1
    command -v mpicc >/dev/null 2>&1 || return 1
    # The MPI library and header must both exist; mpicc -show names the include/lib flags.
    pkg-config --exists mpich 2>/dev/null || return 1
    local incdir
    incdir="$(pkg-config --variable=includedir mpich 2>/dev/null || true)"
    [ -n "$incdir" ] && [ -f "$incdir/mpi.h" ] || return 1
    # Make sure mpirun belongs to MPICH, not OpenMPI (the two fight over the alternatives).
    mpirun --version 2>&1 | grep -i 'HYDRA' >/dev/null || return 1
    return 0
}

have_libclang() {
    # libclang-dev ships the unversioned libclang.so symlink and clang's builtin headers.
    dpkg-query -W -f='${Status}' libclang-dev 2>/dev/null | grep 'install ok installed' >/dev/null
}

if have_mpi && have_libclang; then
    echo "install-mpi: MPICH and libclang already installed, nothing to do"
    mpirun --version 2>&1 | sed -n 1,2p  # sed reads it all: no SIGPIPE under pipefail
    exit 0
fi

bash "$(dirname "$0")/apt-install.sh" install-mpi mpich libmpich-dev libclang-dev

if ! have_mpi; then
    echo "install-mpi: installed packages but MPICH is still not usable" >&2
    echo "  (is OpenMPI installed and owning the mpirun/mpicc alternatives?)" >&2
    exit 1
fi
if ! have_libclang; then
    echo "install-mpi: libclang-dev did not install" >&2
    exit 1
fi
echo "install-mpi: done"
mpirun --version 2>&1 | sed -n 1,2p  # sed reads it all: no SIGPIPE under pipefail
