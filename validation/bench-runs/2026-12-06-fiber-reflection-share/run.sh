#!/bin/bash
# Old (8a7f0c4's estimators: the binary built from 282f2b3, same outputs) against new (0ed537e),
# on one machine in one run, 2 threads.
# Build: cargo build --release -p baker (new); old: git worktree add /tmp/landed 8a7f0c4 &&
#        (cd /tmp/landed && CARGO_TARGET_DIR=/tmp/landed-target cargo build --release -p baker).
cd "$(dirname "$0")/../../.."
O=${OLD:-/tmp/meas4/baker-new}; N=target/release/baker
D=validation/bench-runs/2026-12-06-fiber-reflection-share
T=specs/fibers-thesis.yaml
P=$D/poly-thesis-ev32.yaml
row() { python3 -c "
import json,sys
d=json.load(sys.stdin); d=d[0] if isinstance(d,list) else d
print('θi %5.1f: %9d photons %7.2f s  noise %.4f  thesis %.4f' % (d['theta_i_deg'], d['photons'], d['seconds'], d['noise']['median_rel_se'], d['noise']['thesis_rel_se']))"; }
echo "== polyester, one direction each, traced to the thesis's noise (fiber trace, $P)"
for t in 89 85 75 45 5; do
  for b in O N; do B=${!b}; [ $b = O ] && [ $t = 85 -o $t = 75 -o $t = 5 ] && continue
    echo -n "$b "; $B fiber trace $P --entry polyester --theta-i $t --threads 2 --json 2>/dev/null | row; done
done
echo "== thesis bench, expected_exits all, 3 directions, undyed"
for b in O N; do B=${!b}; echo "-- $b"; $B fiber bench --thesis $T --directions 3 --expected-exits all --entry polyester --entry silk 2>&1 | grep -E "^(polyester|silk) "; done
echo "== thesis bench, the spec's estimators (split 4, exit_draws 16), 3 directions, undyed"
for b in O N; do B=${!b}; echo "-- $b"; $B fiber bench --thesis $T --directions 3 2>&1 | grep -E "^(polyester|silk|cotton|wool) "; done
echo "== default settings (no target): old and new bake byte-identical tables"
R=validation/bench-runs/2026-12-03-fiber-estimators
rm -rf /tmp/meas5/one-O /tmp/meas5/one-N; mkdir -p /tmp/meas5
for b in O N; do B=${!b}; /usr/bin/time -f "$b silk-one %e s wall" $B bake --threads 2 -q -o /tmp/meas5/one-$b $R/silk-one.yaml; done
cmp /tmp/meas5/one-O/*/silk/section-00.bcsdf /tmp/meas5/one-N/*/silk/section-00.bcsdf && echo "silk-one .bcsdf identical"
echo "== polyester at the thesis's noise, full bake, expected_exits all (new; first pass 131072 and 32768)"
for y in validation/bench-runs/2026-12-05-fiber-ev-speed/poly-thesis-ev.yaml $P; do
  rm -rf /tmp/meas5/poly
  /usr/bin/time -f "new $(basename $y) %e s wall" $N bake --threads 2 -q -o /tmp/meas5/poly $y 2>&1 | tail -1
  ls -l /tmp/meas5/poly/*/polyester/ | tail -2
  python3 -c "import json,glob; e=json.load(open(glob.glob('/tmp/meas5/poly/*/manifest.json')[0]))['entries'][0]; print(json.dumps(e['noise']), json.dumps(e['photons']), e['bcsdf_bytes'], e['hdf5_bytes'])"
done
echo done
