#!/usr/bin/env bash
# A cluster of three hosts on one machine, with faults: the `netns_` tests of tests/mpi.rs.
#
# Each host is a network namespace (fcnet-N-0..2, its own IP 10.N.0.10..12 on `eth0`), joined by
# veth pairs to a bridge in the root namespace (10.N.0.1, where mpiexec listens). MPICH's hydra
# (`mpiexec -f hosts -launcher ssh -launcher-exec launch`) starts one hydra_pmi_proxy per host
# through `launch`, an ssh stand-in that runs the command inside the host's namespace
# (`ip netns exec`); the proxies start 2 ranks each. Ranks on different hosts can only reach each
# other by TCP over the veths (the tests set UCX_TLS=tcp,self: UCX's shared memory would join
# ranks across namespaces, which share one kernel).
#
# The tests (cargo test --release --features mpi --test mpi -- --ignored netns_) check that 6
# ranks on 3 hosts give one process's image, and that a link taken down, a host whose processes
# are all killed, and 100 ms of added latency (tc netem, or the userspace delay) in the middle of a render end in a
# bounded time with a clear error (latency: the same image).
#
# The ranks run on MPICH 5.0.2 (.ci/install-mpich-runtime.sh, run here: PyPI's `mpich` wheel in
# /opt), the binary being the one built against Debian's MPICH 4.0.2 (the same ABI, libmpi.so.12):
# 4.0.2's MPI_Finalize hangs over UCX's TCP across hosts in a third of the runs (docs/mpi.md).
# Needs root (namespaces, veths, tc), iproute2 and MPICH (.ci/install-mpi.sh). Fails loudly when
# the namespaces cannot be made; FORECAST_NO_MPI=1 skips it. Where the kernel has no sch_netem
# (tc says "Specified qdisc kind is unknown"; such a kernel has no `tc` qdisc that adds a fixed
# delay: tbf's `latency` only bounds a queue), host 2's link is instead two TAP devices joined by
# scripts/netns-delay.py (python3), which holds host 2's outgoing frames for the milliseconds the
# latency test writes to $dir/delay: the same fault, made in userspace; the script says which.
# Usage: bash scripts/mpi-netns.sh [TEST-NAME-FILTER]    (uses and fills CARGO_TARGET_DIR=target/mpi;
# FORECAST_NETNS_TEST_BIN=PATH runs that test binary of tests/mpi.rs instead of cargo)
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${FORECAST_NO_MPI:-0}" = "1" ]; then
    echo "mpi-netns: SKIPPED (FORECAST_NO_MPI=1): the cluster of network namespaces was not tested" >&2
    exit 0
fi
fail() {
    echo "" >&2
    echo "mpi-netns: FAILED: $*" >&2
    echo "mpi-netns: (the multi-host MPI tests did not run; FORECAST_NO_MPI=1 skips all MPI tests)" >&2
    exit 1
}
[ "$(id -u)" = "0" ] || fail "needs root to create network namespaces"
command -v mpiexec >/dev/null 2>&1 || fail "mpiexec not found (bash .ci/install-mpi.sh)"
# the ranks' MPI runtime: MPICH 5.0.2 (Debian's 4.0.2 hangs in MPI_Finalize across hosts)
# (FORECAST_NETNS_MPI=DIR: the MPI in DIR, bin/mpiexec and lib/, instead; /usr is Debian's 4.0.2)
if [ -n "${FORECAST_NETNS_MPI:-}" ]; then
    mpi="$FORECAST_NETNS_MPI"
else
    mpi="$(bash .ci/install-mpich-runtime.sh | tail -n 1)" || fail "cannot install the MPICH runtime (.ci/install-mpich-runtime.sh)"
fi
[ -x "$mpi/bin/mpiexec" ] || fail "no $mpi/bin/mpiexec"
if ! command -v ip >/dev/null 2>&1 || ! command -v tc >/dev/null 2>&1; then
    bash .ci/apt-install.sh mpi-netns iproute2 || fail "cannot install iproute2 (ip, tc)"
fi

n=$(($$ % 200 + 20)) # a subnet and names of our own
net="10.$n.0"
pre="fcnet-$n"
br="fcbr$n"
dir="$(mktemp -d "${TMPDIR:-/tmp}/mpi-netns.XXXXXX")"
cleanup() {
    [ -s "$dir/delay.pid" ] && kill "$(cat "$dir/delay.pid")" 2>/dev/null
    for i in 0 1 2; do
        # whatever a test left running in a host
        for p in $(ip netns pids "$pre-$i" 2>/dev/null); do kill -9 "$p" 2>/dev/null || true; done
        ip netns del "$pre-$i" 2>/dev/null || true
    done
    ip netns del "$pre-probe" 2>/dev/null || true
    ip link del "$br" 2>/dev/null || true
    rm -rf "$dir"
}
trap cleanup EXIT

ip link add "$br" type bridge || fail "cannot create a bridge ($br): no network namespaces here"
ip addr add "$net.1/24" dev "$br"
echo "$br" > "$dir/iface"
ip link set "$br" up
: > "$dir/hosts"
: > "$dir/nodes"
# Latency: `tc netem` where the kernel has sch_netem; else host 2's link is two TAP devices joined
# by scripts/netns-delay.py, which holds host 2's outgoing frames for the milliseconds in
# $dir/delay (what netem's `delay` does on host 2's eth0)
netem=1
ip netns add "$pre-probe" || fail "ip netns add failed: network namespaces cannot be created here"
if ! tc -n "$pre-probe" qdisc add dev lo root netem delay 1ms 2>"$dir/netem.err"; then
    netem=0
    command -v python3 >/dev/null 2>&1 || fail "no tc netem ($(cat "$dir/netem.err")) and no python3 for the userspace delay"
    echo "mpi-netns: tc netem does not work here ($(cat "$dir/netem.err"): the kernel has no sch_netem);" \
        "host 2's link delays in userspace instead (scripts/netns-delay.py)" >&2
fi
ip netns del "$pre-probe"
for i in 0 1 2; do
    ns="$pre-$i"
    ip netns add "$ns" || fail "ip netns add $ns failed: network namespaces cannot be created here"
    if [ "$i" = 2 ] && [ "$netem" = 0 ]; then
        python3 scripts/netns-delay.py "fcv$n-$i" "fct$n-$i" "$ns" "$dir/delay" "$dir/delay.ready" &
        echo $! >"$dir/delay.pid"
        for _ in $(seq 100); do [ -e "$dir/delay.ready" ] && break; sleep 0.05; done
        [ -e "$dir/delay.ready" ] || fail "scripts/netns-delay.py did not make its TAP devices"
        ip -n "$ns" link set "fct$n-$i" name eth0
    else
        ip link add "fcv$n-$i" type veth peer name eth0 netns "$ns" || fail "cannot create a veth pair for $ns"
    fi
    ip link set "fcv$n-$i" master "$br" up
    ip -n "$ns" addr add "$net.1$i/24" dev eth0
    ip -n "$ns" link set eth0 up
    ip -n "$ns" link set lo up
    echo "$net.1$i:2" >> "$dir/hosts"
    # namespace, the veth's end on the bridge (the host's link), the host's address
    echo "$ns fcv$n-$i $net.1$i" >> "$dir/nodes"
done
# each host reaches the others over the bridge
for i in 1 2; do
    said="$(ip netns exec "$pre-0" timeout 3 bash -c ": </dev/tcp/$net.1$i/9" 2>&1 || true)"
    case "$said" in
        *refused*) ;; # reached: nothing listens on port 9
        *) fail "host 0 cannot reach host $i ($net.1$i) over the veths: $said" ;;
    esac
done

# the ssh stand-in: `launch [ssh options] HOST COMMAND...` runs COMMAND in HOST's namespace
cat > "$dir/launch" <<EOF
#!/bin/bash
while [ "\${1#-}" != "\$1" ]; do shift; done
host="\$1"; shift
ns=\$(awk -v h="\$host" '\$3 == h { print \$1 }' "$dir/nodes")
[ -n "\$ns" ] || { echo "launch: unknown host \$host" >&2; exit 255; }
exec ip netns exec "\$ns" sh -c "\$*"
EOF
chmod +x "$dir/launch"

echo "== mpi-netns: 3 hosts ($net.10-12, namespaces $pre-0..2), 2 ranks each, over veths;" \
    "$("$mpi/bin/mpichversion" | sed -n 1p | tr -s ' \t' ' ') ($mpi)"
export FORECAST_NETNS_DIR="$dir" FORECAST_NETNS_NETEM="$netem" FORECAST_NETNS_DELAY="$dir/delay" \
    FORECAST_NETNS_MPI="$mpi"
if [ -n "${FORECAST_NETNS_TEST_BIN:-}" ]; then
    # a test binary built before (cargo test --release --features mpi --test mpi --no-run)
    "$FORECAST_NETNS_TEST_BIN" --ignored --nocapture --test-threads=1 "${1:-netns_}" </dev/null \
        || fail "the tests above failed"
else
    CARGO_TARGET_DIR=target/mpi cargo test --release --features mpi --test mpi -- --ignored --nocapture \
        --test-threads=1 "${1:-netns_}" </dev/null || fail "the tests above failed"
fi
[ "$netem" = "1" ] || echo "mpi-netns: the latency test ran with the userspace delay (no sch_netem in this kernel)" >&2
echo "mpi-netns: passed"
