#!/bin/bash
# Per-sample variance and cost of pt-cf's cached tables (energy × cos, the default --table-cache 1)
# against per-point tables (the BSDF product, --table-cache 0), and of pt, on a glass ball under
# a normal map over a roughconductor floor (tests/normal_mapped_casters.rs's glossy_receiver).
# Run from this folder: F=../../target/release/forecast ./run.sh; then python3 an.py (OpenEXR, numpy)
F=${F:-../../target/release/forecast}
mkdir -p out
for a in 0.2 0.3; do sed "s/^alpha = .*/alpha = $a/" glossy-receiver.toml > glossy-$a.toml; done
for s in 1 2 3 4 5 6 7 8; do for a in 0.2 0.3; do
  for tc in 0 1; do
    $F render glossy-$a.toml --method pt-cf --resolution 96x96 --spp 128 --threads 1 --seed $s --quiet --table-cache $tc --out out/a$a-tc$tc-s$s
  done
  $F render glossy-$a.toml --method pt --resolution 96x96 --spp 128 --threads 1 --seed $s --quiet --out out/pt-a$a-s$s
done; done
