#!/usr/bin/env bash
# Mitsuba agreement check for the path tracer (`pt`) on the cornell-box scene.
#
# Renders scenes/cornell-box.toml with `pt` at 256x256 and compares it with the independent
# Mitsuba 3 reference committed in tests/reference (65,984 spp, plus two independent halves;
# provenance in tests/reference/README.md):
#   forecast diff TEST.exr REF.exr --half0 H0.exr --half1 H1.exr --png DIFF.png
# `forecast diff` applies metrics::mitsuba_agreement and exits non-zero on failure:
#   * every per-channel image mean within 0.5 % of the reference;
#   * ratio = mean (I-R)^2 / mean (var_I + var_R) within 5 sigma of 1 (floor 0.03), where
#     sigma = sqrt(2 sum s_p^2 + 2 sum r_p^2) / sum s_p is the ratio's own standard error under
#     pure noise (s_p: per-pixel variance of the difference, r_p: reference variance from the
#     halves, (h0-h1)^2/4). For 256^2 pixels this is typically a few percent.
# The test EXR must carry its variance of the mean in channels var.R, var.G, var.B.
#
# Environment: SPP (default 1024), SEED (default 1), FORECAST (binary; default: cargo build
# --release and use target/release/forecast), OUT (default out/mitsuba-check).
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
ref_dir="$root/tests/reference"
ref="$ref_dir/cornell-box-mitsuba-256.exr"
half0="$ref_dir/cornell-box-mitsuba-256.half0.exr"
half1="$ref_dir/cornell-box-mitsuba-256.half1.exr"
for f in "$ref" "$half0" "$half1"; do
  [[ -f "$f" ]] || { echo "check-mitsuba: missing reference file $f" >&2; exit 2; }
done

spp="${SPP:-1024}"
seed="${SEED:-1}"
out="${OUT:-out/mitsuba-check}"
if [[ -z "${FORECAST:-}" ]]; then
  cargo build --release --quiet
  FORECAST="$root/target/release/forecast"
fi
mkdir -p "$out"
prefix="$out/pt-256-${spp}spp-seed${seed}"

echo "check-mitsuba: rendering pt 256x256, $spp spp, seed $seed -> $prefix.exr"
"$FORECAST" render scenes/cornell-box.toml --method pt --resolution 256x256 \
  --spp "$spp" --seed "$seed" --out "$prefix" --quiet

echo "check-mitsuba: comparing with $ref"
status=0
"$FORECAST" diff "$prefix.exr" "$ref" --half0 "$half0" --half1 "$half1" \
  --png "$prefix-diff.png" || status=$?
if [[ $status -eq 0 ]]; then
  echo "check-mitsuba: PASS (difference map: $prefix-diff.png)"
else
  echo "check-mitsuba: FAIL (exit $status; difference map: $prefix-diff.png)" >&2
fi
exit "$status"
