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
echo "== old vs new: .bcsdf bytes, and how the .h5 values differ (new: fractions rounded to f32 before storing)"
for k in one sweep; do cmp -s /tmp/meas3/$k-O/*/silk/section-00.bcsdf /tmp/meas3/$k-N/*/silk/section-00.bcsdf && echo "$k .bcsdf identical" || echo "$k .bcsdf differs"; done
python3 - <<'P'
import glob, h5py, numpy as np
for k in ("one", "sweep"):
    a = h5py.File(glob.glob(f"/tmp/meas3/{k}-O/*/silk/silk.h5")[0]); b = h5py.File(glob.glob(f"/tmp/meas3/{k}-N/*/silk/silk.h5")[0])
    out = []
    def walk(x, y, p=""):
        for key in x:
            if isinstance(x[key], h5py.Group): walk(x[key], y[key], p + key + "/"); continue
            u, v = x[key][()], y[key][()]
            if u.dtype.kind != "f": assert np.array_equal(u, v), key; continue
            d = u != v
            rel = float((np.abs(u - v)[d] / np.abs(u)[d]).max()) if d.any() else 0.0
            out.append(f"{p}{key}: {int(d.sum())} of {u.size} values differ, largest relative difference {rel:.2g}")
    walk(a, b); print(k, ".h5:"); print("  " + "\n  ".join(out))
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
