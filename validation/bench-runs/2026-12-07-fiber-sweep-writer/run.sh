#!/bin/bash
# alternate builds: O=old N=new; cotton one vs sweep20, R rounds
cd /work/main
S=validation/bench-runs/2026-12-05-fiber-sweep-h5
T=$(mktemp -d)
for r in $(seq ${R:-3}); do for b in O N; do B=/tmp/baker-$([ $b = O ] && echo old || echo new); for k in one sweep20; do
  rm -rf $T/out; t0=$(date +%s.%N)
  $B bake --threads 2 -q -o $T/out $S/cotton-$k.yaml
  t1=$(date +%s.%N); h5=$(stat -c %s $T/out/cotton-$k/cotton/cotton.h5)
  echo "$b $k $(echo "$t1 - $t0" | bc) h5=$h5"
done; done; done
rm -rf $T
