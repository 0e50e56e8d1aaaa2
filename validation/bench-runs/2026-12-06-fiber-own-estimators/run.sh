#!/bin/bash
# Which estimator is fastest for each fiber of specs/fibers.yaml at its 6° bins, and the
# default spec with each fiber's own estimators:   bash run.sh BAKER > log.txt 2>&1
# (BAKER: a release build, e.g. target/release/baker). Runs one bake at a time on 2 threads.
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1")
T=$(mktemp -d)
# A copy of specs/fibers.yaml with the bake: block's fields set (k=v ...), without the
# fibers' own estimators, baked for some entries at --photons P; prints seconds and noise.
variant() { # NAME PHOTONS "ENTRIES" k=v ...
  local name=$1 ph=$2 entries=$3; shift 3
  python3 - "$T/$name.yaml" "$@" <<'PY'
import re, sys
s = open("specs/fibers.yaml").read()
s = re.sub(r"^    estimators: .*\n", "", s, flags=re.M)
for kv in sys.argv[2:]:
    k, v = kv.split("=", 1)
    pat = re.compile(r"^(  " + re.escape(k) + r":)\s*\S+", re.M)
    s = pat.sub(r"\g<1> " + v, s) if pat.search(s) else s.replace("  seed: 1\n", f"  seed: 1\n  {k}: {v}\n", 1)
open(sys.argv[1], "w").write(s)
PY
  # Each group of entries in a folder of its own (a second group in the same folder would be
  # a subset bake, written to subset/).
  local o; o="$T/$name-$(echo "$entries" | md5sum | cut -c1-8)"
  "$B" bake --threads 2 -q --photons "$ph" $entries -o "$o" "$T/$name.yaml"
  report "$name" "$o/$name"
}
report() { # NAME DIR: per entry seconds, median relative SE, 1/(noise² × seconds)
  python3 - "$1" "$2" <<'PY'
import json, sys
name, d = sys.argv[1:]
m = json.load(open(d + "/manifest.json"))
t = {e["entry"]: e for e in json.load(open(d + "/timing.json"))["entries"]}
print(name)
for e in m["entries"]:
    s, z = t[e["name"]]["seconds"], e["noise"]["median_rel_se"]
    print(f"  {e['name']:20s} {s:8.2f} s  noise {z:.4f}  p90 {e['noise']['p90_rel_se']:.3f}  "
          f"1/(noise²·s) {1 / (z * z * s):9.2f}  photons {e['photons']['total']}  "
          f"estimators {e['split']}/{e['exit_draws']}/{e['expected_exits']}  .bcsdf {e['bcsdf_bytes']} B")
PY
}
E1="--entry polyester --entry polyester_trilobal --entry cotton_mercerised --entry wool"
E2="--entry silk --entry cotton"
echo "== each estimator for every entry at 8192 photons per direction (two batches: the"
echo "   noise metric reads low by the same factor for every estimator, so compare within a row)"
for E in "$E1" "$E2"; do
  variant plain 8192 "$E"
  variant split2-exit4 8192 "$E" split=2 exit_draws=4
  variant split4-exit16 8192 "$E" split=4 exit_draws=16
  variant expected-all 8192 "$E" expected_exits=all
done
echo "== specs/fibers.yaml as shipped (each fiber its own estimators) against all plain"
variant all-plain 16384 ""
/usr/bin/time -f "own estimators: %e s wall" "$B" bake --threads 2 -q -o "$T/own" specs/fibers.yaml
report own "$T/own/fibers"
echo "== sweeps with the estimators the default gives silk (2/4 draws) and cotton (expectation)"
S=validation/bench-runs/2026-12-03-fiber-estimators; C=validation/bench-runs/2026-12-05-fiber-sweep-h5
for f in $S/silk-one.yaml $S/silk-sweep20.yaml; do
  sed 's/seed: 1}/seed: 1, split: 2, exit_draws: 4}/' $f > "$T/d24-$(basename $f)"
  rm -rf "$T/s"; /usr/bin/time -f "$(basename $f) split 2, exit_draws 4: %e s wall" "$B" bake --threads 2 -q -o "$T/s" "$T/d24-$(basename $f)"
done
for f in $S/silk-one.yaml $S/silk-sweep20.yaml $C/cotton-one.yaml $C/cotton-sweep20.yaml; do
  sed 's/seed: 1}/seed: 1, expected_exits: all}/' $f > "$T/ev-$(basename $f)"
  rm -rf "$T/s"; /usr/bin/time -f "$(basename $f) expected_exits all: %e s wall" "$B" bake --threads 2 -q -o "$T/s" "$T/ev-$(basename $f)"
done
echo "== the thesis spec's polyester and silk with their own estimators"
"$B" fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --entry polyester --entry silk --threads 2 | sed -n '2,4p'
rm -rf "$T"
echo done
