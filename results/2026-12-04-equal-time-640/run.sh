#!/usr/bin/env bash
# Issue #34's 640-wide cells not run before: the SMS ring at 640×480 and `figurines` (diffuse
# table) at 640×360, 60 s, 3 seeds, `pt-cf` against Mitsuba 3 `path` and `ptracer`; crops are the
# 256-wide ones scaled (×2.5 for the SMS ring, ×2 for figurines).
set -euo pipefail
cd "$(dirname "$0")/../.."
CROPS="floor=200,150,250,150" bash scripts/equal-time-vs-mitsuba.sh \
    scenes/external/sms-ring/ring.xml 640x480 60 3 out/et43/sms-640
CROPS="knot=138,180,132,90 blob=308,188,134,88" bash scripts/equal-time-vs-mitsuba.sh \
    results/2026-12-03-auto-rule/figurines-diffuse-table.toml 640x360 60 3 out/et43/figurines-640
