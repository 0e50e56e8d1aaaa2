#!/usr/bin/env bash
# Old (the previous stop's build, 0b51225) against new (this record's build): the AVX2
# dispatch macro must change neither the bits nor the speed. Run from the repository root:
#   bash validation/bench-runs/2026-12-08-fiber-dispatch-macro/run.sh OLD_BAKER NEW_BAKER
set -euo pipefail
old=$1 new=$2
sweep=validation/bench-runs/2026-12-05-fiber-sweep-h5/cotton-sweep20.yaml
echo "# $(date -u +%FT%TZ) $(nproc) cores"
for b in old new; do
  bin=${!b}
  rm -rf /tmp/dispatch-$b
  /usr/bin/time -f "$b cotton sweep20 bake: %e s" "$bin" bake -q --threads 2 -o /tmp/dispatch-$b "$sweep"
done
for f in cotton/section-00.bcsdf cotton/cotton.h5; do
  cmp /tmp/dispatch-old/cotton-sweep20/$f /tmp/dispatch-new/cotton-sweep20/$f && echo "identical: $f"
done
for round in 1 2; do
  for b in old new; do
    bin=${!b}
    echo "$b round $round: $("$bin" fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry silk 2>&1 | grep '^silk')"
  done
done
