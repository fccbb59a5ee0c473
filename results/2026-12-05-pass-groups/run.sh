#!/usr/bin/env bash
# Pass groups (issue #33): samples per second of the render loop, before and after, the two
# binaries alternating run by run on one idle machine.
#   BASE=… NEW=… BASE_EMBREE=… NEW_EMBREE=… bash run.sh OUT [RUNS] [SECONDS]
# Each run: forecast render SCENE --method M --time S --resolution RES --threads 2 --seed RUN;
# the figure is passes·W·H / timings.render_s (the render loop alone) from its JSON.
set -euo pipefail
out="$1"; runs="${2:-3}"; secs="${3:-12}"
root="$(cd "$(dirname "$0")/../.." && pwd)"
mkdir -p "$out"
tsv="$out/runs.tsv"
echo -e "scene\tres\tmethod\taccel\tbinary\trun\tpasses\trender_s\tsamples_per_s" >"$tsv"
one() { # scene res method accel label bin run
  local o="$out/$1-$3-$4-$5-$7"
  local args=()
  [[ "$4" == embree ]] && args=(--accel embree)
  "$6" render "$root/$1" --method "$3" --time "${secs}s" --resolution "$2" --threads 2 --seed "$7" \
    --quiet --out "$o" "${args[@]}" 2>/dev/null
  python3 - "$o.json" "$2" "$(basename "$1" .toml)" "$3" "$4" "$5" "$7" >>"$tsv" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); w, h = map(int, sys.argv[2].split('x'))
r = j['timings']['render_s']
print('\t'.join([sys.argv[3], sys.argv[2], sys.argv[4], sys.argv[5], sys.argv[6], sys.argv[7],
                 str(j['passes']), f'{r:.3f}', f"{j['passes'] * w * h / r:.6g}"]))
PY
}
fig="results/2026-12-03-auto-rule/figurines-diffuse-table.toml"
for spec in "scenes/ring.toml 256x256" "scenes/cornell-box.toml 640x640" "$fig 640x360"; do
  read -r scene res <<<"$spec"
  for run in $(seq 1 "$runs"); do
    for cfg in "pt obvhs" "pt embree" "pt-cf obvhs"; do
      read -r method accel <<<"$cfg"
      if [[ "$accel" == embree ]]; then b="$BASE_EMBREE"; n="$NEW_EMBREE"; else b="$BASE"; n="$NEW"; fi
      one "$scene" "$res" "$method" "$accel" base "$b" "$run"
      one "$scene" "$res" "$method" "$accel" new "$n" "$run"
    done
  done
done
python3 - "$tsv" <<'PY'
import csv, sys, collections
rows = list(csv.DictReader(open(sys.argv[1]), delimiter='\t'))
g = collections.defaultdict(list)
for r in rows:
    g[(r['scene'], r['res'], r['method'], r['accel'], r['binary'])].append(float(r['samples_per_s']))
for k in sorted({k[:4] for k in g}):
    b, n = g[k + ('base',)], g[k + ('new',)]
    mb, mn = sum(b) / len(b), sum(n) / len(n)
    print(*k, 'base', ' '.join(f'{x:.4g}' for x in b), 'new', ' '.join(f'{x:.4g}' for x in n), f'new/base {mn / mb:.3f}')
PY
