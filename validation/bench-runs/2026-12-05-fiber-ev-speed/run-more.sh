#!/bin/bash
# The rest of this record's figures, new code only (282f2b3; the tracer, the spec's estimators
# and the default bake's code paths are those of the landed code): tracer rates, dyed table
# sizes with the spec's estimators, and the sweep ratio at the default settings.
cd "$(dirname "$0")/../../.."
N=/tmp/meas4/baker-new
T=specs/fibers-thesis.yaml
echo "== tracer throughput"
$N fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
echo "== thesis bench, the spec's estimators, each entry's own dye, 3 directions"
$N fiber bench --thesis $T --directions 3 --dyed 2>&1 | grep -vE "^ratio"
echo "== sweeps at the default settings (6 deg, 16384 photons/direction): one variant and 20"
R=validation/bench-runs/2026-12-03-fiber-estimators; H=validation/bench-runs/2026-12-05-fiber-sweep-h5
for p in "silk $R/silk-one.yaml $R/silk-sweep20.yaml" "cotton $H/cotton-one.yaml $H/cotton-sweep20.yaml" "polyester $H/polyester-one.yaml $H/polyester-sweep20.yaml"; do
  set -- $p; rm -rf /tmp/meas4/s1 /tmp/meas4/s20
  /usr/bin/time -f "$1 one %e s wall" $N bake --threads 2 -q -o /tmp/meas4/s1 $2
  /usr/bin/time -f "$1 sweep20 %e s wall" $N bake --threads 2 -q -o /tmp/meas4/s20 $3
done
echo done
