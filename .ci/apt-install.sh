#!/usr/bin/env bash
# apt-get install of Debian packages as root, or through sudo: the one install step of
# .ci/install-mpi.sh and .ci/install-embree.sh.
#   bash .ci/apt-install.sh WHO PACKAGE...     (WHO names the caller in the error message)
# Exits 1 when neither root nor sudo is available, or when apt-get fails.
set -euo pipefail
who="$1"; shift

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        SUDO="sudo"
    else
        echo "$who: need root (or sudo) to install $*" >&2
        exit 1
    fi
fi

export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends "$@"
