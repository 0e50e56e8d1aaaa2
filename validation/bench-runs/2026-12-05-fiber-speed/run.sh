#!/bin/bash
cd /work/main
O=/tmp/meas/baker-old; N=/tmp/meas/baker-new
echo "== tracer throughput (fiber bench), old then new"
$O fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
$N fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
echo "== thesis bench"
for e in polyester silk cotton wool; do
  for c in "1 1" "4 16"; do set -- $c
    echo "-- old $e $c"; $O fiber bench --thesis specs/fibers-thesis.yaml --entry $e --directions 3 --split $1 --exit-draws $2 2>&1 | grep -E "^$e"
    echo "-- new $e $c"; $N fiber bench --thesis specs/fibers-thesis.yaml --entry $e --directions 3 --split $1 --exit-draws $2 2>&1 | grep -E "^$e"
  done
done
for e in polyester wool silk; do
  echo "-- new $e 1 16 inside"; $N fiber bench --thesis specs/fibers-thesis.yaml --entry $e --directions 3 --split 1 --exit-draws 16 --expected-exits inside 2>&1 | grep -E "^$e"
  echo "-- new $e 4 16 all"; $N fiber bench --thesis specs/fibers-thesis.yaml --entry $e --directions 3 --split 4 --exit-draws 16 --expected-exits all 2>&1 | grep -E "^$e"
done
echo "== sweep (silk, 6 deg, 16384 photons/direction)"
for b in O N; do B=${!b}; rm -rf /tmp/meas/one /tmp/meas/sweep
  /usr/bin/time -f "$b one %e s" $B bake --threads 2 -q -o /tmp/meas/one validation/bench-runs/2026-12-03-fiber-estimators/silk-one.yaml
  /usr/bin/time -f "$b sweep20 %e s" $B bake --threads 2 -q -o /tmp/meas/sweep validation/bench-runs/2026-12-03-fiber-estimators/silk-sweep20.yaml
done
ls -la /tmp/meas/sweep/*/silk/ /tmp/meas/one/*/silk/
echo done
