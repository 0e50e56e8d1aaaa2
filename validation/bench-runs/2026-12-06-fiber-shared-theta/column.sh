#!/usr/bin/env bash
# One whole φ column of ENTRY's stored directions (45 θ rows), dyed, 2 threads, per setting
# "SHARE_THETA SPLIT EXIT_DRAWS", one after another in this run (the logs' order).
# Usage: column.sh BAKER ENTRY "1 16 16" "8 32 32" ...
set -euo pipefail
B=$1; e=$2; shift 2
for a in "$@"; do
  set -- $a
  "$B" fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry "$e" \
    --share-theta "$1" --split "$2" --exit-draws "$3" 2>&1 | grep "^$e"
done
