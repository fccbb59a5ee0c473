#!/usr/bin/env bash
# Samples per second of `forecast --method pt` against Mitsuba 3 `path`, equal wall-clock budget
# (issue 33). A benchmark, not a CI test: run it on a quiet machine; it is not in scripts/test.sh.
#
#   scripts/bench-vs-mitsuba.sh [SCENE] [RESOLUTION] [BUDGET_S] [RUNS]
#   e.g. scripts/bench-vs-mitsuba.sh scenes/ring.toml 256x256 60 3
# Defaults: scenes/cornell-box.toml 640x640 60 3.
#
# Environment:
#   THREADS       worker threads of both renderers (default: all cores, `nproc`)
#   MAX_DEPTH     forecast `--max-depth` (path vertices, default 64); Mitsuba gets max_depth =
#                 MAX_DEPTH + 1 (it counts path segments: a path whose last scattering vertex is
#                 vertex MAX_DEPTH ends with segment MAX_DEPTH + 1, by NEE or by the BSDF ray)
#   RR_DEPTH      Mitsuba rr_depth (default 5 = forecast's transport::roulette::RR_FROM_VERTEX:
#                 both roulette from the 5th surface vertex on, survival min(max β·η², 0.95))
#   VARIANT       Mitsuba variant (default llvm_ad_rgb; scalar_rgb needs no LLVM)
#   MITSUBA_VENV  virtual environment (default out/mitsuba-venv; created with pip if missing)
#   FORECAST      forecast binary (default: cargo build --release, target/release/forecast)
#   FORECAST_ARGS extra arguments of forecast's render (e.g. "--accel embree")
#   OUT           work folder (default out/bench-vs-mitsuba)
#
# Timing. forecast: `render --time BUDGET` (whole passes; loading, BVH and probe inside the
# budget), samples = passes·W·H over its JSON `timings.total_s`. Mitsuba: scripts/mitsuba_timed.py
# (from just before `load_file`, so scene load, BVH and LLVM JIT are inside the budget; chunks of
# spp, each kernel compiled once, until the next chunk would pass the budget); samples = spp·W·H
# over the elapsed time (Mitsuba renders forecast's box pixel: PIXEL_FILTER, as in mitsuba_timed.py).
# Both counts are whole samples per
# pixel. The ratio printed is forecast / Mitsuba, per run and averaged over RUNS. The cpu ratio
# divides the same sample counts by each process's user + system CPU seconds instead (Mitsuba's
# counted from just before `load_file`): it is the figure to read when other work shares the
# machine, which slows both renderers' wall clocks unevenly.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scene="${1:-scenes/cornell-box.toml}"
res="${2:-640x640}"
budget="${3:-60}"
runs="${4:-3}"
threads="${THREADS:-$(nproc)}"
max_depth="${MAX_DEPTH:-64}"
rr_depth="${RR_DEPTH:-5}"
variant="${VARIANT:-llvm_ad_rgb}"
venv="${MITSUBA_VENV:-$root/out/mitsuba-venv}"
out="${OUT:-$root/out/bench-vs-mitsuba}"
[[ "$res" =~ ^([0-9]+)x([0-9]+)$ ]] || { echo "bench-vs-mitsuba: resolution must be WxH, got $res" >&2; exit 2; }
w="${BASH_REMATCH[1]}"; h="${BASH_REMATCH[2]}"
[[ "$budget" =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "bench-vs-mitsuba: budget is seconds, got $budget" >&2; exit 2; }
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || { echo "bench-vs-mitsuba: runs must be a positive integer, got $runs" >&2; exit 2; }
[[ -f "$scene" ]] || { echo "bench-vs-mitsuba: no scene $scene" >&2; exit 2; }

# --- Mitsuba 3 in a local virtual environment -------------------------------------------------
if ! "$venv/bin/python" -c 'import mitsuba' 2>/dev/null; then
  echo "bench-vs-mitsuba: installing Mitsuba 3 into $venv (pip)"
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet mitsuba numpy
fi
if [[ "$variant" == llvm* ]] && ! ldconfig -p | grep -q 'libLLVM'; then
  if [[ "$(id -u)" == 0 ]] && command -v apt-get >/dev/null; then
    echo "bench-vs-mitsuba: Mitsuba's llvm variants need LLVM: apt-get install -y libllvm19"
    apt-get install -y -q libllvm19 >/dev/null
  else
    echo "bench-vs-mitsuba: $variant needs LLVM: run 'apt-get install libllvm19' as root (or VARIANT=scalar_rgb)" >&2
    exit 2
  fi
fi

# --- forecast and the exported scene -----------------------------------------------------------
if [[ -z "${FORECAST:-}" ]]; then
  cargo build --release --quiet
  FORECAST="$root/target/release/forecast"
fi
mkdir -p "$out"
name="$(basename "${scene%.*}")"
if [[ "$scene" == *.xml ]]; then
  xml="$scene" # already Mitsuba XML (it must load in Mitsuba 3 as it is): integrator and film are replaced
else
  xml="$out/$name.xml"
  "$FORECAST" export-mitsuba "$scene" --out "$xml" >/dev/null
fi

mitsuba_run() { # SEED -> "spp seconds cpu_seconds" (scripts/mitsuba_timed.py, no image written)
  "$venv/bin/python" "$root/scripts/mitsuba_timed.py" "$xml" "$w" "$h" "$budget" "$threads" "$((max_depth + 1))" \
    "$rr_depth" "$variant" path "$1" -
}

forecast_run() { # SEED -> "spp seconds cpu_seconds"
  local prefix="$out/forecast-$name-$1"
  /usr/bin/time -f '%U %S' -o "$prefix.cpu" "$FORECAST" render "$scene" --method pt --time "${budget}s" --resolution "$res" --threads "$threads" \
    --max-depth "$max_depth" --seed "$1" --out "$prefix" --quiet ${FORECAST_ARGS:-} 2>/dev/null
  "$venv/bin/python" -c 'import json, sys; j = json.load(open(sys.argv[1])); u, s = map(float, open(sys.argv[2]).read().split()[-2:]); print(j["passes"], j["timings"]["total_s"], u + s)' \
    "$prefix.json" "$prefix.cpu"
}

echo "bench-vs-mitsuba: $scene at ${w}x${h}, ${budget} s each, $runs runs, $threads threads," \
  "forecast pt --max-depth $max_depth vs Mitsuba $variant path max_depth=$((max_depth + 1)) rr_depth=$rr_depth"
printf '%-4s %12s %14s %12s %14s %7s %9s\n' run "forecast spp" "forecast S/s" "mitsuba spp" "mitsuba S/s" ratio "cpu ratio"
rows=""
for ((i = 1; i <= runs; i++)); do
  fres="$(forecast_run "$i")" # a failed run stops the script (set -e)
  mres="$(mitsuba_run "$i")"
  row="$(awk -v px="$((w * h))" -v i="$i" -v f="$fres" -v m="$mres" 'BEGIN {
    split(f, a, " "); split(m, b, " ")
    fs = a[1] * px / a[2]; ms = b[1] * px / b[2]; fc = a[1] * px / a[3]; mc = b[1] * px / b[3]
    printf "%-4d %12d %14.4g %12d %14.4g %7.3f %9.3f\n", i, a[1], fs, b[1], ms, fs / ms, fc / mc }')"
  echo "$row"
  rows+="$row"$'\n'
done
# the mean of the per-run ratios (wall-clock and per CPU-second: user + system time of each
# process, Mitsuba's from just before load_file), and the ratio of the mean rates
awk 'NF == 7 { f += $3; m += $5; r += $6; c += $7; n++ } END {
  printf "mean %12s %14.4g %12s %14.4g %7.3f %9.3f  (ratio of the means %.3f)\n", "", f / n, "", m / n, r / n, c / n, f / m }' <<<"$rows"
