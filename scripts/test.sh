#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run calls this script).
#   1. installs MPICH (+ libclang for bindgen) if missing — needs root; FORECAST_NO_MPI=1 skips MPI
#   2. cargo test --release                    (unit + integration tests, single process)
#   3. cargo test --release --features mpi --test mpi   (2-rank tests under mpirun; target/mpi), then
#      scripts/mpi-netns.sh: 3 hosts in network namespaces, 2 ranks each, with faults, on the
#      MPICH 5.0.2 runtime it installs (about a minute), where the machine allows (root, `ip netns`);
#      else a loud NOT RUN with the reason. FORECAST_NETNS=0 skips it.
#   4. installs libembree-dev if missing (root/sudo); FORECAST_NO_EMBREE=1 skips Embree, then
#      cargo test --release --features embree --test accel_embree --test wavefront --test pass_groups
#      --test bvh (target/embree; Embree against obvhs, pt image z-tests, the packet queries, the
#      wavefront pt and pass groups bit for bit against their scalar forms, and tests/bvh.rs on
#      the Embree back end)
#   5. scripts/check-mitsuba.sh                (pt vs the independent Mitsuba 3 reference)
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${FORECAST_NO_MPI:-0}" != "1" ]; then
    if [ "$(id -u)" = "0" ] || command -v sudo >/dev/null 2>&1; then
        bash .ci/install-mpi.sh
    else
        echo "warning: not root and no sudo: skipping the MPI install" >&2
    fi
fi

log="$(mktemp)"
trap 'rm -f "$log"' EXIT

echo "== cargo test --release"
cargo test --release 2>&1 | tee -a "$log"

if [ "${FORECAST_NO_MPI:-0}" != "1" ] && command -v mpirun >/dev/null 2>&1; then
    echo "== cargo test --release --features mpi --test mpi (2 ranks)"
    # a separate target dir keeps the MPI binary from replacing the default one
    CARGO_TARGET_DIR=target/mpi cargo test --release --features mpi --test mpi -- --test-threads=1 2>&1 | tee -a "$log"
    # the multi-host tests, wherever this machine can make network namespaces (root, `ip netns`)
    netns_why=""
    if [ "${FORECAST_NETNS:-1}" = "0" ]; then
        netns_why="FORECAST_NETNS=0"
    elif [ "$(id -u)" != "0" ]; then
        netns_why="not root (network namespaces, veths and tc need root)"
    else
        command -v ip >/dev/null 2>&1 || bash .ci/apt-install.sh test.sh iproute2 || true
        if ! command -v ip >/dev/null 2>&1; then
            netns_why="no \`ip\` (iproute2) here"
        elif ! said="$( (ip netns add "fcprobe-$$" && ip link add "fcp$$a" type veth peer name "fcp$$b" \
            && ip link set "fcp$$b" netns "fcprobe-$$" && ip -n "fcprobe-$$" link set "fcp$$b" up) 2>&1)"; then
            # a namespace and a veth pair into it: what scripts/mpi-netns.sh builds for each host
            netns_why="a network namespace with a veth pair cannot be made here: $said"
        fi
        ip link del "fcp$$a" 2>/dev/null || true
        ip netns del "fcprobe-$$" 2>/dev/null || true
        # the ranks' MPI runtime (PyPI's mpich wheel): a machine that cannot fetch it says so
        if [ -z "$netns_why" ] && ! bash .ci/install-mpich-runtime.sh >/dev/null; then
            netns_why="the MPICH 5.0.2 runtime could not be installed (.ci/install-mpich-runtime.sh: python3-venv and PyPI)"
        fi
    fi
    if [ -z "$netns_why" ]; then
        echo "== scripts/mpi-netns.sh (3 hosts in network namespaces, 2 ranks each, with faults)"
        bash scripts/mpi-netns.sh 2>&1 | tee -a "$log"
    else
        echo "" >&2
        echo "############################################################################" >&2
        echo "## NOT RUN: scripts/mpi-netns.sh, the multi-host MPI tests: $netns_why" >&2
        echo "############################################################################" >&2
        echo "" >&2
    fi
else
    echo "warning: MPI tests skipped (mpirun not found)" >&2
fi

embree=0
if [ "${FORECAST_NO_EMBREE:-0}" != "1" ]; then
    if [ "$(id -u)" = "0" ] || command -v sudo >/dev/null 2>&1; then
        bash .ci/install-embree.sh && embree=1
    elif [ -f /usr/include/embree3/rtcore.h ]; then
        embree=1
    else
        echo "warning: not root and no sudo: skipping the Embree install" >&2
    fi
fi
if [ "$embree" = "1" ]; then
    echo "== cargo test --release --features embree --test accel_embree --test wavefront --test pass_groups --test bvh (Embree back end)"
    # a separate target dir keeps the Embree build from replacing the default one
    CARGO_TARGET_DIR=target/embree cargo test --release --features embree --test accel_embree --test wavefront --test pass_groups 2>&1 \
        | tee -a "$log"
    FORECAST_TEST_ACCEL=embree CARGO_TARGET_DIR=target/embree cargo test --release --features embree --test bvh 2>&1 \
        | tee -a "$log"
else
    echo "warning: Embree tests skipped" >&2
fi

echo "== Mitsuba agreement check"
SPP="${SPP:-1024}" bash scripts/check-mitsuba.sh

# one closing line over every cargo test binary run above
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "all suites: %d passed, %d failed\n", p, f }' "$log"
