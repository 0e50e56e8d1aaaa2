#!/usr/bin/env python3
"""Write tests/surfaces/rough_dielectric_beckmann.csv: Mitsuba 3's `roughdielectric` lobes.

An independent reference for the rough fiber boundary of baker/src/fiber/surface.rs
(`Surface { eta, alpha }`, `Surface::scatter`): for a photon meeting a Beckmann-rough
dielectric boundary, the probability that its new direction of travel falls in each bin of
the sphere, computed from Mitsuba 3's own BSDF (plugin `roughdielectric`, distribution
`beckmann`, Smith single scattering), not from the baker.

How to run (from anywhere; the repository root is found from this file's path):

    pip install mitsuba==3.9.1 numpy        # validation/requirements.txt pins both
    python3 validation/make_rough_interface_fixture.py           # (re)writes the CSV
    python3 validation/make_rough_interface_fixture.py --out F   # writes F instead
    python3 validation/check_rough_interface.py --check-fixture  # recompute and compare

Mitsuba's variant is `scalar_rgb` (float32; the pip wheel has no double variant, and its
llvm_ad_rgb variant does not run with the libLLVM 15 installed here).

Frame and bins, in the Rust code's terms. The local frame has +z = nf, the mean normal
facing the photon (`scatter(d, nf, inside, u)` with nf = (0, 0, 1)); the photon travels
along d = (sin θi, 0, −cos θi), both for side = outside (`inside = false`: it comes from
index 1 and meets index eta) and for side = inside (`inside = true`: it travels in the fiber,
index eta, and meets index 1). The outgoing direction w = (x, y, z) is the photon's new
direction of travel (`Scatter::dir`): z > 0 is reflection, z < 0 transmission. Bins:
iz = floor((z + 1)/0.05) in 0..40 (equal solid angle), iphi = floor(|φ|/10°) in 0..18 with
φ = atan2(y, x) ∈ (−180°, 180°] folded to [0°, 180°] (iphi = 0 holds the forward direction
+x, the specular reflection and the refraction). p is the probability of the bin (both
halves ±φ together).

Mitsuba's conventions: si.wi = −d (pointing away from the surface, towards where the photon
came from), wo = the new direction of travel, TransportMode.Importance (particle tracing:
the transmission term then has no (1/η)² radiance-compression factor, so ∫ eval dωo is the
fraction of photon power that leaves, and is ≤ 1). Mitsuba's local +z is the exterior
(ext_ior = 1) side: for side = outside its frame is ours; for side = inside the photon arrives
with cos θ < 0 in Mitsuba's frame (wi_mi = (−sin θi, 0, −cos θi)) and Mitsuba's wo_mi =
(x, y, −z) for our w = (x, y, z).

`BSDF.eval` returns f(wi, wo)·|cos θo| (roughdielectric.cpp: reflection F·D·G/(4|cos θi|) =
f_r·|cos θo| with f_r = F·D·G/(4|cos θi||cos θo|); transmission likewise without the
1/|cos θo|), so p = ∫_bin eval dωo with dωo = dz dφ. The script checks this numerically:
the cosine-free integral of eval/|cos θo| is far from 1 while ∫ eval dωo ≈ 1 − loss, and a
histogram of Mitsuba's own sampler (BSDF.sample, weights included) agrees with p.

Quadrature, per case. Each bin is integrated over φ ∈ [0°, 180°] and doubled (the lobes are
symmetric under y → −y), in (θo, φo) with dωo = sin θo dθo dφo (smooth at the poles, unlike
z), the z-bin edges mapped to θ = arccos z. A cell's integral Q1 is a 4 × 4-point
Gauss–Legendre rule; Q2 is the same rule on its four halves (the quadrature halved). Each bin
starts as 4 × 2 cells; a bin whose Σ|Q2 − Q1| exceeds 1e-5·p + 1e-13 has its largest-error
cells halved (the fewest that leave the rest under a quarter of that), until no bin does.
The cells are placed with `mitsuba_eval64`, a float64 transcription of roughdielectric.cpp's
eval (Mitsuba's float32 eval is noisy where 1 − F is small, near total internal reflection,
and a halving test chasing that noise never stops); on the final cells the written
p = 2 Σ Q2 is computed with Mitsuba's own BSDF.eval. Reported per case: the halving error
2 Σ|Q2 − Q1| of the transcription (pure quadrature error: ≤ 1e-5 p by construction, and
the value written is the halved one, so its error is smaller still), the same with
Mitsuba's eval (quadrature plus float32 noise), and |p_mitsuba − p_f64|. Gauss nodes never
fall on bin edges, the grazing plane z = 0 included. One case takes 0.5–1 million Mitsuba
evaluations (~1 µs each); the whole fixture ~15 s.

Rows: `alpha,eta,side,theta_i_deg,iz,iphi,p`, plus one row per case with iz = iphi = −1 and
p = 1 − Σ p (the energy Mitsuba's single-scattering model loses).
"""

import argparse
import math
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "tests" / "surfaces" / "rough_dielectric_beckmann.csv"

ETA = 1.55
BETAS_DEG = (6.5, 15.0)
CASES = (("outside", 0.0), ("outside", 30.0), ("outside", 60.0), ("inside", 0.0), ("inside", 30.0))
NZ, NPHI = 40, 18
MITSUBA_VERSION = "3.9.1"

# Quadrature settings (see the docstring).
GL_K = 4
INIT_SPLIT = (4, 2)
TOL_REL = 1e-5
TOL_ABS = 1e-13
MAX_ROUNDS = 24

_GX, _GW = np.polynomial.legendre.leggauss(GL_K)


def alphas():
    return [math.tan(math.radians(b)) for b in BETAS_DEG]


def load_mitsuba():
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    if mi.__version__ != MITSUBA_VERSION:
        print(f"warning: mitsuba {mi.__version__}, fixture made with {MITSUBA_VERSION}", file=sys.stderr)
    return mi


class MitsubaLobe:
    """Mitsuba's roughdielectric for one case, in the frame of the module docstring."""

    def __init__(self, mi, alpha, eta, side, theta_i_deg):
        self.mi = mi
        self.bsdf = mi.load_dict(
            {
                "type": "roughdielectric",
                "distribution": "beckmann",
                "alpha": alpha,
                "int_ior": eta,
                "ext_ior": 1.0,
            }
        )
        self.ctx = mi.BSDFContext(mi.TransportMode.Importance)
        self.si = mi.SurfaceInteraction3f()
        t = math.radians(theta_i_deg)
        self.sgn = 1.0 if side == "outside" else -1.0  # our z → Mitsuba's z
        self.si.wi = mi.Vector3f(-math.sin(t), 0.0, self.sgn * math.cos(t))
        self.n_evals = 0

    def eval_tphi(self, theta, phi):
        """eval (cosine included) at our directions given by θo and φo (arrays)."""
        s = np.sin(theta)
        x, y, zz = s * np.cos(phi), s * np.sin(phi), self.sgn * np.cos(theta)
        V, ev, ctx, si = self.mi.Vector3f, self.bsdf.eval, self.ctx, self.si
        out = [ev(ctx, si, V(a, b, c))[0] for a, b, c in zip(x.tolist(), y.tolist(), zz.tolist())]
        self.n_evals += len(out)
        return np.asarray(out, dtype=np.float64)

    def sample(self, n, rng):
        """n directions from Mitsuba's own sampler, in our frame, with their weights."""
        mi = self.mi
        u = rng.random((n, 3))
        w = np.empty((n, 3))
        wt = np.empty(n)
        for i, (a, b, c) in enumerate(u.tolist()):
            bs, weight = self.bsdf.sample(self.ctx, self.si, a, mi.Point2f(b, c))
            wo = bs.wo
            w[i] = (wo[0], wo[1], self.sgn * wo[2])
            wt[i] = weight[0]
        return w, wt


class Formula64:
    """roughdielectric.cpp's eval (Importance mode, Beckmann, Mitsuba's rational Smith G1)
    transcribed into float64 numpy, in the same frame. Used only to place the quadrature
    cells: Mitsuba's float32 eval is noisy where 1 − F is small (near total internal
    reflection), which keeps a halving test from converging there. The values written are
    Mitsuba's own; the report compares both."""

    def __init__(self, alpha, eta, side, theta_i_deg):
        t = math.radians(theta_i_deg)
        self.sgn = 1.0 if side == "outside" else -1.0
        self.wi = np.array([-math.sin(t), 0.0, self.sgn * math.cos(t)])
        self.alpha, self.eta = alpha, eta
        self.n_evals = 0

    def eval_tphi(self, theta, phi):
        s = np.sin(theta)
        wo = np.stack([s * np.cos(phi), s * np.sin(phi), self.sgn * np.cos(theta)], axis=-1)
        self.n_evals += len(theta)
        return mitsuba_eval64(self.wi, wo, self.alpha, self.eta)


def _fresnel64(c, eta):
    """mitsuba/render/fresnel.h fresnel(): unpolarised reflectance, c < 0 from inside."""
    out = c >= 0
    eta_it = np.where(out, eta, 1 / eta)
    eta_ti = np.where(out, 1 / eta, eta)
    ci = np.abs(c)
    ct = np.sqrt(np.maximum(1 - (1 - c * c) * eta_ti**2, 0.0))
    a_s = (ci - eta_it * ct) / (ci + eta_it * ct)
    a_p = (ct - eta_it * ci) / (ct + eta_it * ci)
    return np.where(ci == 0, 1.0, 0.5 * (a_s**2 + a_p**2))


def _smith_g1_64(v, m, alpha):
    """mitsuba/render/microfacet.h smith_g1() for Beckmann (its rational approximation)."""
    xy = alpha**2 * (v[..., 0] ** 2 + v[..., 1] ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = 1 / np.sqrt(xy / v[..., 2] ** 2)
        r = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a))
    r = np.where(xy == 0, 1.0, r)
    return np.where((v * m).sum(-1) * v[..., 2] <= 0, 0.0, r)


def _beckmann_d64(m, alpha):
    """mitsuba/render/microfacet.h eval(): exp(−tan²θ/α²)/(π α² cos⁴θ), 0 below 1e-20."""
    c2 = m[..., 2] ** 2
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = np.exp(-(m[..., 0] ** 2 + m[..., 1] ** 2) / alpha**2 / c2) / (np.pi * alpha**2 * c2 * c2)
    return np.where(r * m[..., 2] > 1e-20, r, 0.0)


def mitsuba_eval64(wi, wo, alpha, eta_int):
    """roughdielectric.cpp eval() in Mitsuba's frame (wi: 3-vector, wo: (..., 3))."""
    ci, co = wi[2], wo[..., 2]
    reflect = ci * co > 0
    eta = eta_int if ci > 0 else 1 / eta_int
    h = wi + wo * np.where(reflect, 1.0, eta)[..., None]
    m = h / np.linalg.norm(h, axis=-1, keepdims=True)
    m = m * np.where(m[..., 2] < 0, -1.0, 1.0)[..., None]
    d = _beckmann_d64(m, alpha)
    wim, wom = (m * wi).sum(-1), (m * wo).sum(-1)
    f = _fresnel64(wim, eta_int)
    g = _smith_g1_64(np.broadcast_to(wi, wo.shape), m, alpha) * _smith_g1_64(wo, m, alpha)
    r = f * d * g / (4 * abs(ci))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.abs((1 - f) * d * g * eta * eta * wim * wom / (ci * (wim + eta * wom) ** 2))
    return np.where(ci == 0, 0.0, np.where(reflect, r, np.nan_to_num(t)))


def _cell_values(lobe, t0, t1, p0, p1):
    """4×4 Gauss–Legendre integral of eval·sin θ over each cell [t0,t1]×[p0,p1] of (θo, φo)."""
    ht, hp = 0.5 * (t1 - t0), 0.5 * (p1 - p0)
    ct, cp = 0.5 * (t1 + t0), 0.5 * (p1 + p0)
    tt = ct[:, None, None] + ht[:, None, None] * _GX[None, :, None]
    pp = cp[:, None, None] + hp[:, None, None] * _GX[None, None, :]
    tt, pp = np.broadcast_arrays(tt, pp)
    f = lobe.eval_tphi(tt.ravel(), pp.ravel()).reshape(tt.shape) * np.sin(tt)
    return ht * hp * np.einsum("cij,i,j->c", f, _GW, _GW)


def _children(cells):
    """The four halves of each cell (t0, t1, p0, p1), family by family (4 per cell)."""
    t0, t1, p0, p1 = cells
    tm, pm = 0.5 * (t0 + t1), 0.5 * (p0 + p1)
    return (
        np.stack([t0, t0, tm, tm], axis=1).ravel(),
        np.stack([tm, tm, t1, t1], axis=1).ravel(),
        np.stack([p0, pm, p0, pm], axis=1).ravel(),
        np.stack([pm, p1, pm, p1], axis=1).ravel(),
    )


def _initial_cells():
    """INIT_SPLIT cells per bin over φ ∈ [0, π], in (θ, φ); and their bin numbers."""
    sz, sp = INIT_SPLIT
    dp = math.pi / NPHI
    # Bin iz is z ∈ [−1 + 0.05 iz, −1 + 0.05 (iz + 1)], i.e. θ from te[iz + 1] to te[iz].
    te = np.arccos(np.clip(-1.0 + np.arange(NZ + 1) * (2.0 / NZ), -1.0, 1.0))
    iz, ip, jz, jp = np.meshgrid(np.arange(NZ), np.arange(NPHI), np.arange(sz), np.arange(sp), indexing="ij")
    lo, hi = te[iz + 1], te[iz]
    t0 = (lo + (hi - lo) * jz / sz).ravel()
    t1 = np.where(jz == sz - 1, hi, lo + (hi - lo) * (jz + 1) / sz).ravel()
    p0 = (ip * dp + jp * dp / sp).ravel()
    p1 = np.where(jp == sp - 1, (ip + 1) * dp, ip * dp + (jp + 1) * dp / sp).ravel()
    return (t0, t1, p0, p1), (iz * NPHI + ip).ravel()


def adapt_mesh(lobe):
    """Cells (one family each: the cell and its four halves) and their bins, refined on `lobe`.

    A family's error is |Q2 − Q1| (Q1: the cell's rule, Q2: the sum over its halves). A bin
    whose summed error exceeds TOL_REL·p + TOL_ABS has its largest-error families halved (the
    fewest that leave the rest below a quarter of the tolerance), until no bin fails.
    """
    nb = NZ * NPHI
    cells, b = _initial_cells()
    q1 = _cell_values(lobe, *cells)
    qc = _cell_values(lobe, *_children(cells)).reshape(-1, 4)
    for _ in range(MAX_ROUNDS):
        q2 = qc.sum(axis=1)
        e = np.abs(q2 - q1)
        pb = np.bincount(b, weights=q2, minlength=nb)
        tol = TOL_REL * np.abs(pb) + TOL_ABS
        bad = np.bincount(b, weights=e, minlength=nb) > tol
        if not bad.any():
            return cells, b
        split = np.zeros(len(e), dtype=bool)
        for k in np.flatnonzero(bad):
            mine = np.flatnonzero(b == k)
            mine = mine[np.argsort(-e[mine], kind="stable")]
            tail = np.cumsum(e[mine][::-1])[::-1]  # error of this family and all smaller ones
            split[mine[tail > 0.25 * tol[k]]] = True
        keep = ~split
        # The four halves of a split family become four families of their own.
        halves = tuple(a.reshape(-1, 4)[split].ravel() for a in _children(cells))
        nqc = _cell_values(lobe, *_children(halves)).reshape(-1, 4)
        cells = tuple(np.concatenate([a[keep], h]) for a, h in zip(cells, halves))
        b = np.concatenate([b[keep], np.repeat(b[split], 4)])
        q1 = np.concatenate([q1[keep], qc[split].ravel()])
        qc = np.concatenate([qc[keep], nqc])
    raise RuntimeError("quadrature did not converge in MAX_ROUNDS rounds")


def integrate_on(lobe, cells, b):
    """(p, err) as (NZ, NPHI) arrays on a fixed mesh: p = 2 Σ Q2 (both ±φ halves) and the
    halving estimate err = 2 Σ |Q2 − Q1| per bin."""
    nb = NZ * NPHI
    q1 = _cell_values(lobe, *cells)
    q2 = _cell_values(lobe, *_children(cells)).reshape(-1, 4).sum(axis=1)
    p = 2.0 * np.bincount(b, weights=q2, minlength=nb)
    err = 2.0 * np.bincount(b, weights=np.abs(q2 - q1), minlength=nb)
    return p.reshape(NZ, NPHI), err.reshape(NZ, NPHI)


def bin_probabilities(mi, alpha, eta, side, theta_i_deg):
    """Mitsuba's bin probabilities for one case, with error estimates (a dict)."""
    f64 = Formula64(alpha, eta, side, theta_i_deg)
    cells, b = adapt_mesh(f64)
    p64, err64 = integrate_on(f64, cells, b)
    lobe = MitsubaLobe(mi, alpha, eta, side, theta_i_deg)
    p, err = integrate_on(lobe, cells, b)
    return {"p": p, "err": err, "p64": p64, "err64": err64, "cells": len(b), "evals": lobe.n_evals}


def bin_index(w):
    """(iz, iphi) of directions w (n×3) in the bins of the module docstring."""
    iz = np.clip(np.floor((w[:, 2] + 1.0) / (2.0 / NZ)).astype(int), 0, NZ - 1)
    phi = np.abs(np.degrees(np.arctan2(w[:, 1], w[:, 0])))
    ip = np.clip(np.floor(phi / (180.0 / NPHI)).astype(int), 0, NPHI - 1)
    return iz, ip


def compute_all(mi, verbose=True):
    """{(alpha, side, theta): bin_probabilities dict (+ "seconds")} for every case."""
    res = {}
    for a in alphas():
        for side, th in CASES:
            t0 = time.time()
            r = bin_probabilities(mi, a, ETA, side, th)
            r["seconds"] = time.time() - t0
            res[(a, side, th)] = r
            if verbose:
                print(f"  {case_line(a, side, th, r)}", flush=True)
    return res


def rel_err(p, err, floor=1e-6):
    """Largest err/p over the bins with p > floor."""
    m = p > floor
    return float((err[m] / p[m]).max())


def case_line(a, side, th, r):
    p, p64 = r["p"], r["p64"]
    d = np.abs(p - p64)
    return (
        f"beta={math.degrees(math.atan(a)):4.1f} {side:7s} theta_i={th:4.1f}: "
        f"loss={1 - p.sum():+.3e} (f64 {1 - p64.sum():+.3e}); "
        f"halving err/p max {rel_err(p64, r['err64']):.1e} (p>1e-6) {rel_err(p64, r['err64'], 1e-9):.1e} (p>1e-9), "
        f"abs {r['err64'].max():.1e} [mitsuba f32: {rel_err(p, r['err']):.1e}]; "
        f"|p_mitsuba - p_f64| max {d.max():.1e} abs, {rel_err(p64, d):.1e} rel (p>1e-6); "
        f"{r['cells']} cells, {r['evals']} evals, {r['seconds']:.1f}s"
    )


def rows(res):
    out = []
    for (a, side, th), r in res.items():
        p = r["p"]
        for iz in range(NZ):
            for ip in range(NPHI):
                out.append((a, ETA, side, th, iz, ip, p[iz, ip]))
        out.append((a, ETA, side, th, -1, -1, 1.0 - p.sum()))
    return out


def format_row(r):
    a, eta, side, th, iz, ip, p = r
    return f"{a:.17g},{eta:.17g},{side},{th:g},{iz},{ip},{p:.12e}"


def header(mi_version):
    a1, a2 = alphas()
    return f"""\
# Rough dielectric boundary lobes from Mitsuba 3 (an independent reference for
# baker/src/fiber/surface.rs Surface::scatter; no number comes from the baker).
# Source: Mitsuba {mi_version} (pip `mitsuba`), variant scalar_rgb (float32), plugin
# roughdielectric {{distribution: beckmann, alpha: tan(beta), int_ior: {ETA}, ext_ior: 1.0,
# sample_visible: default}}, BSDFContext(TransportMode.Importance), BSDF.eval (which already
# includes |cos theta_o|). alpha = tan(6.5 deg) = {a1:.17g}, tan(15 deg) = {a2:.17g}.
# Mitsuba's Beckmann D(m) = exp(-tan^2(theta_m)/alpha^2)/(pi alpha^2 cos^4(theta_m)): the
# same alpha as Surface::alpha (surface.rs samples tan^2(theta_m) = -alpha^2 ln u).
# Frame (Rust terms): scatter(d, nf, inside, u) with nf = (0,0,1) facing the photon and
# d = (sin theta_i, 0, -cos theta_i); side=outside: inside=false (index 1 -> eta);
# side=inside: inside=true (index eta -> 1). The outgoing direction w = (x,y,z) is the new
# direction of travel (Scatter::dir): z > 0 reflected, z < 0 transmitted.
# Bins: iz = floor((z+1)/0.05) in 0..39 (40 equal-solid-angle bins of z over [-1,1]);
# iphi = floor(|atan2(y,x)| / 10 deg) in 0..17 (phi folded to [0,180] deg, 18 bins; iphi=0
# holds +x, the specular and refracted directions). p = integral over the bin (both +-phi
# halves) of eval(wi, wo) dwo = probability that w falls in the bin.
# Mitsuba mapping: si.wi = -d for outside; for inside (Mitsuba's +z is the ext_ior side)
# si.wi = (-sin theta_i, 0, -cos theta_i) and wo_mitsuba = (x, y, -z).
# Row iz = iphi = -1: p = 1 - sum of the 720 bins, the energy Mitsuba's single-scattering
# (Smith) model loses (multiple scattering ignored); the baker's V-cavity walk loses none.
# Quadrature: adaptive 4x4-point Gauss-Legendre on cells of the (theta, phi) bins, halved
# until the per-bin halving difference <= 1e-5 p + 1e-13 (see the script's docstring).
# Losses below ~1e-7 (some slightly negative) are zero within float32 and quadrature error.
# Regenerate: python3 validation/make_rough_interface_fixture.py
# Check: python3 validation/check_rough_interface.py --check-fixture (1e-6 absolute)
# Columns: alpha,eta,side,theta_i_deg,iz,iphi,p
"""


def write(res, mi_version, path):
    path.parent.mkdir(parents=True, exist_ok=True)
    text = header(mi_version) + "\n".join(format_row(r) for r in rows(res)) + "\n"
    path.write_text(text)


def read_fixture(path=OUT):
    """{(alpha, side, theta): p (NZ×NPHI)} and {(alpha, side, theta): loss} from the CSV."""
    ps, loss = {}, {}
    for line in path.read_text().splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        a, eta, side, th, iz, ip, p = line.split(",")
        key = (float(a), side, float(th))
        iz, ip, p = int(iz), int(ip), float(p)
        if iz < 0:
            loss[key] = p
        else:
            ps.setdefault(key, np.zeros((NZ, NPHI)))[iz, ip] = p
    return ps, loss


class _NoCosine:
    """eval/|cos θo|: the integral a BSDF without the cosine factor would give."""

    def __init__(self, lobe):
        self.lobe = lobe

    def eval_tphi(self, theta, phi):
        return self.lobe.eval_tphi(theta, phi) / np.abs(np.cos(theta))


def sanity_checks(mi, res, n=100_000, seed=7):
    """The cosine convention of eval, Mitsuba's own sampler against p, and Mitsuba's float32
    eval against the float64 transcription (printed; returns the sampler's largest |z|)."""
    rng = np.random.default_rng(seed)
    print("Sanity checks:")
    # 1. eval includes |cos θo|: at θi = 60° the lobes sit at cos θo ≈ 0.5 (R) and 0.83 (T).
    a = alphas()[0]
    f64 = Formula64(a, ETA, "outside", 60.0)
    cells, b = adapt_mesh(f64)
    lobe = MitsubaLobe(mi, a, ETA, "outside", 60.0)
    p, _ = integrate_on(lobe, cells, b)
    pc, _ = integrate_on(_NoCosine(lobe), cells, b)
    print(
        f"  cosine: beta=6.5 outside 60: integral of eval = {p.sum():.6f} (<= 1: eval is f|cos|); "
        f"integral of eval/|cos| = {pc.sum():.4f}"
    )
    # 2. Mitsuba's float32 eval against the float64 transcription at random directions.
    worst_rel = 0.0
    for a_, side, th in res:
        lobe = MitsubaLobe(mi, a_, ETA, side, th)
        f64 = Formula64(a_, ETA, side, th)
        t = np.arccos(rng.uniform(-1, 1, 20000))
        ph = rng.uniform(0, math.pi, 20000)
        x, y = lobe.eval_tphi(t, ph), f64.eval_tphi(t, ph)
        m = y > 1e-3 * y.max()
        worst_rel = max(worst_rel, float(np.median(np.abs(x - y)[m] / y[m])))
    print(f"  transcription: median |eval_mitsuba/eval_f64 - 1| <= {worst_rel:.1e} per case")
    # 3. Mitsuba's sampler: weighted histogram vs p.
    worst = 0.0
    for (a_, side, th), r in res.items():
        p = r["p"]
        lobe = MitsubaLobe(mi, a_, ETA, side, th)
        w, wt = lobe.sample(n, rng)
        iz, ip = bin_index(w)
        idx = iz * NPHI + ip
        s1 = np.bincount(idx, weights=wt, minlength=NZ * NPHI) / n
        s2 = np.bincount(idx, weights=wt * wt, minlength=NZ * NPHI) / n
        sd = np.sqrt(np.maximum(s2 - s1 * s1, 0) / n)
        pf = p.ravel()
        m = pf * n > 20
        zs = np.abs(s1 - pf)[m] / np.maximum(sd[m], 1e-300)
        worst = max(worst, zs.max())
        print(
            f"  sampler beta={math.degrees(math.atan(a_)):4.1f} {side:7s} {th:4.1f}: mean weight {wt.mean():.5f} "
            f"vs sum p {p.sum():.5f}; {m.sum()} bins with n p > 20: max |z| {zs.max():.2f}, "
            f"mean z^2 {np.mean(zs**2):.2f}"
        )
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=pathlib.Path, default=OUT)
    ap.add_argument("--no-sanity", action="store_true", help="skip the sanity checks")
    args = ap.parse_args()
    mi = load_mitsuba()
    t0 = time.time()
    print(f"Mitsuba {mi.__version__} roughdielectric (beckmann), eta={ETA}:")
    res = compute_all(mi)
    print(f"quadrature: {time.time() - t0:.1f}s")
    worst = max(rel_err(r["p64"], r["err64"]) for r in res.values())
    worst9 = max(rel_err(r["p64"], r["err64"], 1e-9) for r in res.values())
    worst_abs = max(float(r["err64"].max()) for r in res.values())
    dev = max(float(np.abs(r["p"] - r["p64"]).max()) for r in res.values())
    print(
        f"max halving error: {worst:.2e} of p (bins with p > 1e-6), {worst9:.2e} (p > 1e-9), "
        f"{worst_abs:.1e} absolute; max |p_mitsuba - p_f64| = {dev:.1e}"
    )
    write(res, mi.__version__, args.out)
    print(f"wrote {args.out}")
    if not args.no_sanity:
        t0 = time.time()
        sanity_checks(mi, res)
        print(f"sanity checks: {time.time() - t0:.1f}s")


if __name__ == "__main__":
    main()
