#!/bin/bash
# Towards the dyed ≤ 200 MB aim: the dyed silk and cotton sizes at the thesis's noise with
# coarser rounding (`bake.quantise_to_se` 0.25, the default; 0.5; 1.0, the largest the
# schema allows: rounding error up to one standard error). Sizes only (deterministic: the
# photons each direction takes do not depend on timing).
#   bash quantise.sh BAKER > log-quantise.txt 2>&1
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1")
T=$(mktemp -d)
for q in 0.25 0.5 1.0; do
  sed "s/^  precision: f16/  precision: f16\n  quantise_to_se: $q/" specs/fibers-thesis.yaml > "$T/q$q.yaml"
  echo "== quantise_to_se $q"
  "$B" fiber bench --thesis "$T/q$q.yaml" --directions 3 --dyed --threads 2 --entry silk --entry cotton | sed -n '3,4p'
done
rm -rf "$T"
