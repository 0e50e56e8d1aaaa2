#!/bin/bash
# The polyester sweep ratio at millisecond resolution (/usr/bin/time rounds to 10 ms, a
# twentieth of a 0.2 s bake): 20 rounds, old and new alternating, mean and median wall time.
#   O=... N=... bash ratio.sh > ratio.txt 2>&1
cd "$(dirname "$0")/../../.."
O=${O:-/tmp/meas6/baker-old}; N=${N:-/tmp/meas6/baker-new}
S=validation/bench-runs/2026-12-05-fiber-sweep-h5
T=$(mktemp -d)
for r in $(seq 20); do for b in O N; do B=${!b}; for k in one sweep20; do
  rm -rf $T/out; t0=$(date +%s.%N)
  $B bake --threads 2 -q -o $T/out $S/polyester-$k.yaml
  echo "$b $k $(echo "$(date +%s.%N) - $t0" | bc)"
done; done; done > $T/times
python3 - $T/times <<'P'
import sys, statistics as st
t = {}
for line in open(sys.argv[1]):
    b, k, s = line.split(); t.setdefault((b, k), []).append(float(s))
for b in ("O", "N"):
    one, sw = t[(b, "one")], t[(b, "sweep20")]
    print(f"{b}: one variant mean {st.mean(one):.4f} s (median {st.median(one):.4f}), 20 variants mean {st.mean(sw):.4f} s (median {st.median(sw):.4f}); ratio of means {st.mean(sw)/st.mean(one):.3f}, of medians {st.median(sw)/st.median(one):.3f}")
P
rm -rf $T
