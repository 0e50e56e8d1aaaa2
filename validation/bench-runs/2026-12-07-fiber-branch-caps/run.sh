#!/usr/bin/env bash
# Cotton's split events, three variations of who is followed after a split (issue 18, speed
# at the thesis's noise). Each is a temporary patch with an environment knob; its default
# reproduces the shipped tracer bit for bit. One whole φ column of the thesis bench per
# setting, nothing else running:
#   bash validation/bench-runs/2026-12-07-fiber-branch-caps/run.sh > log.txt 2>&1
set -euo pipefail
cd "$(dirname "$0")/../../.."
R=validation/bench-runs/2026-12-07-fiber-branch-caps
bench() { target/release/baker fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry cotton 2>&1 | grep "^cotton"; }
try() { # patch, variable, values…
  local p=$1 v=$2; shift 2
  git apply $R/$p
  cargo build --release -q
  for x in "$@"; do echo "== $p: $v=$x"; env $v=$x bash -c "$(declare -f bench); bench"; done
  git apply -R $R/$p
}
try branch-cap.patch BAKER_BRANCHES 0 1 4 8
try stay-children.patch BAKER_STAYS 1 2 4
try child-draws.patch BAKER_CHILD_DRAWS 1 4
try split-child.patch BAKER_SPLIT_CHILD 0 1
cargo build --release -q
