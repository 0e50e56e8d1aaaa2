#!/bin/bash
# Item 6 (a 20-variant dye × depth-of-shade sweep ≤ 1.3× one variant) with the batch tallies
# in f32: OLD and NEW builds, alternating, twice; the tables they write compared; the default
# spec's whole bake with each.
#   bash run.sh OLD_BAKER NEW_BAKER > log.txt 2>&1      (from anywhere; ~40 min on 2 cores)
#   FROM=2 TO=3 T=FOLDER bash run.sh OLD NEW   (sections 2 to 3 only, on a first run's FOLDER)
set -e
cd "$(dirname "$0")/../../.."
O=$(realpath "$1"); N=$(realpath "$2")
FROM=${FROM:-1}; TO=${TO:-3}
T=${T:-$(mktemp -d)}
S=validation/bench-runs/2026-12-03-fiber-estimators; C=validation/bench-runs/2026-12-05-fiber-sweep-h5
# Each fiber with the estimators specs/fibers.yaml gives it: cotton the expectation, silk 8
# draws and the expectation, polyester the expectation.
for k in one sweep20; do
  sed 's/seed: 1}/seed: 1, expected_exits: all}/' $C/cotton-$k.yaml > "$T/cotton-$k.yaml"
  sed 's/seed: 1}/seed: 1, split: 8, exit_draws: 8, expected_exits: all}/' $S/silk-$k.yaml > "$T/silk-$k.yaml"
  sed 's/seed: 1}/seed: 1, expected_exits: all}/' $C/polyester-$k.yaml > "$T/polyester-$k.yaml"
done
if [ "$FROM" -le 1 ]; then
  echo "== sweeps, 6°, 16,384 photons, wall seconds ($(date -u +%H:%M))"
  for fib in cotton silk polyester; do
    for round in 1 2; do
      for b in O N; do
        for k in one sweep20; do
          rm -rf "$T/$b-$fib-$k"
          t0=$(date +%s.%N)
          "${!b}" bake --threads 2 -q -o "$T/$b-$fib-$k" "$T/$fib-$k.yaml"
          printf '%s %s %-8s round %s: %.2f s\n' "$b" "$fib" "$k" "$round" "$(echo "$(date +%s.%N) - $t0" | bc)"
        done
      done
    done
  done | tee "$T/times"
  python3 - "$T/times" <<'P'
import sys, collections
t = collections.defaultdict(list)
for line in open(sys.argv[1]):
    b, fib, k, _, r, s, _u = line.split()
    t[(b, fib, k)].append(float(s))
for fib in ("cotton", "silk", "polyester"):
    for b in ("O", "N"):
        one, sw = t[(b, fib, "one")], t[(b, fib, "sweep20")]
        rs = ", ".join(f"{w / o:.3f}" for o, w in zip(one, sw))
        print(f"{fib:9s} {b}: one {', '.join(map(str, one))} s; sweep {', '.join(map(str, sw))} s; sweep / one per round {rs}")
P
fi

if [ "$FROM" -le 2 ] && [ "$TO" -ge 2 ]; then
echo "== the tables: NEW against OLD (the same photons; only the tallies' rounding differs)"
# The sweeps' .h5: f̂ as stored (rounded to its noise, so a value moves by a rounding step
# where the tallies' rounding crosses a step's edge), the albedos, the noise.
for fib in cotton silk; do
  python3 - "$T/O-$fib-sweep20" "$T/N-$fib-sweep20" "$fib" <<'P'
import glob, sys
import h5py, numpy as np
o, n, fib = sys.argv[1:]
a, = glob.glob(o + "/**/*.h5", recursive=True)
b, = glob.glob(n + "/**/*.h5", recursive=True)
with h5py.File(a) as A, h5py.File(b) as B:
    for g in sorted(A):
        fa = A[g]["f_normalised"][()].astype(np.float64)
        fb = B[g]["f_normalised"][()].astype(np.float64)
        m = fa > 0
        rel = np.abs(fb[m] - fa[m]) / fa[m]
        la, lb = (X[g]["albedo"][()].astype(np.float64) for X in (A, B))
        na, nb = (X[g]["median_rel_se"][()].mean() for X in (A, B))
        print(f"{fib} {g}: {m.sum()} values > 0, {np.count_nonzero(fb[m] != fa[m])} changed; "
              f"|new − old| / old: 99th percentile {np.percentile(rel, 99):.1e}, max {rel.max():.1e}; "
              f"albedo |new − old| max {np.abs(lb - la).max():.1e}; mean median rel. SE old {na:.6f}, new {nb:.6f}")
P
done
# One direction at 2° with the thesis spec's settings, unrounded (`fiber trace --json`): the
# tallies' rounding against the estimator's own per-bin error.
for e in cotton silk; do
  for b in O N; do
    "${!b}" fiber trace specs/fibers-thesis.yaml --entry $e --theta-i -45 --phi-i 30 --threads 2 --json > "$T/trace-$b-$e.json"
  done
  python3 - "$T/trace-O-$e.json" "$T/trace-N-$e.json" "$e" <<'P'
import json, sys
import numpy as np
a, b = (json.load(open(p)) for p in sys.argv[1:3])
ha, hb = (np.array(x["hist2d"], float) for x in (a, b))
se = np.array(a["hist2d_se"], float)
m = ha > 0
rel = np.abs(hb[m] - ha[m]) / ha[m]
z = np.abs(hb[m] - ha[m]) / np.where(se[m] > 0, se[m], np.inf)
print(f"{sys.argv[3]} θi −45° φi 30°, {a['photons']} photons ({a['estimator']}): {m.sum()} bins > 0; "
      f"|new − old| / old median {np.median(rel):.1e}, 99th percentile {np.percentile(rel, 99):.1e}, max {rel.max():.1e}; "
      f"in units of the bin's SE: max {z.max():.1e}; albedo old {a['albedo']!r}, new {b['albedo']!r}")
P
done

fi

if [ "$TO" -ge 3 ]; then
echo "== the default spec, whole bake (specs/fibers.yaml, $(date -u +%H:%M))"
for b in O N; do
  rm -rf "$T/$b-default"
  t0=$(date +%s.%N)
  "${!b}" bake --threads 2 -q -o "$T/$b-default" specs/fibers.yaml
  printf '%s default spec: %.2f s wall\n' "$b" "$(echo "$(date +%s.%N) - $t0" | bc)"
  python3 - "$T/$b-default/fibers" <<'P'
import json, sys
d = sys.argv[1]
t = {e["entry"]: e for e in json.load(open(d + "/timing.json"))["entries"]}
for e in json.load(open(d + "/manifest.json"))["entries"]:
    print(f"  {e['name']:18s} {t[e['name']]['seconds']:8.2f} s, median rel. SE {e['noise']['median_rel_se']:.4f}, .bcsdf {e['bcsdf_bytes']} B")
P
done
fi
rm -rf "$T"
echo done
