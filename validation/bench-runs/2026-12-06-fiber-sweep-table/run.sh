#!/bin/bash
# Old (83fc005, the previous record's code) against new (this record's commit), on one machine
# in one run: the previous record's script with five polyester rounds.
# Build: git worktree add /tmp/landed 83fc005 && (cd /tmp/landed && CARGO_TARGET_DIR=/tmp/landed-target cargo build --release -p baker)
#        cargo build --release -p baker; then
#        O=old-binary N=new-binary bash run.sh > log.txt 2>&1   (needs h5py)
POLY_ROUNDS=5 exec bash "$(dirname "$0")/../2026-12-06-fiber-sweep-costs/run.sh"
