#!/bin/bash
# Old (landed 4e3f567) against new (this record's commit), on one machine in one run.
# Build: git worktree add /tmp/landed 4e3f567 && (cd /tmp/landed && CARGO_TARGET_DIR=/tmp/landed-target cargo build --release -p baker)
#        cargo build --release -p baker; copy both binaries to /tmp/meas3/baker-{old,new}.
cd "$(dirname "$0")/../../.."
O=/tmp/meas3/baker-old; N=/tmp/meas3/baker-new
R=validation/bench-runs/2026-12-03-fiber-estimators
echo "== sweep (silk, 6 deg, 16384 photons/direction): one variant and 20, twice each"
for b in O N O N; do B=${!b}; rm -rf /tmp/meas3/one-$b /tmp/meas3/sweep-$b
  /usr/bin/time -f "$b one %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas3/one-$b $R/silk-one.yaml
  /usr/bin/time -f "$b sweep20 %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas3/sweep-$b $R/silk-sweep20.yaml
done
ls -l /tmp/meas3/one-*/*/silk/ /tmp/meas3/sweep-*/*/silk/ | grep -E "bcsdf|h5|one-|sweep-"
echo "== .bcsdf byte-identical, .h5 values identical (old vs new)"
for k in one sweep; do cmp /tmp/meas3/$k-O/*/silk/section-00.bcsdf /tmp/meas3/$k-N/*/silk/section-00.bcsdf && echo "$k .bcsdf identical"; done
python3 - <<'P'
import glob, h5py, numpy as np
for k in ("one", "sweep"):
    a = h5py.File(glob.glob(f"/tmp/meas3/{k}-O/*/silk/silk.h5")[0]); b = h5py.File(glob.glob(f"/tmp/meas3/{k}-N/*/silk/silk.h5")[0])
    n = 0
    def walk(x, y):
        global n
        for key in x:
            if isinstance(x[key], h5py.Group): walk(x[key], y[key])
            else:
                assert np.array_equal(x[key][()], y[key][()]), key; n += 1
    walk(a, b); print(k, ".h5:", n, "datasets, every value identical")
P
echo "== thesis bench with table sizes (new): undyed, then each entry's own dye"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 2>&1 | grep -vE "^ratio"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --dyed 2>&1 | grep -vE "^ratio"
echo "== tracer throughput (fiber bench, new)"
$N fiber bench --photons 2000000 --repeat 2 2>&1 | tail -8
echo "== polyester at the thesis's noise, full bake (new)"
rm -rf /tmp/meas3/poly
/usr/bin/time -f "new poly-thesis %e s wall" $N bake --threads 2 -q -o /tmp/meas3/poly $R/poly-thesis.yaml 2>&1 | tail -3
ls -l /tmp/meas3/poly/*/polyester/
python3 -c "import json; e=json.load(open('/tmp/meas3/poly/poly-thesis/manifest.json'))['entries'][0]; print(json.dumps(e['noise']), json.dumps(e['photons']), e['bcsdf_bytes'], e['hdf5_bytes'])"
echo done
