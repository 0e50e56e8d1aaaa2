#!/bin/bash
# The thesis-fidelity figures with OLD and NEW builds in one run: `fiber bench --thesis`
# (dyed, 3 stored directions per entry) and the polyester full thesis bake.
#   bash thesis.sh OLD_BAKER NEW_BAKER > log-thesis.txt 2>&1
set -e
cd "$(dirname "$0")/../../.."
O=$(realpath "$1"); N=$(realpath "$2")
T=$(mktemp -d)
for b in O N; do
  echo "== $b: fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --dyed ($(date -u +%H:%M))"
  "${!b}" fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --dyed --threads 2 \
    --entry polyester --entry silk --entry cotton --entry wool | sed -n '2,6p'
done
for b in O N; do
  rm -rf "$T/p"
  t0=$(date +%s.%N)
  "${!b}" bake --threads 2 -q -o "$T/p" validation/bench-runs/2026-12-06-fiber-f32-lobes/poly-thesis-split8.yaml
  printf '%s polyester full thesis bake: %.2f s wall, .bcsdf %s B\n' "$b" "$(echo "$(date +%s.%N) - $t0" | bc)" \
    "$(find "$T/p" -name '*.bcsdf' -printf '%s\n' | paste -sd+ | bc)"
done
rm -rf "$T"
