#!/bin/bash
# The sweep ratio for polyester and cotton too (6°, 16,384 photons/direction, as silk in run.sh).
cd "$(dirname "$0")/../../.."
O=/tmp/meas3/baker-old; N=/tmp/meas3/baker-new
D=validation/bench-runs/2026-12-05-fiber-sweep-h5
for f in polyester cotton; do
  for b in O N O N; do B=${!b}; rm -rf /tmp/meas3/$f-one-$b /tmp/meas3/$f-sweep-$b
    /usr/bin/time -f "$f $b one %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas3/$f-one-$b $D/$f-one.yaml
    /usr/bin/time -f "$f $b sweep20 %e s wall, %U s user, %S s sys" $B bake --threads 2 -q -o /tmp/meas3/$f-sweep-$b $D/$f-sweep20.yaml
  done
  for k in one sweep; do cmp -s /tmp/meas3/$f-$k-O/*/$f/section-00.bcsdf /tmp/meas3/$f-$k-N/*/$f/section-00.bcsdf && echo "$f $k .bcsdf identical" || echo "$f $k .bcsdf differs (f32 fractions)"; done
done
echo done
