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
#
# Second form, for a TOML scene exported to Mitsuba (issue #61):
#   scripts/check-mitsuba.sh --export SCENE.toml
# writes SCENE.toml with `forecast export-mitsuba` (XML, meshes and images in OUT/), loads the XML
# in Mitsuba 3 (the scene must load without an error) and compares image means over the whole
# film: Mitsuba `path` in MI_RUNS (default 16) runs of MI_SPP (default 1024) spp with their own
# seeds, its standard error from the runs' spread, against forecast `pt` rendering the same XML
# at SPP (default 16384) spp, its standard error from the variance channel. Per channel
# z = (forecast − Mitsuba)/sqrt(se_f² + se_m²) must satisfy |z| < 3.4 (Šidák over the three
# channels at family-wise 1e-3 — the caustics' heavy tails make the standard errors themselves
# noisy: a failure is a reason to rerun with more samples, not a proof). Needs Python with
# mitsuba and numpy: MITSUBA_PYTHON (default out/mitsuba-venv/bin/python, as
# scripts/bench-vs-mitsuba.sh makes it); VARIANT (default scalar_rgb).
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"

if [[ "${1:-}" == "--export" ]]; then
  toml="$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"
  name="$(basename "$toml" .toml)"
  out="${OUT:-out/mitsuba-check}/export-$name"
  py="${MITSUBA_PYTHON:-$root/out/mitsuba-venv/bin/python}"
  if [[ -z "${FORECAST:-}" ]]; then
    cargo build --release --quiet
    FORECAST="$root/target/release/forecast"
  fi
  mkdir -p "$out"
  "$FORECAST" export-mitsuba "$toml" --out "$out/$name.xml"
  "$FORECAST" render "$out/$name.xml" --method pt --spp "${SPP:-16384}" --seed "${SEED:-1}" \
    --out "$out/$name-pt" --quiet
  cd "$out"
  exec "$py" - "$name" "${MI_RUNS:-16}" "${MI_SPP:-1024}" "${VARIANT:-scalar_rgb}" <<'PY'
import sys, numpy as np, mitsuba as mi
name, runs, spp, variant = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
mi.set_variant(variant)
scene = mi.load_file(name + ".xml")
means = np.array([np.array(mi.render(scene, spp=spp, seed=1000 + k))[..., :3].reshape(-1, 3).mean(0)
                  for k in range(runs)])
mi_mean, mi_se = means.mean(0), means.std(0, ddof=1) / np.sqrt(runs)
chans = dict(mi.Bitmap(name + "-pt.exr").split())
img, var = np.array(chans["<root>"])[..., :3], np.array(chans["var"])[..., :3]
n = img.shape[0] * img.shape[1]
fc_mean, fc_se = img.reshape(-1, 3).mean(0), np.sqrt(var.reshape(-1, 3).sum(0)) / n
z = (fc_mean - mi_mean) / np.sqrt(fc_se ** 2 + mi_se ** 2)
print(f"check-mitsuba: {name}: Mitsuba 3 {mi.__version__} ({variant}, {runs} x {spp} spp) mean "
      f"{np.round(mi_mean, 5)} +- {np.round(mi_se, 5)}")
print(f"check-mitsuba: {name}: forecast pt mean {np.round(fc_mean, 5)} +- {np.round(fc_se, 5)}")
print(f"check-mitsuba: {name}: ratio forecast/Mitsuba {np.round(fc_mean / mi_mean, 4)}, z {np.round(z, 2)}")
ok = bool(np.all(np.abs(z) < 3.4))
print("check-mitsuba: " + ("PASS" if ok else "FAIL"))
sys.exit(0 if ok else 1)
PY
fi
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
