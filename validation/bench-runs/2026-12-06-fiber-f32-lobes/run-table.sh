#!/bin/bash
# The issue's table and sweeps with this record's code (NEW), and the default settings'
# bits against the landed code (OLD):  bash run-table.sh OLD_BAKER NEW_BAKER > log-table.txt 2>&1
set -e
cd "$(dirname "$0")/../../.."
O=$1; N=$2
T=$(mktemp -d)
echo "== the spec's estimators (split 4, exit_draws 16), undyed"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --threads 2 2>&1 | sed -n '2,7p'
echo "== dyed (each entry's own dye), the spec's estimators"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --dyed --threads 2 2>&1 | sed -n '2,7p'
echo "== dyed, expected_exits all"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --dyed --expected-exits all --entry polyester --entry silk --threads 2 2>&1 | sed -n '2,5p'
echo "== tracer rates"
$N fiber bench --photons 2000000 --repeat 2 2>&1 | tail -12
echo "== sweeps (default settings: 6°, 16,384 photons per direction), wall"
for f in validation/bench-runs/2026-12-03-fiber-estimators/silk-one.yaml validation/bench-runs/2026-12-03-fiber-estimators/silk-sweep20.yaml \
         validation/bench-runs/2026-12-05-fiber-sweep-h5/cotton-one.yaml validation/bench-runs/2026-12-05-fiber-sweep-h5/cotton-sweep20.yaml \
         validation/bench-runs/2026-12-05-fiber-sweep-h5/polyester-one.yaml validation/bench-runs/2026-12-05-fiber-sweep-h5/polyester-sweep20.yaml; do
  rm -rf $T/s; /usr/bin/time -f "$(basename $f): %e s wall" $N bake --threads 2 -q -o $T/s $f
done
echo "== default settings, old against new: silk one variant"
for b in O N; do rm -rf $T/$b; /usr/bin/time -f "$b silk-one: %e s wall" ${!b} bake --threads 2 -q -o $T/$b validation/bench-runs/2026-12-03-fiber-estimators/silk-one.yaml; done
cmp $T/O/*/silk/*.bcsdf $T/N/*/silk/*.bcsdf && echo "silk-one .bcsdf identical old/new"
rm -rf $T
echo done
