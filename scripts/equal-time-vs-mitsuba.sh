#!/usr/bin/env bash
# Equal wall-clock time, crop by crop: forecast against every peer (issues 34 and 62): Mitsuba 3
# `path` and `ptracer`, LuxCore PATHCPU (hybrid back/forward) and BIDIRCPU, Cycles (path guiding).
# A benchmark, not a CI test: run it on a quiet machine; it is not in scripts/test.sh.
#
#   scripts/equal-time-vs-mitsuba.sh SCENE RESOLUTION BUDGET_S SEEDS OUT
#   e.g. THREADS=2 REF_BUDGET=3600 scripts/equal-time-vs-mitsuba.sh scenes/external/sms-pool/scene.xml 480x270 60 3 out/et/pool-60
#        CROPS="wall=226,198,24,36" REFERENCE=ref.exr scripts/equal-time-vs-mitsuba.sh scenes/cornell-box.toml 256x256 60 3 out/et/c
#
# Every renderer gets the same budget, seeds 1..SEEDS, in the order seed by seed (forecast methods,
# then each peer), so that a slow spell of a shared machine falls on all of them alike.
# forecast: `render --time BUDGET` (loading and preprocess inside). Mitsuba: scripts/mitsuba_timed.py
# (loading and JIT inside), rr_depth 5. LuxCore: scripts/peer-luxcore.py, Cycles:
# scripts/peer-cycles.py (scene reading, texture decoding and BVH inside; docs/peers.md says what
# maps and what does not, and how close each peer's image mean is to Mitsuba's).
# Path length: for an XML scene without MAX_DEPTH, the scene's own max_depth d (Mitsuba's
# segments) for every renderer (forecast --max-depth d − 1); with MAX_DEPTH m, forecast m and
# every peer m + 1 segments.
#
# The table (scripts/et_metrics.py; OUT/table.txt, OUT/table.json), per renderer and crop:
#   noise   the RMSE of one render from the seed-to-seed differences: sqrt(mean over seed pairs of
#           MSE(a, b) / 2). For unbiased renderers this is the RMSE against the true image.
#   ref     (with a reference) sqrt(mean over seeds of MSE against the reference image), which
#           also holds the reference's own noise and any bias.
#   relmse  (with a reference) MSE against it over the reference crop's mean squared.
#   relvar  noise² over the crop's mean squared (no reference needed).
#   mean    the crop's mean value (pixels and channels, mean over seeds): a renderer that cannot
#           see part of a crop (Mitsuba's ptracer renders mirrors and glass seen directly black)
#           shows a low noise there but a lower mean.
# then each renderer's relmse (or relvar) over the best other one's, per crop; and, in
# OUT/renders.tsv, each render's spp, wall seconds and CPU seconds (a CPU/wall ratio below the
# thread count means the machine was shared).
#
# Environment:
#   CROPS      space-separated NAME=X,Y,W,H in pixels of RESOLUTION, or in fractions of the frame
#              (any value with a decimal point); "whole" is always added. Unset for one of the SMS
#              scenes of scenes/external: their named crops below (fixed before any measurement).
#   REFERENCE  an EXR at RESOLUTION (optional); or REF_BUDGET=S: a Mitsuba `path` render of S
#              seconds (seed 1000, REF_THREADS threads, default THREADS) made once into OUT/reference.exr
#   METHODS    forecast methods (default auto: the method forecast picks); FORECAST_ARGS extra
#              render arguments
#   PEERS      Mitsuba integrators (default "path ptracer"; empty for none)
#   LUXCORE    LuxCore engines of peer-luxcore.py (default "path bidir" when LUXCORE_VENV has
#              pyluxcore, else none; add path-nohybrid on sms-pool, where hybrid PATHCPU renders the
#              floor seen through the water too dark: docs/peers.md); LUXCORE_VENV (default
#              out/luxcore-venv)
#   CYCLES     "cycles" (path guiding) and/or "cycles-noguide" (default "cycles" when BLENDER_VENV
#              has bpy, else none); BLENDER_VENV (default out/blender-venv)
#   THREADS    threads of every renderer (default nproc); MAX_DEPTH (see above)
#   PIXEL_FILTER  box (default): every peer renders forecast's box pixel (Mitsuba rfilter box,
#              LuxCore BOX ½, Cycles BOX 1), so all estimate the same pixel and their noise
#              compares; scene: the peers keep the file's filter (the SMS scenes' gaussian spreads a
#              sample over ~π pixels and cuts a pixel's variance ~3×: not comparable; docs/peers.md)
#   FORECAST   binary (default target/release/forecast, built if missing); MITSUBA_VENV
#              (default out/mitsuba-venv; see docs/mitsuba.md); VARIANT (default llvm_ad_rgb)
#
# The named crops of the SMS scenes (fractions of the frame; chosen from 120x68 Mitsuba and
# peer renders before any equal-time run, docs/peers.md):
#   sms-sphere-smooth, sms-sphere  shadow_caustic: the caustic in the sphere's shadow (its right
#                                  eighth is the sphere's silhouette: glass seen directly);
#                                  shadow_floor: the same crop without those columns, floor only
#                                  (added 2026-12-08 from the geometry, for Mitsuba's ptracer,
#                                  which renders the glass black)
#   sms-plane                      plate_caustic: the gold plate's caustic on the floor
#   sms-pool                       pool_floor: the pool floor seen through the water
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -eq 5 ] || { sed -n 2,10p "$0" >&2; exit 2; }
scene="$1"; res="$2"; budget="$3"; seeds="$4"; out="$5"
[[ "$res" =~ ^([0-9]+)x([0-9]+)$ ]] || { echo "equal-time-vs-mitsuba: resolution must be WxH, got $res" >&2; exit 2; }
w="${BASH_REMATCH[1]}"; h="${BASH_REMATCH[2]}"
[[ "$budget" =~ ^[0-9]+$ ]] || { echo "equal-time-vs-mitsuba: budget is whole seconds, got $budget" >&2; exit 2; }
[[ "$seeds" =~ ^[2-9]$|^[1-9][0-9]+$ ]] || { echo "equal-time-vs-mitsuba: at least 2 seeds (the noise needs pairs), got $seeds" >&2; exit 2; }
[ -f "$scene" ] || { echo "equal-time-vs-mitsuba: no scene $scene" >&2; exit 2; }
methods="${METHODS:-auto}"; peers="${PEERS-path ptracer}"
export PIXEL_FILTER="${PIXEL_FILTER:-box}"
case "$PIXEL_FILTER" in box|scene) ;; *) echo "equal-time-vs-mitsuba: PIXEL_FILTER must be box or scene, got $PIXEL_FILTER" >&2; exit 2 ;; esac
threads="${THREADS:-$(nproc)}"; variant="${VARIANT:-llvm_ad_rgb}"
venv="${MITSUBA_VENV:-$root/out/mitsuba-venv}"
lux_venv="${LUXCORE_VENV:-$root/out/luxcore-venv}"
blender_venv="${BLENDER_VENV:-$root/out/blender-venv}"
bin="${FORECAST:-$root/target/release/forecast}"
[ -x "$bin" ] || (cd "$root" && cargo build --release --quiet)
if ! "$venv/bin/python" -c 'import mitsuba' 2>/dev/null; then
    echo "equal-time-vs-mitsuba: no Mitsuba in $venv (docs/mitsuba.md: python3 -m venv $venv && $venv/bin/pip install mitsuba numpy); the table needs it too" >&2
    exit 2
fi
if [ -z "${LUXCORE+x}" ]; then
    LUXCORE=""; "$lux_venv/bin/python" -c 'import pyluxcore' >/dev/null 2>&1 && LUXCORE="path bidir"
fi
if [ -z "${CYCLES+x}" ]; then
    CYCLES=""; "$blender_venv/bin/python" -c 'import bpy' >/dev/null 2>&1 && CYCLES="cycles"
fi
mkdir -p "$out"
log="$out/renders.tsv"
[ -f "$log" ] || printf 'renderer\tseed\tspp\twall_s\tcpu_s\n' >"$log"
xml="$out/scene.xml"
if [[ "$scene" == *.xml ]]; then xml="$scene"; else "$bin" export-mitsuba "$scene" --out "$xml" >/dev/null; fi
# path length: Mitsuba's segments (seg) for the peers, forecast's surface vertices (seg − 1)
if [ -n "${MAX_DEPTH:-}" ]; then
    seg=$((MAX_DEPTH + 1))
elif [[ "$scene" == *.xml ]]; then
    seg="$(python3 -c 'import sys, xml.etree.ElementTree as E
r = E.parse(sys.argv[1]).getroot()
v = [i.get("value") for g in r.findall("integrator") for i in g if i.get("name") == "max_depth"]
print(v[0] if v else "65")' "$scene")"
else
    seg=65
fi
fc_depth=$((seg - 1))
# the named crops of the SMS scenes (fractions of the frame; see the header)
if [ -z "${CROPS+x}" ]; then
    case "$(basename "$(dirname "$(readlink -f "$scene")")")" in
        sms-sphere-smooth|sms-sphere) CROPS="shadow_caustic=0.150,0.230,0.120,0.330 shadow_floor=0.150,0.230,0.090,0.330" ;;
        sms-plane) CROPS="plate_caustic=0.100,0.600,0.400,0.350" ;;
        sms-pool) CROPS="pool_floor=0.300,0.500,0.350,0.300" ;;
        *) CROPS="" ;;
    esac
fi
reference="${REFERENCE:-}"
if [ -z "$reference" ] && [ -n "${REF_BUDGET:-}" ]; then
    reference="$out/reference.exr"
    if [ ! -f "$reference" ]; then
        echo "equal-time-vs-mitsuba: reference: Mitsuba path, ${REF_BUDGET} s" >&2
        read -r spp secs cpu < <("$venv/bin/python" "$root/scripts/mitsuba_timed.py" "$xml" "$w" "$h" "$REF_BUDGET" \
            "${REF_THREADS:-$threads}" "$seg" 5 "$variant" path 1000 "$reference" 2>"$out/reference.log")
        printf 'reference-mitsuba-path\t1000\t%s\t%.2f\t%.2f\n' "$spp" "$secs" "$cpu" >>"$log"
    fi
fi

render_forecast() { # METHOD SEED
    local o="$out/$1-$2"
    [ -f "$o.exr" ] && return
    /usr/bin/time -f '%e %U %S' -o "$o.time" "$bin" render "$scene" --method "$1" --time "${budget}s" --resolution "$res" \
        --threads "$threads" --max-depth "$fc_depth" --seed "$2" --out "$o" --quiet ${FORECAST_ARGS:-} 2>"$o.log"
    python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); e,u,s=map(float,open(sys.argv[2]).read().split()[-3:]); print("\t".join([sys.argv[3], sys.argv[4], str(j["passes"]), "%.2f" % e, "%.2f" % (u+s)]))' \
        "$o.json" "$o.time" "$1" "$2" >>"$log"
}
render_mitsuba() { # INTEGRATOR SEED
    local o="$out/mitsuba-$1-$2"
    [ -f "$o.exr" ] && return
    read -r spp secs cpu < <("$venv/bin/python" "$root/scripts/mitsuba_timed.py" "$xml" "$w" "$h" "$budget" "$threads" \
        "$seg" 5 "$variant" "$1" "$2" "$o.exr" 2>"$o.log")
    printf 'mitsuba-%s\t%s\t%s\t%.2f\t%.2f\n' "$1" "$2" "$spp" "$secs" "$cpu" >>"$log"
}
render_luxcore() { # ENGINE SEED
    local o="$out/luxcore-$1-$2"
    [ -f "$o.exr" ] && return
    read -r spp secs cpu < <("$lux_venv/bin/python" "$root/scripts/peer-luxcore.py" "$xml" "$w" "$h" "$budget" "$2" "$threads" \
        "$1" "$o.exr" --max-depth "$seg" 2>"$o.log" | tail -n 1)
    printf 'luxcore-%s\t%s\t%s\t%.2f\t%.2f\n' "$1" "$2" "$spp" "$secs" "$cpu" >>"$log"
}
render_cycles() { # VARIANT SEED
    local o="$out/$1-$2" g=()
    [ -f "$o.exr" ] && return
    [ "$1" = "cycles-noguide" ] && g=(--no-guiding)
    read -r spp secs cpu < <("$blender_venv/bin/python" "$root/scripts/peer-cycles.py" "$xml" "$w" "$h" "$budget" "$2" "$threads" \
        "$o.exr" --max-depth "$seg" "${g[@]}" 2>"$o.log" | tail -n 1)
    printf '%s\t%s\t%s\t%.2f\t%.2f\n' "$1" "$2" "$spp" "$secs" "$cpu" >>"$log"
}
renderers=()
for m in $methods; do renderers+=("$m"); done
for p in $peers; do renderers+=("mitsuba-$p"); done
for e in $LUXCORE; do renderers+=("luxcore-$e"); done
for c in $CYCLES; do renderers+=("$c"); done
for ((s = 1; s <= seeds; s++)); do
    # a renderer that fails (a scene it cannot read) is reported and left out of the table
    for m in $methods; do echo "equal-time-vs-mitsuba: $m seed $s" >&2
        render_forecast "$m" "$s" || echo "equal-time-vs-mitsuba: $m seed $s failed (see $out/$m-$s.log)" >&2; done
    for p in $peers; do echo "equal-time-vs-mitsuba: Mitsuba $p seed $s" >&2
        render_mitsuba "$p" "$s" || echo "equal-time-vs-mitsuba: Mitsuba $p seed $s failed" >&2; done
    for e in $LUXCORE; do echo "equal-time-vs-mitsuba: LuxCore $e seed $s" >&2
        render_luxcore "$e" "$s" || echo "equal-time-vs-mitsuba: LuxCore $e seed $s failed" >&2; done
    for c in $CYCLES; do echo "equal-time-vs-mitsuba: Cycles ($c) seed $s" >&2
        render_cycles "$c" "$s" || echo "equal-time-vs-mitsuba: Cycles $c seed $s failed" >&2; done
done

printf '# %s %s, %s s, seeds 1..%s, %s threads, %s segments (commit %s); peers'"'"' pixel filter %s; crops: whole %s\n' "$scene" "$res" "$budget" "$seeds" \
    "$threads" "$seg" "$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)" "$PIXEL_FILTER" "$CROPS" | tee "$out/table.txt"
"$venv/bin/python" "$root/scripts/et_metrics.py" "$out" "$seeds" "${renderers[*]}" "$CROPS" "$reference"
