#!/usr/bin/env python3
"""Closed-form check of `baker fiber trace` for a smooth circular dielectric fiber.

How to run (the repository root is the parent of this file's folder; nothing is built here):

    python3 validation/check_fiber_cylinder.py --self-test        # closed form only, no baker
    python3 validation/check_fiber_cylinder.py                    # 6 MC runs vs closed form
    python3 validation/check_fiber_cylinder.py --baker PATH --photons 4000000 --seed 7 --plot f.png

References (nothing of the Rust code is reused):
  S. R. Marschner, H. W. Jensen, M. Cammarano, S. Worley, P. Hanrahan, "Light scattering from
  human hair fibers", ACM TOG 22(3) (SIGGRAPH 2003), 780-791: Bravais index, exit azimuth.
  E. d'Eon, G. Francois, M. Hill, J. Letteri, J.-M. Aubry, "An energy-conserving hair
  reflectance model", Comput. Graph. Forum 30(4) (EGSR 2011), 1181-1187: attenuation A_p.

Conventions (those of the tracer): fiber axis +z; omega_i points TOWARDS the light, omega_o
is the direction the photon leaves in; theta = asin(omega.z), phi = atan2(omega.y, omega.x);
dphi = phi_o - phi_i wrapped to [-180, 180) deg. A smooth cylinder of radius R = D/2 (um),
index eta, absorption mua (1/um), lit by a parallel beam at longitudinal angle theta_i sends
all light to the cone theta_o = -theta_i. Azimuthally, with the beam offset h uniform on
[-1, 1] (the beam covers exactly the projected width D):
  gamma_i = asin(h);  eta' = sqrt(eta^2 - sin^2 theta_i) / cos theta_i   (Bravais)
  gamma_t = asin(h / eta');  sin theta_t = sin theta_i / eta
  phi_p(h) = 2 p gamma_t - 2 gamma_i + p pi, wrapped to [-pi, pi)   (p = 0: R, 1: TT, 2: TRT..)
  A_0 = F,  A_p = (1 - F)^2 F^(p-1) T^p  (p >= 1)
  F = unpolarised Fresnel reflectance (mean of s and p) of relative index eta at the true 3-D
      angle of incidence, cos = cos theta_i cos gamma_i (internal reflections have the same F
      by reciprocity);  T = exp(-mua 2R cos gamma_t / cos theta_t) (3-D chord length).
  Without absorption sum_p A_p = F + (1-F)^2 sum_{p>=1} F^(p-1) = 1 exactly.
Reference per 2-degree dphi bin b (180 bins from -180):
  ref[b] = (1/2) int_{-1}^{1} sum_p A_p(h) 1[phi_p(h) in b] dh,
by midpoint quadrature in h (--quad-points, default 2**21). The sum over p is not cut at a
fixed P: the light still inside, (1-F) (F T)^p, is followed per h until it is < 1e-18 or its
total is < 1e-16 of the beam (near grazing F -> 1: a fixed P = 40 would lose ~1e-5 of it). The
quadrature error per bin is estimated as |ref(Nq) - ref(Nq/2)|.

Check per run (eta = 1.55, D = 10 um, theta_i in {0, 30, 60} deg x mua in {0, 0.05}/um,
phi_i = 0, --photons, seed --seed + run index):
  * z_b = (mc_b - ref_b) / se_b, se_b = sqrt(mc_se_b^2 + qerr_b^2), where mc_se is
    `dphi_hist_se`; bins with mc_b = 0 < ref_b use sqrt(ref_b / N + qerr_b^2), N = `photons`.
    Pass if max_b |z_b| < z*, the Sidak two-sided threshold for 180 bins at family-wise
    alpha = --alpha (0.001) per run: z* = Phi^-1(1 - a1/2), a1 = 1 - (1 - alpha)^(1/180).
  * |albedo - sum(ref)| <= 4 albedo_se (+1e-9); for mua = 0 also |albedo - 1| <= 4 SE (+1e-9).
  * sum(dphi_hist) equals albedo (1e-6 relative) and >= (1 - 1e-9) albedo lies in the hist2d
    rows whose theta range comes within 2 deg of -theta_i (-60 lies on a bin edge).
Prints one line per run and exits 1 on any failure (or if the baker cannot be run).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
from pathlib import Path

import numpy as np

NBINS = 180
ROOT = Path(__file__).resolve().parent.parent


def fresnel(cos_i, eta):
    """Unpolarised Fresnel reflectance, outside -> inside of relative index eta > 1."""
    cos_i = np.clip(cos_i, 0.0, 1.0)
    cos_t = np.sqrt(1.0 - (1.0 - cos_i**2) / eta**2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp)


def geometry(h, theta_i_deg, eta, mua, diam):
    th = math.radians(theta_i_deg)
    gi = np.arcsin(h)
    eta_p = math.sqrt(eta**2 - math.sin(th) ** 2) / math.cos(th)
    gt = np.arcsin(h / eta_p)
    f = fresnel(math.cos(th) * np.cos(gi), eta)
    cos_tt = math.sqrt(1.0 - (math.sin(th) / eta) ** 2)
    t = np.exp(-mua * diam * np.cos(gt) / cos_tt)
    return gi, gt, f, t


def reference(theta_i_deg, eta, mua, diam, nq, split=False):
    """ref[180] (fraction of intercepted power per dphi bin); split=True also returns R only."""
    h = -1.0 + (np.arange(nq) + 0.5) * (2.0 / nq)
    gi, gt, f, t = geometry(h, theta_i_deg, eta, mua, diam)
    hist = np.zeros(NBINS)

    def deposit(phi, weight):
        b = np.floor(np.mod(phi + math.pi, 2 * math.pi) / (2 * math.pi) * NBINS).astype(np.int64)
        hist[:] += np.bincount(np.clip(b, 0, NBINS - 1), weights=weight, minlength=NBINS)

    deposit(-2.0 * gi, f)
    r_only = hist.sum() / nq
    w = 1.0 - f  # power inside, per unit incident, still to be emitted
    p = 1
    while w.size:
        w = w * t
        deposit(2 * p * gt - 2 * gi + p * math.pi, w * (1.0 - f))
        w = w * f
        if w.sum() < 1e-16 * nq:  # all light still inside is < 1e-16 of the beam: stop
            break
        keep = w > 1e-18
        gi, gt, f, t, w = gi[keep], gt[keep], f[keep], t[keep], w[keep]
        p += 1
    return (hist / nq, r_only) if split else hist / nq


def albedo_closed(theta_i_deg, eta, mua, diam, n=4000):
    """Independent total: int_0^{pi/2} [F + (1-F)^2 T/(1-F T)] cos(gamma) dgamma, Gauss-Legendre."""
    x, wq = np.polynomial.legendre.leggauss(n)
    g = 0.25 * math.pi * (x + 1.0)
    _, _, f, t = geometry(np.sin(g), theta_i_deg, eta, mua, diam)
    return float(np.sum(0.25 * math.pi * wq * np.cos(g) * (f + (1 - f) ** 2 * t / (1 - f * t))))


def self_test(args):
    ok = True
    def check(cond, msg):
        nonlocal ok
        ok &= bool(cond)
        print(("ok   " if cond else "FAIL ") + msg)
    for th in (0.0, 15.0, 30.0, 45.0, 60.0, 80.0):
        ref = reference(th, args.eta, 0.0, args.diameter_um, args.quad_points)
        check(abs(ref.sum() - 1.0) < 1e-12, f"theta_i={th:4.1f}: sum(ref) - 1 = {ref.sum() - 1:+.2e} (mua=0)")
        check(np.max(np.abs(ref - ref[::-1])) < 1e-6,
              f"theta_i={th:4.1f}: max|ref(dphi) - ref(-dphi)| = {np.max(np.abs(ref - ref[::-1])):.1e}")
    for th in (0.0, 30.0, 60.0):
        ref = reference(th, args.eta, 0.05, args.diameter_um, args.quad_points)
        a = albedo_closed(th, args.eta, 0.05, args.diameter_um)
        check(abs(ref.sum() - a) < 1e-9, f"theta_i={th:4.1f}, mua=0.05: sum(ref) = {ref.sum():.10f}, "
              f"geometric-series integral = {a:.10f}")
    ref, r_only = reference(0.0, args.eta, 0.0, args.diameter_um, args.quad_points, split=True)
    x, wq = np.polynomial.legendre.leggauss(4000)
    g = 0.25 * math.pi * (x + 1.0)
    r_gl = float(np.sum(0.25 * math.pi * wq * np.cos(g) * fresnel(np.cos(g), args.eta)))
    check(abs(r_only - r_gl) < 1e-9, f"theta_i=0: R-only fraction {r_only:.10f} vs "
          f"int F(cos g) cos g dg = {r_gl:.10f}")
    f0 = ((args.eta - 1) / (args.eta + 1)) ** 2
    check(ref[89] > 0 and ref[90] > 0 and r_only > f0, f"theta_i=0: R-only fraction > F(0) = {f0:.5f}")
    print("self-test:", "passed" if ok else "FAILED")
    return ok


def run_baker(args, theta_i, mua, seed):
    cmd = [str(args.baker), "fiber", "trace", "--section", "circle", "--diameter-um", repr(args.diameter_um),
           "--eta", repr(args.eta), "--beta-deg", "0", "--mua-per-um", repr(mua), "--theta-i", repr(theta_i),
           "--phi-i", repr(args.phi_i), "--photons", str(args.photons), "--seed", str(seed), "--json"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {proc.returncode}: {proc.stderr.strip()[-500:]}")
    return json.loads(proc.stdout)


def compare(args, theta_i, mua, out, zstar):
    """Returns (list of failure strings, row dict)."""
    fails = []
    ref = reference(theta_i, args.eta, mua, args.diameter_um, args.quad_points)
    qerr = np.abs(ref - reference(theta_i, args.eta, mua, args.diameter_um, args.quad_points // 2))
    mc = np.asarray(out["dphi_hist"], float)
    mc_se = np.asarray(out["dphi_hist_se"], float)
    edges = np.asarray(out["dphi_edges_deg"], float)
    if mc.shape != (NBINS,) or mc_se.shape != (NBINS,) or not np.allclose(edges, np.linspace(-180, 180, NBINS + 1)):
        return [f"dphi binning is not 180 x 2 deg from -180"], dict(ref=ref, mc=mc, zmax=math.inf, ref_tot=ref.sum())
    n = float(out["photons"])
    se = np.where((mc == 0) | (mc_se == 0), np.sqrt(ref / n), mc_se)
    se = np.sqrt(se**2 + qerr**2)
    z = np.where(se > 0, (mc - ref) / np.where(se > 0, se, 1.0), np.where(mc == ref, 0.0, math.inf))
    zmax, bmax = float(np.max(np.abs(z))), int(np.argmax(np.abs(z)))
    if not zmax < zstar:
        fails.append(f"max|z| = {zmax:.2f} at dphi bin [{edges[bmax]:.0f}, {edges[bmax + 1]:.0f}) "
                     f"(mc {mc[bmax]:.4e} +- {mc_se[bmax]:.1e}, ref {ref[bmax]:.4e})")
    alb, alb_se, ref_tot = float(out["albedo"]), float(out["albedo_se"]), float(ref.sum())
    if abs(alb - ref_tot) > 4 * alb_se + 1e-9:
        fails.append(f"albedo {alb:.6f} +- {alb_se:.1e} vs closed form {ref_tot:.6f}")
    if mua == 0 and abs(alb - 1.0) > 4 * alb_se + 1e-9:
        fails.append(f"albedo {alb:.9f} +- {alb_se:.1e} is not 1 without absorption")
    if abs(mc.sum() - alb) > 1e-6 * max(alb, 1e-12):
        fails.append(f"sum(dphi_hist) = {mc.sum():.9f} != albedo {alb:.9f}")
    te = np.asarray(out["theta_o_edges_deg"], float)
    h2 = np.asarray(out["hist2d"], float)
    rows = (te[:-1] <= -theta_i + 2.0) & (te[1:] >= -theta_i - 2.0)
    near = float(h2[rows].sum()) if h2.shape == (len(te) - 1, NBINS) else -1.0
    if not near >= (1 - 1e-9) * alb:
        fails.append(f"only {near:.9f} of albedo {alb:.9f} in theta_o rows near {-theta_i:g} deg "
                     f"(hist2d shape {h2.shape})")
    pw = out.get("projected_width_um")
    if pw is not None and abs(float(pw) - args.diameter_um) > 1e-6 * args.diameter_um:
        print(f"  warning: projected_width_um = {pw} != D = {args.diameter_um}")
    return fails, dict(ref=ref, mc=mc, zmax=zmax, ref_tot=ref_tot)


def plot(path, results):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"matplotlib not installed: no plot written to {path}")
        return
    centres = np.linspace(-179, 179, NBINS)
    fig, axes = plt.subplots(1, len(results), figsize=(4 * len(results), 3.5), squeeze=False)
    for ax, (label, row) in zip(axes[0], results):
        ax.semilogy(centres, np.maximum(row["ref"], 1e-9), "k-", lw=1, label="closed form")
        ax.semilogy(centres, np.maximum(row["mc"], 1e-9), "r.", ms=3, label="baker MC")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("dphi [deg]")
    axes[0][0].set_ylabel("fraction per 2 deg bin")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"plot written to {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", type=Path, default=ROOT / "target" / "release" / "baker")
    ap.add_argument("--eta", type=float, default=1.55)
    ap.add_argument("--diameter-um", type=float, default=10.0)
    ap.add_argument("--thetas", type=float, nargs="+", default=[0.0, 30.0, 60.0])
    ap.add_argument("--muas", type=float, nargs="+", default=[0.0, 0.05])
    ap.add_argument("--phi-i", type=float, default=0.0)
    ap.add_argument("--photons", type=int, default=2_000_000)
    ap.add_argument("--seed", type=int, default=20031)
    ap.add_argument("--alpha", type=float, default=0.001, help="family-wise alpha per run")
    ap.add_argument("--quad-points", type=int, default=2**21)
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("--plot", metavar="FILE.png")
    args = ap.parse_args()
    if args.self_test:
        sys.exit(0 if self_test(args) else 1)
    a1 = 1.0 - (1.0 - args.alpha) ** (1.0 / NBINS)
    zstar = statistics.NormalDist().inv_cdf(1.0 - a1 / 2.0)
    print(f"baker {args.baker}; eta {args.eta}, D {args.diameter_um} um, {args.photons} photons; z* = {zstar:.3f}")
    print(f"{'theta_i':>7} {'mua':>6} {'albedo MC':>22} {'ref':>10} {'max|z|':>7} {'z*':>6}  result")
    n_fail, results = 0, []
    for k, (th, mua) in enumerate((th, mua) for th in args.thetas for mua in args.muas):
        try:
            out = run_baker(args, th, mua, args.seed + k)
            fails, row = compare(args, th, mua, out, zstar)
            albedo = f"{out['albedo']:.6f} +- {out['albedo_se']:.1e}"
        except (OSError, RuntimeError, ValueError, KeyError, TypeError) as e:
            fails, row, albedo = [f"{type(e).__name__}: {e}"], None, "-"
        ref_tot = f"{row['ref_tot']:.6f}" if row else "-"
        zmax = f"{row['zmax']:.2f}" if row else "-"
        print(f"{th:7.1f} {mua:6.3f} {albedo:>22} {ref_tot:>10} {zmax:>7} {zstar:6.2f}  {'FAIL' if fails else 'pass'}")
        for f in fails:
            print("    " + f)
        n_fail += bool(fails)
        if row:
            results.append((f"theta_i={th:g}, mua={mua:g}", row))
    if args.plot and results:
        plot(args.plot, results)
    print(f"check_fiber_cylinder: {len(args.thetas) * len(args.muas) - n_fail} passed, {n_fail} failed")
    sys.exit(1 if n_fail else 0)


if __name__ == "__main__":
    main()
