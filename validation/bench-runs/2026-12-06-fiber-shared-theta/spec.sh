#!/usr/bin/env bash
# The thesis spec's silk and cotton as `specs/fibers-thesis.yaml` now sets them (share_theta 8,
# split 32, exit_draws 32): one whole φ column, dyed, 2 threads. Usage: spec.sh BAKER
set -euo pipefail
B=${1:-target/release/baker}
for e in silk cotton; do
  "$B" fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry "$e"
done
