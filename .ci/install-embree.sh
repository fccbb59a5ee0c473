#!/usr/bin/env bash
# Install Intel Embree 3, needed only for `cargo build --features embree` (`--accel embree`).
#
# Why the package:
#   libembree-dev  embree3/rtcore*.h and the unversioned libembree3.so the linker finds
#                  (`#[link(name = "embree3")]` in src/accel/embree.rs; no build script, no
#                  bindgen); pulls in libembree3-3 (the runtime library, with its ISA dispatch)
#
# Idempotent: when it is already present it changes nothing and runs no apt command.
# Needs root (or sudo) only when something is missing. Debian/Ubuntu only.
set -euo pipefail

have_embree() {
    [ -f /usr/include/embree3/rtcore.h ] || return 1
    # grep without -q reads all of ldconfig's output: no SIGPIPE under pipefail
    ldconfig -p 2>/dev/null | grep 'libembree3\.so ' >/dev/null || [ -e /usr/lib/x86_64-linux-gnu/libembree3.so ] || return 1
    return 0
}

if have_embree; then
    echo "install-embree: Embree 3 already installed, nothing to do"
    grep -m1 RTC_VERSION_STRING /usr/include/embree3/rtcore_config.h || true
    exit 0
fi

bash "$(dirname "$0")/apt-install.sh" install-embree libembree-dev

if ! have_embree; then
    echo "install-embree: installed libembree-dev but embree3/rtcore.h or libembree3.so is missing" >&2
    exit 1
fi
echo "install-embree: done"
grep -m1 RTC_VERSION_STRING /usr/include/embree3/rtcore_config.h || true
