#!/bin/bash
# Old (cfc9e18) against new (this record's code) in one run on one 2-core machine:
#   bash run.sh OLD_BAKER NEW_BAKER > log.txt 2>&1
# Build each with `cargo build --release -p baker` at its commit and copy target/release/baker.
set -e
cd "$(dirname "$0")/../../.."
O=$1; N=$2
R=validation/bench-runs/2026-12-06-fiber-f32-lobes
P4=validation/bench-runs/2026-12-06-fiber-reflection-share/poly-thesis-ev32.yaml   # split 4, exit_draws 16
P8=$R/poly-thesis-split8.yaml                                                        # split 8, exit_draws 8
T=$(mktemp -d)
figures() {  # the manifest's noise, photons and sizes
  python3 -c "
import json,glob,sys;e=json.load(open(glob.glob(sys.argv[1]+'/*/manifest.json')[0]))['entries'][0]
n=e['noise'];p=e['photons']
print(f\"  at target {n['directions_at_target']}/45, median noise {n['median_rel_se']:.4%} (thesis {n['thesis_rel_se']:.4%}), photons min {p['min']} median {p['median']} max {p['max']} total {p['total']}, .bcsdf {e['bcsdf_bytes']} B, .h5 {e['hdf5_bytes']} B\")" "$1"
}
echo "== full polyester bakes at the thesis's noise (expected_exits all), alternating old/new"
for round in 1 2; do
  for spec in P4 P8; do
    for b in O N; do
      rm -rf $T/o
      /usr/bin/time -f "$spec $b round $round: %e s wall, %U s user" ${!b} bake --threads 2 -q -o $T/o ${!spec}
      figures $T/o
      cp $T/o/*/polyester/*.bcsdf $T/$spec-$b.bcsdf
    done
  done
done
for spec in P4 P8; do cmp -s $T/$spec-O.bcsdf $T/$spec-N.bcsdf && echo "$spec: .bcsdf identical old/new" || echo "$spec: .bcsdf differs old/new (f32 lobe densities)"; done
echo "== fiber bench --thesis, expected_exits all, polyester and silk"
for b in O N; do
  echo "-- $b"
  ${!b} fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --expected-exits all --entry polyester --entry silk --threads 2 2>&1 | sed -n '2,4p'
done
echo "-- N, split 8, exit_draws 8"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 3 --expected-exits all --split 8 --exit-draws 8 --entry polyester --entry silk --threads 2 2>&1 | sed -n '2,4p'
echo "-- N, cotton, 1 direction"
$N fiber bench --thesis specs/fibers-thesis.yaml --directions 1 --expected-exits all --entry cotton --threads 2 2>&1 | sed -n '2,3p'
rm -rf $T
echo done
