#!/bin/bash
# Old (landed b1b1456) against new (this record's commit), on one machine in one run.
# Build: git worktree add /tmp/landed b1b1456 && (cd /tmp/landed && CARGO_TARGET_DIR=/tmp/landed-target cargo build --release -p baker)
#        cargo build --release -p baker; copy both binaries to /tmp/meas6/baker-{old,new}.
cd "$(dirname "$0")/../../.."
# O, N and POLY_ROUNDS may be set (the later record ../2026-12-06-fiber-sweep-table does).
O=${O:-/tmp/meas6/baker-old}; N=${N:-/tmp/meas6/baker-new}
S=validation/bench-runs/2026-12-05-fiber-sweep-h5; E=validation/bench-runs/2026-12-03-fiber-estimators
sweep() { # fiber, spec of one variant, spec of 20, rounds
  echo "== $1 sweep (6 deg, 16384 photons/direction): one variant and 20, old and new alternating"
  for r in $(seq $4); do for b in O N; do B=${!b}; rm -rf /tmp/meas6/$1-one-$b /tmp/meas6/$1-sweep-$b
    /usr/bin/time -f "$1 $b one %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas6/$1-one-$b $2
    /usr/bin/time -f "$1 $b sweep20 %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas6/$1-sweep-$b $3
  done; done
  ls -l /tmp/meas6/$1-*/*/$1/ | grep -E "bcsdf|h5|meas6"
}
sweep polyester $S/polyester-one.yaml $S/polyester-sweep20.yaml ${POLY_ROUNDS:-3}
sweep silk $E/silk-one.yaml $E/silk-sweep20.yaml 2
sweep cotton $S/cotton-one.yaml $S/cotton-sweep20.yaml 2
echo "== polyester at the thesis's noise, split 8 (full bake), old and new"
for b in O N; do B=${!b}; rm -rf /tmp/meas6/poly-$b
  /usr/bin/time -f "poly-thesis $b %e s wall, %U s user" $B bake --threads 2 -q -o /tmp/meas6/poly-$b validation/bench-runs/2026-12-06-fiber-f32-lobes/poly-thesis-split8.yaml
done
echo "== old vs new: the stored values (.h5 f_normalised = the .bcsdf's decoded values), albedo, .bcsdf bytes"
python3 - <<'P'
import glob, h5py, numpy as np, filecmp
for k in ("polyester-one", "polyester-sweep", "silk-one", "silk-sweep", "cotton-one", "cotton-sweep", "poly"):
    fib = "polyester" if k == "poly" else k.split("-")[0]
    a = glob.glob(f"/tmp/meas6/{k}-O/*/{fib}/*.bcsdf")[0]; b = a.replace(f"{k}-O", f"{k}-N")
    ha = h5py.File(glob.glob(f"/tmp/meas6/{k}-O/*/{fib}/{fib}.h5")[0]); hb = h5py.File(glob.glob(f"/tmp/meas6/{k}-N/*/{fib}/{fib}.h5")[0])
    for name in ("f_normalised", "albedo"):
        u = ha["section-00"][name][()]; v = hb["section-00"][name][()]
        d = u != v
        rel = float((np.abs(u - v)[d] / np.abs(u)[d]).max()) if d.any() else 0.0
        print(f"{k}: {name} {int(d.sum())} of {u.size} values differ, largest relative difference {rel:.2g}")
    print(f"{k}: .bcsdf {'identical' if filecmp.cmp(a, b, shallow=False) else 'differs'} ({a.split('/')[-1]})")
P
echo "== old vs new: albedo_se and the gamut-mapping record (they follow the tabulated attenuations' last bits)"
python3 - <<'P'
import glob, h5py
for k, fib in (("polyester-sweep", "polyester"), ("silk-one", "silk"), ("silk-sweep", "silk"), ("cotton-sweep", "cotton")):
    a = h5py.File(glob.glob(f"/tmp/meas6/{k}-O/*/{fib}/{fib}.h5")[0])["section-00"]; b = h5py.File(glob.glob(f"/tmp/meas6/{k}-N/*/{fib}/{fib}.h5")[0])["section-00"]
    u, v = a["albedo_se"][()], b["albedo_se"][()]; d = u != v
    rel = float((abs(u - v)[d] / abs(u)[d]).max()) if d.any() else 0.0
    print(f"{k}: albedo_se {int(d.sum())} of {u.size} differ, largest relative difference {rel:.2g}; gamut clip old {a.attrs['rgb_gamut_clip']} new {b.attrs['rgb_gamut_clip']}")
P
echo done
