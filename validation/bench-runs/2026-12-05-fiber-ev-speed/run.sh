#!/bin/bash
# Old (landed 0fbf7e4) against new (this record's code, 282f2b3), on one machine in one run.
# Build: git worktree add /tmp/landed 0fbf7e4 && (cd /tmp/landed && CARGO_TARGET_DIR=/tmp/landed-target cargo build --release -p baker)
#        cargo build --release -p baker; copy both binaries to /tmp/meas4/baker-{old,new}.
cd "$(dirname "$0")/../../.."
O=/tmp/meas4/baker-old; N=/tmp/meas4/baker-new
D=validation/bench-runs/2026-12-05-fiber-ev-speed
T=specs/fibers-thesis.yaml
echo "== thesis bench, expected-value exit scoring (split 4, exit_draws 16, expected_exits all), old then new, undyed"
for e in polyester silk; do
  for b in O N; do B=${!b}; echo "-- $b (3 directions)"; $B fiber bench --thesis $T --directions 3 --expected-exits all --entry $e 2>&1 | grep -E "^$e "; done
done
for b in O N; do B=${!b}; echo "-- $b (1 direction)"; $B fiber bench --thesis $T --directions 1 --expected-exits all --entry cotton 2>&1 | grep -E "^cotton "; done
echo "== thesis bench, the spec's estimators (split 4, exit_draws 16, no expectation), new, 3 directions, undyed"
$N fiber bench --thesis $T --directions 3 2>&1 | grep -vE "^ratio"
echo "== polyester and silk, expected_exits all, dyed (the entry's own dye), new, 3 directions"
$N fiber bench --thesis $T --directions 3 --expected-exits all --entry polyester --entry silk --dyed 2>&1 | grep -E "^(polyester|silk) "
echo "== default settings (plain tracing, no expectation): old and new bake byte-identical tables"
R=validation/bench-runs/2026-12-03-fiber-estimators
rm -rf /tmp/meas4/one-O /tmp/meas4/one-N
for b in O N; do B=${!b}; /usr/bin/time -f "$b silk-one %e s wall" $B bake --threads 2 -q -o /tmp/meas4/one-$b $R/silk-one.yaml; done
cmp /tmp/meas4/one-O/*/silk/section-00.bcsdf /tmp/meas4/one-N/*/silk/section-00.bcsdf && echo "silk-one .bcsdf identical"
echo "== polyester at the thesis's noise, full bake with expected_exits all (new)"
rm -rf /tmp/meas4/poly
/usr/bin/time -f "new poly-thesis-ev %e s wall" $N bake --threads 2 -q -o /tmp/meas4/poly $D/poly-thesis-ev.yaml 2>&1 | tail -3
ls -l /tmp/meas4/poly/*/polyester/
python3 -c "import json; e=json.load(open('/tmp/meas4/poly/poly-thesis-ev/manifest.json'))['entries'][0]; print(json.dumps(e['noise']), json.dumps(e['photons']), e['bcsdf_bytes'], e['hdf5_bytes'])"
echo done
