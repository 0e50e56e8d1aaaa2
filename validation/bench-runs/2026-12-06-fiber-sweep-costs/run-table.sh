#!/bin/bash
# The issue's table with this record's code (NEW), after run.sh:
#   bash run-table.sh OLD_BAKER NEW_BAKER > log-table.txt 2>&1
# The first part is the previous record's table script (the spec's estimators undyed and
# dyed, dyed with the expectation, tracer rates, sweeps, default bits old/new); then what
# that record measured in its run.sh: undyed with the expectation, and the polyester bake.
set -e
cd "$(dirname "$0")/../../.."
N=$2
bash validation/bench-runs/2026-12-06-fiber-f32-lobes/run-table.sh "$1" "$2"
echo "== undyed, expected_exits all: polyester and silk (3 directions), cotton (1)"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --expected-exits all --entry polyester --entry silk --threads 2 2>&1 | sed -n '2,4p'
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 1 --expected-exits all --entry cotton --threads 2 2>&1 | sed -n '2,3p'
echo "== polyester at the thesis's noise, split 8, full bake, with the manifest's figures"
T=$(mktemp -d)
/usr/bin/time -f "poly-thesis-split8: %e s wall, %U s user" $N bake --threads 2 -q -o $T validation/bench-runs/2026-12-06-fiber-f32-lobes/poly-thesis-split8.yaml
python3 -c "
import json,glob,sys;e=json.load(open(glob.glob(sys.argv[1]+'/*/manifest.json')[0]))['entries'][0]
n=e['noise'];p=e['photons']
print(f\"  at target {n['directions_at_target']}/45, median noise {n['median_rel_se']:.4%} (thesis {n['thesis_rel_se']:.4%}), photons min {p['min']} median {p['median']} max {p['max']} total {p['total']}, .bcsdf {e['bcsdf_bytes']} B, .h5 {e['hdf5_bytes']} B\")" $T
rm -rf $T
echo done
