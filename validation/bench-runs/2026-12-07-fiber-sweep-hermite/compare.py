"""Old against new build's tables (run.sh with KEEP=DIR): per fiber and spec, the largest
relative difference of f_normalised over bins above 1e-3 of their slice's maximum, of the
albedo, and the albedo's difference in its own standard errors.
    python3 compare.py /tmp/keep"""
import glob, os, sys
import h5py, numpy as np

keep = sys.argv[1]
for old in sorted(glob.glob(f"{keep}/O-*")):
    new = old.replace("/O-", "/N-")
    for h in sorted(glob.glob(f"{old}/*/*/*.h5")):
        hn = new + h[len(old):]
        with h5py.File(h) as a, h5py.File(hn) as b:
            for g in a:
                fa, fb = a[g]["f_normalised"][()], b[g]["f_normalised"][()]
                big = fa > 1e-3 * fa.max(axis=(-2, -1), keepdims=True)
                rel = np.abs(fb - fa)[big] / fa[big]
                la, lb, se = a[g]["albedo"][()], b[g]["albedo"][()], a[g]["albedo_se"][()]
                z = np.abs(lb - la) / np.where(se > 0, se, np.inf)
                print(f"{os.path.basename(old)[2:]:18s} {g:12s} f: max rel {rel.max():.2e} "
                      f"mean {rel.mean():.2e} changed {np.mean(fa != fb):.4f}  albedo: max rel "
                      f"{np.max(np.abs(lb - la) / np.maximum(la, 1e-30)):.2e}, max {z.max():.3f} SE")
