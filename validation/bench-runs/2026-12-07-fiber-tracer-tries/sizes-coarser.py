# Silk's .bcsdf model (../2026-12-06-fiber-storage-limits/size.py, on the 45 slices its README's
# dump step writes to /tmp/dump/silk) at coarser rounding and with the R − G, B − G decorrelation:
#   cd validation/bench-runs/2026-12-06-fiber-storage-limits && python3 ../2026-12-07-fiber-tracer-tries/sizes-coarser.py
# q is quantise_to_se: the largest rounding error, as a fraction of the bin's standard error.
exec(open('size.py').read().split("print('n',n)")[0])
for kw in [dict(q=0.25), dict(q=0.5), dict(q=1.0), dict(q=0.5, mode='chdelta'), dict(q=1.0, mode='chdelta')]:
    print(kw, '%.1f MB' % tot(**kw))
