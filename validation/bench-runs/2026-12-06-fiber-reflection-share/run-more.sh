#!/bin/bash
# The rest of this stop's figures, new code only (target/release/baker at this record's
# commit): tracer rates, dyed table sizes, cotton with the expectation, sweep ratios.
cd "$(dirname "$0")/../../.."
N=target/release/baker
T=specs/fibers-thesis.yaml
mkdir -p /tmp/meas5
echo "== tracer throughput"
$N fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
echo "== thesis bench, the spec's estimators, each entry's own dye, 3 directions"
$N fiber bench --thesis $T --directions 3 --dyed 2>&1 | grep -E "^(polyester|silk|cotton|wool) "
echo "== thesis bench, expected_exits all, each entry's own dye, 3 directions"
$N fiber bench --thesis $T --directions 3 --dyed --expected-exits all --entry polyester --entry silk 2>&1 | grep -E "^(polyester|silk) "
echo "== thesis bench, expected_exits all, cotton, 1 direction, undyed"
$N fiber bench --thesis $T --directions 1 --expected-exits all --entry cotton 2>&1 | grep -E "^cotton "
echo "== sweeps at the default settings (6 deg, 16384 photons/direction): one variant and 20"
R=validation/bench-runs/2026-12-03-fiber-estimators; H=validation/bench-runs/2026-12-05-fiber-sweep-h5
for p in "silk $R/silk-one.yaml $R/silk-sweep20.yaml" "cotton $H/cotton-one.yaml $H/cotton-sweep20.yaml" "polyester $H/polyester-one.yaml $H/polyester-sweep20.yaml"; do
  set -- $p; rm -rf /tmp/meas5/s1 /tmp/meas5/s20
  /usr/bin/time -f "$1 one %e s wall" $N bake --threads 2 -q -o /tmp/meas5/s1 $2
  /usr/bin/time -f "$1 sweep20 %e s wall" $N bake --threads 2 -q -o /tmp/meas5/s20 $3
done
echo done
