#!/bin/bash
# Old (landed 9d206d4) against new (this record's commit), on one machine in one run.
# Build: git worktree add /tmp/landed 9d206d4 && (cd /tmp/landed && CARGO_TARGET_DIR=/tmp/landed-target cargo build --release -p baker)
#        cargo build --release -p baker; copy both binaries to /tmp/meas2/baker-{old,new}.
cd "$(dirname "$0")/../../.."
O=/tmp/meas2/baker-old; N=/tmp/meas2/baker-new
R=validation/bench-runs/2026-12-03-fiber-estimators
echo "== tracer throughput (fiber bench), old then new"
$O fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
$N fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
echo "== thesis bench, split 4, exit_draws 16, 3 directions"
for e in polyester silk cotton wool; do
  echo "-- old $e"; $O fiber bench --thesis specs/fibers-thesis.yaml --entry $e --directions 3 --split 4 --exit-draws 16 2>&1 | grep -E "^$e"
  echo "-- new $e"; $N fiber bench --thesis specs/fibers-thesis.yaml --entry $e --directions 3 --split 4 --exit-draws 16 2>&1 | grep -E "^$e"
done
echo "== sweep (silk, 6 deg, 16384 photons/direction), twice each"
for b in O N O N; do B=${!b}; rm -rf /tmp/meas2/one /tmp/meas2/sweep
  /usr/bin/time -f "$b one %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas2/one $R/silk-one.yaml
  /usr/bin/time -f "$b sweep20 %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas2/sweep $R/silk-sweep20.yaml
  ls -l /tmp/meas2/one/*/silk/ /tmp/meas2/sweep/*/silk/ | grep -E "bcsdf|h5"
done
echo "== polyester at the thesis's noise, full bake (new)"
rm -rf /tmp/meas2/poly
/usr/bin/time -f "new poly-thesis %e s wall" $N bake --threads 2 -o /tmp/meas2/poly $R/poly-thesis.yaml 2>&1 | tail -3
ls -l /tmp/meas2/poly/*/polyester/
python3 -c "import json; e=json.load(open('/tmp/meas2/poly/poly-thesis/manifest.json'))['entries'][0]; print(json.dumps(e['noise']), json.dumps(e['photons']), e['bcsdf_bytes'], e['hdf5_bytes'])"
echo done
