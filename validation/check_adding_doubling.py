#!/usr/bin/env python3
"""Cross-check of `baker mc` (Monte Carlo) total reflectance and transmittance against adding-doubling.

How to run (from anywhere; the repository root is found from this file's path):

    pip install -r validation/requirements.txt
    python3 validation/check_adding_doubling.py                             # builds the release binary
    python3 validation/check_adding_doubling.py --baker target/release/baker  # skip cargo
    python3 validation/check_adding_doubling.py --only 'n=1.4' -v          # subset, with breakdown

Reference: the adding-doubling (AD) solution of the radiative transport equation,
S. A. Prahl, M. J. C. van Gemert, A. J. Welch, "Determining the optical properties of turbid
media by using the adding-doubling method", Appl. Opt. 32(4), 559-568 (1993), as implemented
in Prahl's Python package `iadpython` (version 0.5.3, pinned in validation/requirements.txt).
Nothing of the Rust code is reused.

Geometry: one homogeneous slab of index n between air (n_above = n_below = 1), physical
thickness 1 mm, optical thickness b = mu_t * d, albedo a = mu_s / mu_t, Henyey-Greenstein
anisotropy g; pencil beam at normal incidence (AD: collimated normal illumination; total
fluxes do not depend on the beam's width). Semi-infinite cases use d = "inf" in the stack
(mu_t = 1/mm) and b = 1e4 in AD (its transmission underflows to 0).

What is compared (per case, both must pass):
  * R_total: AD `UR1` vs MC `rsp + rd + rd_unscattered`. UR1 is the total reflectance for
    collimated normal incidence and *includes* the specular reflection at the top surface and
    the unscattered light that comes back out of the top after reflecting inside the slab
    (the script checks this at start-up: for a = 0, UR1 equals iadpython's
    `unscattered_rt()` reflectance, which is the specular/unscattered term).
  * T_total: AD `UT1` vs MC `tt`. Both include the unscattered (ballistic) transmission.
  Standard error: R's SE is sqrt(rsp_se^2 + rd_se^2 + rd_unscattered_se^2) (missing *_se
  keys count as 0; this ignores the components' negative covariance, i.e. is conservative);
  T's SE is tt_se.
  Pass: |MC - AD| <= 4*SE_MC + 2e-4 (2e-4 allows for the AD discretisation).
  Seeds are fixed per case (CRC32 of the case name), so runs are reproducible for a given
  binary and thread count.

AD accuracy: 24 quadrature points when n = 1, 48 (24 Gauss below the critical angle + 24
Radau above) when n != 1. iadpython 0.5.3 computes Radau weights from a numpy poly1d
derivative that loses precision above ~24 points (weights off by 4e-5 at 32 points, garbage
at 64), so more points would be *less* accurate; the script refuses to run if the Radau
weights it will use do not sum to 1 within 1e-6. Convergence, estimated as the change from
16 (n = 1) or 32 (n != 1) points, is <= ~3e-5 for every case here; it is printed ("AD conv")
and a warning is given if it exceeds 1e-4. Sanity anchor: a = 0.9, g = 0.75, b = 2, n = 1
gives UR1 = 0.09739, UT1 = 0.66096 (van de Hulst's tabulated values).

Case grid: slabs with a in {0.5, 0.9, 0.99} x g in {0, 0.75, 0.9} x n in {1.0, 1.4} x
b in {1, 4} (36 cases, --photons each, default 2e6), plus semi-infinite a in {0.9, 0.99} x
g in {0, 0.9}, n = 1.4 (4 cases, --photons-semi each, default 1e6). With these defaults the MC
SEs are ~1e-4..4e-4, and the MC runs take ~45 s in all on 2 cores (release build).

Prints a table (case, AD, MC +- SE, z-score for R and T) and finally
`check_adding_doubling: N passed, M failed` (N, M count (case, quantity) comparisons, two per
case); exits with 1 if any comparison fails or the baker cannot be run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import iadpython
import iadpython.quadrature

REPO = Path(__file__).resolve().parent.parent

TOL_AD = 2e-4  # allowance for the adding-doubling discretisation
K_SIGMA = 4.0  # allowed number of MC standard errors
B_SEMI_INFINITE = 1e4  # AD optical thickness standing in for a semi-infinite medium
MUT_SEMI_INFINITE = 1.0  # mu_t [1/mm] of the semi-infinite MC stacks
GRID = {"dr_mm": 0.01, "nr": 100}


@dataclass
class Case:
    a: float
    g: float
    n: float
    b: float  # optical thickness; math.inf for semi-infinite
    photons: int

    @property
    def semi_infinite(self) -> bool:
        return math.isinf(self.b)

    @property
    def name(self) -> str:
        b = "inf" if self.semi_infinite else f"{self.b:g}"
        return f"a={self.a:g} g={self.g:g} n={self.n:g} b={b}"

    @property
    def seed(self) -> int:
        return zlib.crc32(self.name.encode()) & 0x7FFFFFFF

    def stack(self) -> dict:
        if self.semi_infinite:
            d, mut = "inf", MUT_SEMI_INFINITE
        else:
            d, mut = 1.0, self.b / 1.0
        layer = {
            "name": "slab",
            "d_mm": d,
            "eta": self.n,
            "mua_per_mm": (1.0 - self.a) * mut,
            "mus_per_mm": self.a * mut,
            "g": self.g,
        }
        return {"n_above": 1.0, "n_below": 1.0, "layers": [layer], "grid": GRID}


def cases(photons: int, photons_semi: int) -> list[Case]:
    out = []
    for n in (1.0, 1.4):
        for b in (1.0, 4.0):
            for a in (0.5, 0.9, 0.99):
                for g in (0.0, 0.75, 0.9):
                    out.append(Case(a, g, n, b, photons))
    for a in (0.9, 0.99):
        for g in (0.0, 0.9):
            out.append(Case(a, g, 1.4, math.inf, photons_semi))
    return out


# ---------------------------------------------------------------- adding-doubling (iadpython)

def quad_points(n: float) -> tuple[int, int]:
    """(quadrature points used, fewer points for the convergence estimate)."""
    return (24, 16) if n == 1.0 else (48, 32)


def check_radau(npts: int) -> None:
    """iadpython's Radau weights degrade above ~24 points; refuse to use bad ones."""
    _, w = iadpython.quadrature.radau(npts, a=0, b=1)
    if abs(w.sum() - 1.0) > 1e-6:
        raise RuntimeError(f"iadpython Radau quadrature with {npts} points is inaccurate "
                           f"(weights sum to {w.sum():.12f}); use fewer quadrature points")


def ad_sample(a: float, g: float, n: float, b: float, quad: int) -> iadpython.Sample:
    bb = B_SEMI_INFINITE if math.isinf(b) else b
    return iadpython.Sample(a=a, b=bb, g=g, d=1.0, n=n, n_above=1.0, n_below=1.0, quad_pts=quad)


def ad_rt(case: Case) -> dict:
    """AD total reflectance/transmittance (collimated normal incidence) and a convergence estimate."""
    q, q_low = quad_points(case.n)
    check_radau(q if case.n == 1.0 else q // 2)
    ur1, ut1, _, _ = ad_sample(case.a, case.g, case.n, case.b, q).rt()
    ur1_l, ut1_l, _, _ = ad_sample(case.a, case.g, case.n, case.b, q_low).rt()
    r_u, t_u = ad_sample(case.a, case.g, case.n, case.b, q).unscattered_rt()
    return {
        "R": float(ur1),
        "T": float(ut1),
        "R_unscattered": float(r_u),
        "T_unscattered": float(t_u),
        "conv": max(abs(ur1 - ur1_l), abs(ut1 - ut1_l)),
        "quad_pts": q,
    }


def ad_selfcheck() -> None:
    """Pin down iadpython's conventions that the comparison relies on."""
    # UR1/UT1 include the specular reflection and the unscattered transmission:
    # with no scattering they equal the unscattered (Fresnel + Beer) terms.
    for n in (1.0, 1.4):
        s = ad_sample(0.0, 0.0, n, 1.0, quad_points(n)[0])
        ur1, ut1, _, _ = s.rt()
        r_u, t_u = s.unscattered_rt()
        rs = ((n - 1) / (n + 1)) ** 2
        tb = math.exp(-1.0)
        r_exact = rs + (1 - rs) ** 2 * rs * tb**2 / (1 - rs**2 * tb**2)
        t_exact = (1 - rs) ** 2 * tb / (1 - rs**2 * tb**2)
        for what, got, want in (("UR1", ur1, r_u), ("UT1", ut1, t_u),
                                ("unscattered r", r_u, r_exact), ("unscattered t", t_u, t_exact)):
            if abs(float(got) - float(want)) > 1e-5:
                raise RuntimeError(f"iadpython convention check failed (n={n}, a=0): "
                                   f"{what} = {float(got):.6f}, expected {float(want):.6f}")
    # Anchor: van de Hulst's tabulated slab (a=0.9, g=0.75, b=2, n=1): R=0.09739, T=0.66096.
    ur1, ut1, _, _ = ad_sample(0.9, 0.75, 1.0, 2.0, 24).rt()
    if abs(ur1 - 0.09739) > 5e-5 or abs(ut1 - 0.66096) > 5e-5:
        raise RuntimeError(f"iadpython anchor check failed: R={ur1:.5f} T={ut1:.5f}, "
                           "expected 0.09739 / 0.66096")


# ---------------------------------------------------------------- Monte Carlo (baker mc)

def build_baker() -> Path:
    print("building: cargo build --release -q -p baker", flush=True)
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "baker"], cwd=REPO, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    if not target.is_absolute():
        target = REPO / target
    return target / "release" / "baker"


def run_mc(baker: Path, case: Case, workdir: Path, timeout: float) -> dict:
    path = workdir / (re.sub(r"[^A-Za-z0-9.]+", "_", case.name) + ".json")
    path.write_text(json.dumps(case.stack(), indent=1))
    cmd = [str(baker), "mc", str(path), "--photons", str(case.photons), "--seed", str(case.seed), "--json"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"`{' '.join(cmd)}` exited {p.returncode}:\n{p.stderr.strip()}")
    try:
        doc = json.loads(p.stdout)
    except json.JSONDecodeError as e:
        raise RuntimeError(f"`{' '.join(cmd)}` did not print one JSON object ({e}):\n{p.stdout[:500]}")
    doc["_wall_s"] = wall
    return doc


def num(doc: dict, key: str) -> float:
    v = doc.get(key, 0.0)
    return 0.0 if v is None else float(v)


def mc_rt(doc: dict) -> dict:
    missing = [k for k in ("rsp", "rd", "rd_unscattered", "tt", "rd_se", "tt_se") if k not in doc]
    if missing:
        raise RuntimeError(f"baker mc JSON lacks keys {missing}")
    r_keys = ("rsp", "rd", "rd_unscattered")
    return {
        "R": sum(num(doc, k) for k in r_keys),
        "R_se": math.sqrt(sum(num(doc, k + "_se") ** 2 for k in r_keys)),
        "T": num(doc, "tt"),
        "T_se": num(doc, "tt_se"),
    }


# ---------------------------------------------------------------- comparison

def judge(ad: float, mc: float, se: float) -> tuple[bool, float]:
    diff = mc - ad
    ok = abs(diff) <= K_SIGMA * se + TOL_AD
    if abs(diff) < 1e-12:  # e.g. semi-infinite T: MC exactly 0, AD ~1e-244
        return ok, 0.0
    z = diff / se if se > 0 else math.copysign(math.inf, diff)
    return ok, z


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baker", help="baker binary to use (default: cargo build --release, target/release/baker)")
    ap.add_argument("--photons", type=float, default=2e6, help="photons per slab case (default 2e6)")
    ap.add_argument("--photons-semi", type=float, default=1e6,
                    help="photons per semi-infinite case (default 1e6)")
    ap.add_argument("--only", metavar="REGEX", help="run only cases whose name matches (e.g. 'n=1.4')")
    ap.add_argument("--timeout", type=float, default=300, help="seconds allowed per MC run (default 300)")
    ap.add_argument("--keep", metavar="DIR", help="write the stack files to DIR and keep them")
    ap.add_argument("--json-out", metavar="PATH", help="write all results as JSON to PATH")
    ap.add_argument("-v", "--verbose", action="store_true",
                    help="also print the unscattered/specular breakdown and MC timings")
    args = ap.parse_args()

    all_cases = cases(int(args.photons), int(args.photons_semi))
    if args.only:
        all_cases = [c for c in all_cases if re.search(args.only, c.name)]
        if not all_cases:
            print(f"no case matches {args.only!r}", file=sys.stderr)
            return 1

    print(f"iadpython {getattr(iadpython, '__version__', '?')}, numpy {np.__version__}")
    ad_selfcheck()
    t0 = time.perf_counter()
    ad = {c.name: ad_rt(c) for c in all_cases}
    print(f"adding-doubling: {len(ad)} cases in {time.perf_counter() - t0:.1f} s "
          f"(max convergence estimate {max(v['conv'] for v in ad.values()):.1e})")
    for name, v in ad.items():
        if v["conv"] > 1e-4:
            print(f"WARNING: AD not converged to 1e-4 for {name}: change {v['conv']:.1e}")

    try:
        baker = Path(args.baker).resolve() if args.baker else build_baker()
    except subprocess.CalledProcessError as e:
        print(f"cargo build failed: {e}", file=sys.stderr)
        print("check_adding_doubling: 0 passed, 1 failed")
        return 1

    tmp = None
    if args.keep:
        workdir = Path(args.keep)
        workdir.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="check_ad_")
        workdir = Path(tmp.name)

    passed = failed = 0
    zs = []
    results = []
    mc_total = 0.0
    hdr = (f"{'case':<28} {'R_AD':>8} {'R_MC':>8} {'± SE':>7} {'z':>6}   "
           f"{'T_AD':>8} {'T_MC':>8} {'± SE':>7} {'z':>6}  {'AD conv':>7}  result")
    print(hdr)
    print("-" * len(hdr))
    for c in all_cases:
        a = ad[c.name]
        try:
            doc = run_mc(baker, c, workdir, args.timeout)
            m = mc_rt(doc)
        except (RuntimeError, subprocess.TimeoutExpired, OSError) as e:
            print(f"{c.name:<28} ERROR: {e}")
            failed += 2
            results.append({"case": c.name, "error": str(e)})
            continue
        mc_total += doc["_wall_s"]
        ok_r, z_r = judge(a["R"], m["R"], m["R_se"])
        ok_t, z_t = judge(a["T"], m["T"], m["T_se"])
        for ok, z in ((ok_r, z_r), (ok_t, z_t)):
            passed += ok
            failed += not ok
            if math.isfinite(z) and z != 0.0:
                zs.append(z)
        bad = [q for q, ok in (("R", ok_r), ("T", ok_t)) if not ok]
        verdict = "ok" if not bad else "FAIL " + ",".join(bad)
        print(f"{c.name:<28} {a['R']:8.5f} {m['R']:8.5f} {m['R_se']:7.5f} {z_r:6.2f}   "
              f"{a['T']:8.5f} {m['T']:8.5f} {m['T_se']:7.5f} {z_t:6.2f}  {a['conv']:7.1e}  {verdict}",
              flush=True)
        if args.verbose:
            print(f"{'':<28} unscattered R: AD {a['R_unscattered']:.5f}, MC rsp+rd_unscattered "
                  f"{num(doc, 'rsp') + num(doc, 'rd_unscattered'):.5f} (rsp {num(doc, 'rsp'):.5f}); "
                  f"AD unscattered T {a['T_unscattered']:.5f}; MC rd {num(doc, 'rd'):.5f}; "
                  f"{c.photons} photons in {doc['_wall_s']:.2f} s "
                  f"({doc.get('photons_per_s', float('nan')):.3g}/s, {doc.get('threads', '?')} threads)")
        results.append({"case": c.name, "seed": c.seed, "photons": c.photons, "ad": a,
                        "mc": m, "ok_R": ok_r, "ok_T": ok_t, "z_R": z_r, "z_T": z_t,
                        "mc_raw": {k: v for k, v in doc.items() if k not in ("r_mm", "rd_r_per_mm2",
                                                                              "rd_r_per_mm2_se")}})
    if tmp is not None:
        tmp.cleanup()

    if zs:
        zz = np.array(zs)
        print(f"MC time {mc_total:.1f} s; z-scores: n={zz.size}, mean {zz.mean():+.2f}, "
              f"rms {math.sqrt(float(np.mean(zz**2))):.2f} (≈1 if the SEs are right and there is no bias), "
              f"max |z| {np.abs(zz).max():.2f}")
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(results, indent=1, default=float))
    print(f"check_adding_doubling: {passed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
