#!/bin/bash
# Old (HEAD before this record) against new, alternating, one whole φ column each at the
# thesis's noise, with the CPU time /usr/bin/time reports:
#   O=old-baker N=new-baker bash run.sh > log.txt 2>&1
cd "$(dirname "$0")/../../.."
for r in 1 2; do for e in silk cotton; do for b in O N; do
  /usr/bin/time -f "$b $e round $r: %e s wall, %U s user" ${!b} fiber bench --thesis specs/fibers-thesis.yaml --columns 1 --dyed --entry $e 2>&1 | grep -E "^$e|wall"
done; done; done
