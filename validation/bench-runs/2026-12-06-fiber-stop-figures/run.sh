#!/usr/bin/env bash
# The figures of issue 18's closing note that are not in the other records of the day, in one
# run on one 2-core machine with nothing else running:
#   bash validation/bench-runs/2026-12-06-fiber-stop-figures/run.sh target/release/baker > log.txt 2>&1
# 1. Item 6: a 20-variant dye × depth-of-shade sweep against one variant (6°, 16,384 photons
#    per direction, RGB, the specs of ../2026-12-06-fiber-sweep-costs), two rounds each.
# 2. The thesis bench per fiber type (the spec's estimators, dyed): polyester, silk and
#    cotton one whole φ column each; wool 4 directions (a column is 45 × 5 s), and wool
#    with Sobol' sampling and with 32 draws, the estimators it has not tried.
set -euo pipefail
cd "$(dirname "$0")/../../.."
B=$1
T=$(mktemp -d)
S=validation/bench-runs/2026-12-05-fiber-sweep-h5; E=validation/bench-runs/2026-12-03-fiber-estimators
sweep() { # fiber, spec of one variant, spec of 20
  for r in 1 2; do
    rm -rf $T/one $T/sw
    /usr/bin/time -f "$1 round $r one: %e s wall" "$B" bake --threads 2 -q -o $T/one $2
    /usr/bin/time -f "$1 round $r sweep20: %e s wall" "$B" bake --threads 2 -q -o $T/sw $3
  done
}
echo "== item 6: sweeps"
sweep polyester $S/polyester-one.yaml $S/polyester-sweep20.yaml
sweep silk $E/silk-one.yaml $E/silk-sweep20.yaml
sweep cotton $S/cotton-one.yaml $S/cotton-sweep20.yaml
echo "== thesis bench (spec's estimators, dyed)"
for e in polyester silk cotton; do
  "$B" fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry $e 2>&1 | grep "^$e"
done
"$B" fiber bench --thesis specs/fibers-thesis.yaml --directions 4 --dyed --entry wool 2>&1 | grep "^wool"
"$B" fiber bench --thesis specs/fibers-thesis.yaml --directions 4 --dyed --entry wool --sampling sobol 2>&1 | grep "^wool"
"$B" fiber bench --thesis specs/fibers-thesis.yaml --directions 4 --dyed --entry wool --split 32 --exit-draws 32 2>&1 | grep "^wool"
echo "== tracer throughput (photons/s, 1 and 2 threads), specs/fibers-thesis.yaml"
"$B" fiber bench specs/fibers-thesis.yaml --photons 2000000 --repeat 2 2>&1 | grep -v "^\s*$"
rm -rf $T
