#!/bin/bash
# More draws per event met from outside (split): the thesis spec's and the default spec's
# estimators before (OLD_DIR: a checkout of d190d65's specs/) and now, in the same run:
#   bash run.sh BAKER OLD_SPECS_DIR > log.txt 2>&1      (≈ 20 min; SCAN=1 adds the scans, ≈ 25 min)
# BAKER: a release build. One measurement at a time, 2 threads.
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1"); OLD=$(realpath "$2")
T=$(mktemp -d)
if [ -n "$SCAN" ]; then
  echo "== the thesis's noise at 2°: cotton and wool, split × exit_draws (6 directions each)"
  for a in "4 16" "16 8" "8 8" "32 4"; do set -- $a
    echo "-- split $1 exit_draws $2"
    "$B" fiber bench --thesis specs/fibers-thesis.yaml --directions 6 --entry cotton --entry wool --split $1 --exit-draws $2 --threads 2 | sed -n '3,4p'
  done
  echo "== silk, 3 directions"
  for a in "4 16 all" "8 4 all" "16 4 all" "16 8 all" "16 8 none"; do set -- $a
    echo "-- split $1 exit_draws $2 expected_exits $3"
    "$B" fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --entry silk --split $1 --exit-draws $2 --expected-exits $3 --threads 2 | sed -n '3,3p'
  done
  echo "== 6°, 8192 photons (scan6deg.sh)"
  bash validation/bench-runs/2026-12-06-fiber-split-scan/scan6deg.sh "$B"
fi
echo "== fiber bench --thesis, 3 directions per entry: before (OLD) and now"
for s in "$OLD/fibers-thesis.yaml" specs/fibers-thesis.yaml; do
  echo "-- $s"; "$B" fiber bench --thesis "$s" --directions 3 --threads 2 | sed -n '2,6p'
done
echo "== fiber bench --thesis --dyed, silk and cotton: before and now"
for s in "$OLD/fibers-thesis.yaml" specs/fibers-thesis.yaml; do
  echo "-- $s"; "$B" fiber bench --thesis "$s" --dyed --directions 3 --entry silk --entry cotton --threads 2 | sed -n '3,4p'
done
echo "== the default spec, whole bake: before and now"
for s in "$OLD/fibers.yaml" specs/fibers.yaml; do
  o="$T/$(echo $s | md5sum | cut -c1-8)"
  /usr/bin/time -f "$s: %e s wall" "$B" bake --threads 2 -q -o "$o" "$s"
  python3 - "$o/fibers" <<'PY'
import json, sys
d = sys.argv[1]
m = json.load(open(d + "/manifest.json"))
t = {e["entry"]: e for e in json.load(open(d + "/timing.json"))["entries"]}
tot = 0
for e in m["entries"]:
    s, z = t[e["name"]]["seconds"], e["noise"]["median_rel_se"]
    tot += e["bcsdf_bytes"]
    print(f"  {e['name']:20s} {s:8.2f} s  median {100*z:6.2f} %  p90 {100*e['noise']['p90_rel_se']:6.2f} %  "
          f"1/(noise²·s) {1 / (z * z * s):9.2f}  estimators {e['split']}/{e['exit_draws']}/{e['expected_exits']}  .bcsdf {e['bcsdf_bytes']} B")
print(f"  .bcsdf total {tot} B")
PY
done
rm -rf "$T"
echo done
