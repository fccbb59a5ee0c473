#!/usr/bin/env bash
# `pt` against Mitsuba 3 `path` over a set of scenes, both of forecast's ray-tracing back ends in
# one run (issue 64): scripts/bench-vs-mitsuba.sh once per scene and back end, then one summary
# table. A benchmark, not a CI test: run it on a quiet machine; it is not in scripts/test.sh.
#
#   scripts/bench-set-vs-mitsuba.sh [BUDGET_S] [RUNS]
#   e.g. scripts/bench-set-vs-mitsuba.sh 15 3
# Defaults: 15 s per run, 3 runs (each run: forecast, Mitsuba, per back end).
#
# Environment:
#   SCENES   "SCENE RESOLUTION" pairs separated by ';' (default: cornell-box 640x640, ring 256x256,
#            figurines 640x360 with its table diffuse (Mitsuba 3 has no Phong), and the pool of scenes/external/sms-pool at 384x216)
#   BACKENDS of "wide obvhs embree" (default "wide embree"): wide = the default build's default
#            tree, obvhs = the default build with `--accel obvhs`, embree = the `embree` feature's
#            build with `--accel embree` (skipped, with a line saying so, where Embree is not
#            installed: .ci/install-embree.sh installs it)
#   THREADS, MAX_DEPTH, RR_DEPTH, VARIANT, MITSUBA_VENV: as scripts/bench-vs-mitsuba.sh
#   OUT      work folder (default out/bench-set-vs-mitsuba); the full output of each scene and
#            back end is kept there as NAME-BACKEND.txt
#
# Builds: wide and obvhs = `cargo build --release` (target/release/forecast, what the README's
# first command makes); embree = `cargo build --release --features embree` in target/embree. Set
# FORECAST_DEFAULT / FORECAST_EMBREE to binaries to skip the builds.
#
# The table gives, per scene and back end, forecast's samples per second over Mitsuba's (the
# mean of the per-run ratios, wall clock) and the same per CPU second (user + system time of
# each process): the figure to read where other work shares the machine.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
budget="${1:-15}"
runs="${2:-3}"
out="${OUT:-$root/out/bench-set-vs-mitsuba}"
mkdir -p "$out"

pool=scenes/external/sms-pool
pool_tex=("$pool/textures/[2K]Tiles06/Tiles06_col.png" "$pool/textures/[2K]Tiles50/Tiles50_col.jpg"
  "$pool/textures/[2K]Tiles54/Tiles54_col.jpg" "$pool/textures/Striped_cotton_01_2K_Normal.jpg")
default_scenes="scenes/cornell-box.toml 640x640;scenes/ring.toml 256x256;results/2026-12-03-auto-rule/figurines-diffuse-table.toml 640x360"
pool_ok=1
for f in "${pool_tex[@]}"; do [[ -f "$f" ]] || pool_ok=0; done
if ((pool_ok)); then
  default_scenes+=";$pool/scene.xml 384x216"
fi
scenes="${SCENES:-$default_scenes}"
backends="${BACKENDS:-wide embree}"

cpu="$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1)"
echo "bench-set-vs-mitsuba: CPU: ${cpu:-unknown} ($(nproc) logical CPUs; flags:" \
  "$(grep -o -w -E 'avx2|avx512f' /proc/cpuinfo | sort -u | tr '\n' ' ')), $(date -u +%Y-%m-%dT%H:%MZ)," \
  "commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), ${budget} s per run, $runs runs"
if [[ -z "${SCENES:-}" ]] && ((!pool_ok)); then
  echo "bench-set-vs-mitsuba: skipping $pool: a texture of it is missing"
fi

have_embree() { [[ -f /usr/include/embree3/rtcore.h ]]; }
declare -A bin
for b in $backends; do
  case "$b" in
    wide | obvhs)
      if [[ -z "${FORECAST_DEFAULT:-}" ]]; then
        cargo build --release --quiet
        FORECAST_DEFAULT="$root/target/release/forecast"
      fi
      bin[$b]="$FORECAST_DEFAULT"
      ;;
    embree)
      if [[ -z "${FORECAST_EMBREE:-}" ]]; then
        if ! have_embree; then
          echo "bench-set-vs-mitsuba: skipping the Embree back end: Embree is not installed (.ci/install-embree.sh)"
          continue
        fi
        CARGO_TARGET_DIR="$root/target/embree" cargo build --release --quiet --features embree
        FORECAST_EMBREE="$root/target/embree/release/forecast"
      fi
      bin[embree]="$FORECAST_EMBREE"
      ;;
    *) echo "bench-set-vs-mitsuba: unknown back end $b (wide, obvhs, embree)" >&2; exit 2 ;;
  esac
done

summary=""
IFS=';' read -r -a list <<<"$scenes"
for entry in "${list[@]}"; do
  read -r scene res <<<"$entry"
  name="$(basename "$(dirname "$scene")")-$(basename "${scene%.*}")"
  for b in $backends; do
    [[ -n "${bin[$b]:-}" ]] || continue
    args="--accel $b"
    log="$out/$name-$b.txt"
    echo "== $scene $res, $b"
    FORECAST="${bin[$b]}" FORECAST_ARGS="$args" OUT="$out/$name-$b" \
      bash "$root/scripts/bench-vs-mitsuba.sh" "$scene" "$res" "$budget" "$runs" | tee "$log"
    # the mean line: "mean  F/s  M/s  ratio  cpu_ratio  (ratio of the means R)"
    summary+="$(awk -v s="$scene" -v r="$res" -v b="$b" '$1 == "mean" {
      printf "%-40s %-9s %-7s %9.3f %9.3f %12.4g %12.4g\n", s, r, b, $4, $5, $2, $3 }' "$log")"$'\n'
  done
done

echo
echo "bench-set-vs-mitsuba: CPU: ${cpu:-unknown}; forecast pt / Mitsuba path, mean of $runs runs of ${budget} s"
printf '%-40s %-9s %-7s %9s %9s %12s %12s\n' scene res backend ratio "cpu ratio" "forecast S/s" "mitsuba S/s"
printf '%s' "$summary"
