#!/bin/bash
# Alternating A/B of one direction's trace time, the thesis spec's estimators, 2 threads:
#   cp <old build> /tmp/baker-old; cp <new build> /tmp/baker-new
#   P=300000 bash ab-trace.sh > log.txt      (columns: round, entry, build, seconds)
cd "$(dirname "$0")/../../.."
for r in 1 2 3; do for e in cotton silk wool; do for b in ${B:-old new}; do
 s=$(/tmp/baker-$b fiber trace specs/fibers-thesis.yaml --entry $e --theta-i -45 --phi-i 30 --photons ${P:-300000} --json -q 2>/dev/null | python3 -c "import json,sys; d=json.load(sys.stdin); d=d[0] if isinstance(d,list) else d; print(round(d['seconds'],3))")
 echo "$r $e $b $s"; done; done; done
