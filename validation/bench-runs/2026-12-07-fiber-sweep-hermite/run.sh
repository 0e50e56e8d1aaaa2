#!/usr/bin/env bash
# One variant against a 20-variant sweep (6°, 16,384 photons per direction, RGB; the specs of
# ../2026-12-06-fiber-sweep-costs), old and new build alternating, R rounds (default 3):
#   O=/tmp/baker-old N=/tmp/baker-new bash validation/bench-runs/2026-12-07-fiber-sweep-hermite/run.sh > log-sweep-ab.txt 2>&1
# Keeps the last round's outputs under $KEEP (if set) for compare.py.
set -euo pipefail
cd "$(dirname "$0")/../../.."
S=validation/bench-runs/2026-12-05-fiber-sweep-h5; E=validation/bench-runs/2026-12-03-fiber-estimators
T=$(mktemp -d)
for r in $(seq "${R:-3}"); do
  for fs in "polyester $S/polyester" "silk $E/silk" "cotton $S/cotton"; do
    set -- $fs
    for b in O N; do
      B=${!b}
      for k in one sweep20; do
        rm -rf "$T/$b-$1-$k"
        t0=$(date +%s.%N)
        "$B" bake --threads 2 -q -o "$T/$b-$1-$k" "$2-$k.yaml"
        t1=$(date +%s.%N)
        printf '%s round %s %s %-8s %6.2f s\n' "$b" "$r" "$1" "$k" "$(echo "$t1 - $t0" | bc)"
      done
    done
  done
done
if [ -n "${KEEP:-}" ]; then mkdir -p "$KEEP"; for d in "$T"/*; do rm -rf "$d/.cache"; done; cp -r "$T"/* "$KEEP"/; fi
rm -rf "$T"
