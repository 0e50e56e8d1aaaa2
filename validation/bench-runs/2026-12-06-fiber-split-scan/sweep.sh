#!/bin/bash
# Item 6 with the estimators the default spec now gives silk (split 8, exit_draws 8, the
# expectation): one variant against the 20-variant dye × depth-of-shade sweep, wall time,
# twice.   bash sweep.sh BAKER > log-sweep.txt 2>&1
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1")
T=$(mktemp -d)
S=validation/bench-runs/2026-12-03-fiber-estimators
for f in silk-one.yaml silk-sweep20.yaml; do
  sed 's/seed: 1}/seed: 1, split: 8, exit_draws: 8, expected_exits: all}/' $S/$f > "$T/$f"
done
for round in 1 2; do
  for f in silk-one.yaml silk-sweep20.yaml; do
    rm -rf "$T/o"; /usr/bin/time -f "round $round $f: %e s wall" "$B" bake --threads 2 -q -o "$T/o" "$T/$f"
  done
done
rm -rf "$T"
