#!/usr/bin/env python3
"""The Mitsuba 3 plugin for baked fiber tables (baker_formats.mitsuba, `baker_bcsdf`).

How to run (from the repository root, after `pip install ./formats/python`):

    python3 validation/check_mitsuba_bcsdf.py --baker target/release/baker

What it does:
  1. bakes validation/specs/mitsuba_bcsdf.yaml (a round polyester and a non-round silk, each
     undyed and dyed; 10 deg bins, 4096 photons per stored direction) into a temporary folder
     (`--tables DIR` reuses a bake);
  2. frame: loads the plugin on a `bsplinecurve` that runs along a slanted world direction,
     intersects camera rays with it and compares the plugin's `eval` with the table's own
     `BcsdfTable.eval_many` at directions mapped independently here (world vectors: table z =
     the curve direction first -> last control point, x = `up` made perpendicular to it, y =
     z x x, so the section turns the right-handed way about the tangent): equal to 1e-5
     relative. The silk's table depends on the incoming azimuth, so the mirror image (the
     Chiang export's (x, z, y) map) must differ from it by > 10 %: the test can see the sign;
  3. chi2: Mitsuba's own `mitsuba.chi2.ChiSquareTest` with `BSDFAdapter` on a
     `SphericalDomain` (variant llvm_ad_rgb), `sample` against `pdf`, at 2 incoming directions
     per table (dyed variants), significance 0.01 with Sidak's correction over the 4 tests.
     The table's pdf is piecewise constant on 10 deg bins that the chi2 grid does not follow,
     so the pdf is integrated with ires = 32 sub-samples per cell of a res = 51 grid (the
     default ires = 4, and even 16, leave quadrature errors at the bins' edges that reject a
     correct sampler of the narrow polyester lobes: p < 1e-5) and 4e5 samples;
  4. white furnace: renders (llvm_ad_rgb, path tracer, unlimited depth with Russian roulette,
     64 x 64 px, 16 spp, box filter) the cloth patch of validation/render_cloth.py (two layers
     of parallel curves) made of each undyed table (no absorption: Lambda = 1) under a
     uniform `constant` emitter of radiance 1, and requires the mean over the pixels that see
     a fiber (an `aov` depth image) to be 1 within 4 standard errors plus the table's own
     energy defect: the pixels are independent estimates (independent sampler), so SE =
     std(pixels) / sqrt(n_pixels); the defect is max |1 - sum_b f dOmega| over the stored
     directions (f16/f32 storage and normalisation; ~1e-7 here). A dyed table must come out
     darker than 0.95 (the control: the test sees energy);
  5. speed: plugin eval and sample, in samples/s, scalar_rgb (one call per query) and
     llvm_ad_rgb (one call per wavefront of 2^18 queries).

`--plant pdf|shape|f|mirror` plants a bug (pdf x 1.1; the pdf of the theta_o-mirrored direction;
f x 1.05; the mirrored frame) and the check must then fail (exit 1): chi2 catches the first
two, the furnace the third, the frame test the fourth. Exits 1 on any failure. About 60 s on
2 cores (bake 12 s).
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

FAILURES = []


def check(ok, msg):
    print(("ok    " if ok else "FAIL  ") + msg, flush=True)
    if not ok:
        FAILURES.append(msg)


def bake(baker, out):
    spec = os.path.join(HERE, "specs", "mitsuba_bcsdf.yaml")
    subprocess.run([baker, "bake", "--quiet", spec, "-o", out], check=True)
    return os.path.join(out, "mitsuba_bcsdf")


def plant(kind):
    """Monkey-patches one bug into the plugin's table calls or frame."""
    import baker_formats
    import baker_formats.mitsuba as bm

    T = baker_formats.BcsdfTable
    if kind == "pdf":
        orig_ep, orig_s = T.eval_pdf_many, T.sample_many
        T.eval_pdf_many = lambda self, a, b, v=0: (lambda r: (r[0], r[1] * 1.1))(orig_ep(self, a, b, v))
        T.sample_many = lambda self, a, u, v=0: (lambda r: (r[0], r[1] * 1.1, r[2]))(orig_s(self, a, u, v))
    elif kind == "shape":
        orig_ep = T.eval_pdf_many

        def ep(self, a, b, v=0):
            f, _ = orig_ep(self, a, b, v)
            _, p = orig_ep(self, a, b * np.array([1.0, 1.0, -1.0]), v)
            return f, p
        T.eval_pdf_many = ep
    elif kind == "f":
        orig_s = T.sample_many
        T.sample_many = lambda self, a, u, v=0: (lambda r: (r[0], r[1], r[2] * 1.05))(orig_s(self, a, u, v))
        orig_ep = T.eval_pdf_many
        T.eval_pdf_many = lambda self, a, b, v=0: (lambda r: (r[0] * 1.05, r[1]))(orig_ep(self, a, b, v))
    elif kind == "mirror":
        orig = bm._local_axes

        def mirrored(s, t, n, up):
            x, y, z = orig(s, t, n, up)
            return x, -y, z
        bm._local_axes = mirrored
    print(f"planted bug: {kind}")


def frame_test(mi, tables):
    from baker_formats import BcsdfTable
    from baker_formats import mitsuba as bm

    rng = np.random.default_rng(7)
    with tempfile.TemporaryDirectory() as tmp:
        axis = np.array([0.8, 0.36, 0.48])
        axis /= np.linalg.norm(axis)
        a, b = -axis, axis
        r = 0.05
        curve = os.path.join(tmp, "c.txt")
        with open(curve, "w") as fh:      # a straight B-spline: 6 control points on the axis
            fh.write("".join(f"{p[0]} {p[1]} {p[2]} {r}\n" for p in np.linspace(a, b, 6)))
        up = np.array([0.0, 0.0, 1.0])
        for name in ("silk", "poly"):
            path = os.path.join(tables, name)
            scene = mi.load_dict({"type": "scene", "c": {
                "type": "bsplinecurve", "filename": curve,
                "bsdf": {"type": bm.PLUGIN, "filename": path, "variant": 1}}})
            bsdf = scene.shapes()[0].bsdf()
            n = 512
            # rays from random directions at random points along the curve, aimed at its axis
            # with a random offset across its width
            d = rng.normal(size=(n, 3))
            d -= (d @ axis)[:, None] * axis
            d /= np.linalg.norm(d, axis=1)[:, None]
            d += rng.uniform(-1.5, 1.5, n)[:, None] * axis
            d /= np.linalg.norm(d, axis=1)[:, None]
            side = np.cross(d, axis)
            side /= np.linalg.norm(side, axis=1)[:, None]
            target = rng.uniform(-0.3, 0.3, n)[:, None] * axis + rng.uniform(-0.9, 0.9, n)[:, None] * r * side
            o = target - 2.0 * d
            ray = mi.Ray3f(mi.Point3f(o.T.astype(np.float32)), mi.Vector3f(d.T.astype(np.float32)))
            si = scene.ray_intersect(ray)
            hit = np.array(si.is_valid(), dtype=bool)
            wo = rng.normal(size=(n, 3))
            wo /= np.linalg.norm(wo, axis=1)[:, None]
            f = np.array(bsdf.eval(mi.BSDFContext(), si, si.to_local(mi.Vector3f(wo.T.astype(np.float32)))),
                         dtype=np.float64).T
            tangent = np.array(si.sh_frame.t, dtype=np.float64).T
            x = up - (up @ axis) * axis
            x /= np.linalg.norm(x)
            y = np.cross(axis, x)
            to_table = np.stack([x, y, axis])          # rows: table axes in world space
            wi_t = (-d) @ to_table.T
            wo_t = wo @ to_table.T
            table = BcsdfTable(bsdf_path := bm.resolve_path(path))
            ref = table.eval_many(wi_t[hit], wo_t[hit], 1).astype(np.float64)
            mirrored = np.stack([x, -y, axis])          # the left-handed frame
            mirror = table.eval_many((-d[hit]) @ mirrored.T, wo[hit] @ mirrored.T, 1).astype(np.float64)
            got = f[hit]
            scale = np.abs(ref).max()
            err = np.abs(got - ref).max() / scale
            err_m = np.abs(mirror - ref).sum() / np.abs(ref).sum()
            check(hit.sum() > n // 2 and np.allclose(tangent[hit], axis, atol=1e-4),
                  f"frame {name}: {hit.sum()}/{n} rays hit; shading frame t = curve direction "
                  f"{axis.round(3).tolist()}")
            check(err < 1e-5, f"frame {name} ({os.path.basename(bsdf_path)}): plugin eval vs table "
                  f"eval in the right-handed table frame, max rel. difference {err:.2e} (<= 1e-5)")
            if name == "silk":
                check(err_m > 0.10, f"frame {name}: the mirrored frame differs by {err_m:.3f} "
                      "(relative L1, > 0.10: the check sees the azimuth's sign)")


def chi2_test(mi, tables):
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    dirs = [(0.6, 0.3, 0.742), (0.1, -0.95, 0.29)]
    tests = [(name, w) for name in ("poly", "silk") for w in dirs]
    results = []
    for name, w in tests:
        w = np.array(w) / np.linalg.norm(w)
        xml = (f'<string name="filename" value="{os.path.join(tables, name)}"/>'
               '<integer name="variant" value="1"/>')
        sf, pf = BSDFAdapter("baker_bcsdf", xml, wi=mi.Vector3f(*(float(x) for x in w)))
        chi = ChiSquareTest(domain=SphericalDomain(), sample_func=sf, pdf_func=pf, sample_dim=3,
                            res=51, ires=32, sample_count=400_000, seed=3)
        t0 = time.time()
        ok = chi.run(0.01, len(tests))
        results.append((name, w.round(3).tolist(), chi.p_value))
        check(bool(ok), f"chi2 {name} wi(local) = {w.round(3).tolist()}: p = {chi.p_value:.4f} "
              f"({time.time() - t0:.1f} s)")
        if not ok:
            print(chi.messages)
    return results


def furnace(mi, tables, res, spp):
    import render_cloth
    from baker_formats import BcsdfTable
    from baker_formats import mitsuba as bm

    out = {}
    for name, variant, dyed in (("silk", "undyed", False), ("poly", "undyed", False),
                                ("poly", 1, True)):
        path = os.path.join(tables, name)
        bsdf = {"type": "baker_bcsdf", "filename": path, "variant": variant}
        scene, aov = render_cloth.furnace_scenes(mi, bsdf, res, spp)
        t0 = time.time()
        img = np.array(mi.render(scene, seed=11), dtype=np.float64)
        dt = time.time() - t0
        depth = np.array(mi.render(aov, seed=1), dtype=np.float64)[..., 0]
        mask = depth > 0
        v = img[mask].mean(axis=1)
        mean, se = v.mean(), v.std(ddof=1) / math.sqrt(len(v))
        table = BcsdfTable(bsdf_path := bm.resolve_path(path))
        if dyed:
            check(mean < 0.95, f"furnace control {name} dyed ({table.variants[1]}): mean {mean:.4f} < 0.95")
            continue
        vi = table.variants.index(variant)
        fn = table.f_normalised()[:, vi]                      # [wi, channel, theta, phi]
        lam = table.directory["albedo"][:, vi]                # [wi, channel]
        ax = table.axes
        res_rad = math.radians(table.directory["res_deg"])
        th = np.radians(ax["theta_o_deg"])
        domega = (np.sin(th + res_rad / 2) - np.sin(th - res_rad / 2)) * res_rad
        energy = (fn * domega[None, None, :, None]).sum(axis=(2, 3)) * lam
        defect = float(np.abs(1.0 - energy).max())
        tol = 4 * se + defect
        out[name] = dict(mean=mean, se=se, tol=tol, pixels=int(mask.sum()), seconds=dt)
        check(abs(mean - 1.0) <= tol,
              f"furnace {name} undyed ({os.path.basename(bsdf_path)}): mean over {mask.sum()} fiber "
              f"pixels {mean:.5f}, |1 - mean| = {abs(mean - 1):.5f} <= 4 SE + defect = "
              f"4 x {se:.5f} + {defect:.1e} ({res} px, {spp} spp, {dt:.1f} s)")
    return out


def speed(mi, tables, n_jit=1 << 18, n_scalar=3000):
    import drjit as dr
    from baker_formats import mitsuba as bm

    rng = np.random.default_rng(5)
    wi = rng.normal(size=(n_jit, 3))
    wi /= np.linalg.norm(wi, axis=1)[:, None]
    wo = rng.normal(size=(n_jit, 3))
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    u = rng.uniform(size=(n_jit, 2))
    out = {}
    for variant in ("llvm_ad_rgb", "scalar_rgb"):
        mi.set_variant(variant)
        if variant != "scalar_rgb":
            bm.enable_jit_evaluation()
        bm.register()
        bsdf = mi.load_dict({"type": "baker_bcsdf", "filename": os.path.join(tables, "silk"), "variant": 1})
        ctx = mi.BSDFContext()
        if variant == "scalar_rgb":
            sis = []
            for k in range(n_scalar):
                s = dr.zeros(mi.SurfaceInteraction3f)
                s.wi = mi.Vector3f(*(float(x) for x in wi[k]))
                sis.append(s)
            wos = [mi.Vector3f(*(float(x) for x in wo[k])) for k in range(n_scalar)]
            us = [mi.Point2f(float(u[k, 0]), float(u[k, 1])) for k in range(n_scalar)]
            t0 = time.perf_counter()
            for k in range(n_scalar):
                bsdf.eval(ctx, sis[k], wos[k])
            te = time.perf_counter() - t0
            t0 = time.perf_counter()
            for k in range(n_scalar):
                bsdf.sample(ctx, sis[k], 0.5, us[k])
            ts = time.perf_counter() - t0
            n = n_scalar
        else:
            si = dr.zeros(mi.SurfaceInteraction3f, n_jit)
            si.wi = mi.Vector3f(wi.T.astype(np.float32))
            w = mi.Vector3f(wo.T.astype(np.float32))
            uu = mi.Point2f(u.T.astype(np.float32))
            dr.eval(si, w, uu)
            t0 = time.perf_counter()
            f = bsdf.eval(ctx, si, w)
            dr.eval(f)
            te = time.perf_counter() - t0
            t0 = time.perf_counter()
            bs, wt = bsdf.sample(ctx, si, dr.zeros(mi.Float, n_jit), uu)
            dr.eval(bs, wt)
            ts = time.perf_counter() - t0
            n = n_jit
        out[variant] = dict(eval_per_s=n / te, sample_per_s=n / ts)
        print(f"speed {variant}: eval {n / te:,.0f} samples/s, sample {n / ts:,.0f} samples/s "
              f"({n} queries, {os.cpu_count()} cores)")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", default="target/release/baker")
    ap.add_argument("--tables", help="reuse a bake of validation/specs/mitsuba_bcsdf.yaml (its folder)")
    ap.add_argument("--plant", choices=["pdf", "shape", "f", "mirror"])
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--json", help="write the numbers here")
    args = ap.parse_args()

    import mitsuba as mi

    t_all = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        tables = args.tables or bake(args.baker, tmp)
        if args.plant:
            plant(args.plant)
        from baker_formats import mitsuba as bm

        mi.set_variant("llvm_ad_rgb")
        bm.enable_jit_evaluation()
        bm.register()
        frame_test(mi, tables)
        p = chi2_test(mi, tables)
        fur = furnace(mi, tables, args.res, args.spp)
        sp = speed(mi, tables)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(chi2=p, furnace=fur, speed=sp), fh, indent=1)
    print(f"{len(FAILURES)} failure(s); {time.time() - t_all:.0f} s")
    sys.exit(1 if FAILURES else 0)


if __name__ == "__main__":
    main()
