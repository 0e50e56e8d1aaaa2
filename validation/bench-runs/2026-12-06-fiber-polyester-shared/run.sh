#!/usr/bin/env bash
# Polyester's whole thesis bake (specs/fibers-thesis.yaml, --entry polyester: 45 stored
# directions, 2° bins, dyed, each to the thesis's noise) alone (share_theta 1, the spec before
# this record) and sharing 8 θ rows (the spec now), alternating, twice, on one 2-core
# machine with nothing else running; then the thesis bench's column for both.
#   bash validation/bench-runs/2026-12-06-fiber-polyester-shared/run.sh BAKER > log.txt 2>&1
set -euo pipefail
cd "$(dirname "$0")/../../.."
B=$1
T=$(mktemp -d)
# The spec as it was: the same entry without share_theta.
sed 's/expected_exits: all, share_theta: 8}}/expected_exits: all}}/' specs/fibers-thesis.yaml > $T/alone.yaml
grep -q "split: 8, exit_draws: 8, expected_exits: all}}" $T/alone.yaml
figures() {
  python3 -c "
import json,glob,sys;e=json.load(open(glob.glob(sys.argv[1]+'/*/manifest.json')[0]))['entries'][0]
n=e['noise'];p=e['photons']
print(f\"  at target {n['directions_at_target']}, median noise {n['median_rel_se']:.4%} (thesis {n['thesis_rel_se']:.4%}), photons median {p['median']} total {p['total']}, albedo RGB max {max(e['albedo'][0]['max']):.4f}, .bcsdf {e['bcsdf_bytes']} B\")" "$1"
}
for round in 1 2; do
  for spec in $T/alone.yaml specs/fibers-thesis.yaml; do
    rm -rf $T/o
    /usr/bin/time -f "round $round $(basename $spec): %e s wall, %U s user" "$B" bake --threads 2 -q --entry polyester -o $T/o $spec
    figures $T/o
  done
done
for k in 1 8; do
  "$B" fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry polyester --share-theta $k 2>&1 | grep "^polyester"
done
rm -rf $T
