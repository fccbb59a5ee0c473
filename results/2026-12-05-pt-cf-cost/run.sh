#!/usr/bin/env bash
# Where pt-cf's time per pass goes, against pt: fixed passes, 2 threads, seed 1, render_s of the
# JSON (the render loop only: no loading, BVH or preprocess), RUNS alternating runs per config.
#   FORECAST=BIN [ARGS="--accel embree"] bash results/2026-12-05-pt-cf-cost/run.sh OUT [RUNS]
# Configurations: pt (its wavefront); pt-cf --table-depth 0 --light-paths 0 (pt's estimator,
# bit for bit, through pt-cf's scalar loop); pt-cf --light-paths 0 (guiding, no light side);
# pt-cf --light-paths N at the pilot's choice (N given, so no pilot).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
bin="${FORECAST:-$root/target/release/forecast}"
out="$1"; runs="${2:-2}"; mkdir -p "$out"
printf "scene\tconfig\trun\tpasses\trender_s\tclosest\tshadow\n" > "$out/runs.tsv"
cases=(
  "cornell|scenes/cornell-box.toml|256x256|512|8192"
  "ring|scenes/ring.toml|256x256|256|65536"
  "figurines|results/2026-12-03-auto-rule/figurines-diffuse-table.toml|640x360|32|28800"
)
for c in "${cases[@]}"; do
  IFS='|' read -r name scene res spp lp <<< "$c"
  for r in $(seq 1 "$runs"); do
    for cfg in pt ptcf-as-pt ptcf-lp0 ptcf; do
      case $cfg in
        pt) args=(--method pt) ;;
        ptcf-as-pt) args=(--method pt-cf --table-depth 0 --light-paths 0) ;;
        ptcf-lp0) args=(--method pt-cf --light-paths 0) ;;
        ptcf) args=(--method pt-cf --light-paths "$lp") ;;
      esac
      o="$out/$name-$cfg-r$r"
      "$bin" render "$root/$scene" "${args[@]}" ${ARGS:-} --resolution "$res" --spp "$spp" --threads 2 --seed 1 --quiet --out "$o" 2>/dev/null
      python3 - "$o.json" "$name" "$cfg" "$r" >> "$out/runs.tsv" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print("\t".join([sys.argv[2], sys.argv[3], sys.argv[4], str(d["passes"]), "%.3f" % d["timings"]["render_s"],
                 str(d["rays"]["closest"]), str(d["rays"]["shadow"])]))
PY
    done
  done
done
python3 - "$out/runs.tsv" <<'PY'
import csv, sys, collections
rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
by = collections.defaultdict(list)
for r in rows:
    by[(r["scene"], r["config"])].append(r)
print("scene      config        s/pass (mean)  ÷ pt   rays/pass ÷ pt")
base = {}
for (s, c), rs in by.items():
    sp = sum(float(r["render_s"]) / int(r["passes"]) for r in rs) / len(rs)
    rays = sum(int(r["closest"]) + int(r["shadow"]) for r in rs) / sum(int(r["passes"]) for r in rs)
    if c == "pt":
        base[s] = (sp, rays)
    b = base[s]
    print(f"{s:10} {c:13} {sp:.5f}        {sp / b[0]:.3f}  {rays / b[1]:.3f}")
PY
