#!/bin/bash
# Default spec (6°, specs/fibers.yaml) at 8192 photons per direction: more draws per event
# met from outside (split) against each fiber's current estimators. Efficiency
# 1/(noise² × s), noise = the manifest's median per-bin relative SE. One bake at a time.
#   bash scan6deg.sh BAKER > log-6deg.txt 2>&1
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1")
T=$(mktemp -d)
. validation/bench-runs/fiber-variant.sh   # variant NAME PHOTONS "ENTRIES" k=v ...
E1="--entry polyester --entry polyester_trilobal --entry cotton_mercerised --entry wool"
E2="--entry silk --entry cotton"
for E in "$E1" "$E2"; do
  variant split2-exit4 8192 "$E" split=2 exit_draws=4
  variant split8-exit4 8192 "$E" split=8 exit_draws=4
  variant split16-exit4 8192 "$E" split=16 exit_draws=4
  variant expected-all 8192 "$E" expected_exits=all
  variant split8-exit4-expected 8192 "$E" split=8 exit_draws=4 expected_exits=all
done
rm -rf "$T"
echo done
