#!/bin/bash
# Which estimator is fastest for each fiber of specs/fibers.yaml at its 6° bins, and the
# default spec with each fiber's own estimators:   bash run.sh BAKER > log.txt 2>&1
# (BAKER: a release build, e.g. target/release/baker). Runs one bake at a time on 2 threads.
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1")
T=$(mktemp -d)
. validation/bench-runs/fiber-variant.sh   # variant NAME PHOTONS "ENTRIES" k=v ..., report NAME DIR
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
